# artic: reproducible runs.  `make setup && make paper` builds every stage and the report;
# `make setup && make test` runs the tests.  Stages rerun only when their inputs changed.
PYTHON ?= python3
VENV   ?= .venv
CONFIG ?= configs/default.yaml
OUT    ?= data
REPORT ?= reports

PY     := $(VENV)/bin/python
ARTIC  := $(VENV)/bin/artic
SRC    := $(shell find artic_cli -name '*.py') pyproject.toml
SCHED  := configs/schedules
SIMS   := $(OUT)/sims

.PHONY: setup mesh sims cuboid experiments musclefunction epmaps dynamic solve figures paper test bench clean
.DELETE_ON_ERROR:

setup: $(VENV)/.installed
$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --upgrade pip
	$(VENV)/bin/pip install --quiet -e '.[test]'
	touch $@

# --- stages ---------------------------------------------------------------
mesh: $(OUT)/mesh.h5
$(OUT)/mesh.h5: $(CONFIG) $(SRC) | setup
	$(ARTIC) build-mesh --config $(CONFIG) --out $@ --plot $(REPORT)/fig1_mesh.png

cuboid: $(OUT)/cuboid.json
$(OUT)/cuboid.json: $(CONFIG) $(SRC) | setup
	$(ARTIC) validate cuboid --config $(CONFIG) --out $@

# the tissue model alone (section II): node-set loads, GG tendon and floor held
$(SIMS)/%_novol.h5: $(SCHED)/%.yaml $(OUT)/mesh.h5
	$(ARTIC) simulate --tongue-only --schedule $< --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --no-volume-constraint

$(SIMS)/%.h5: $(SCHED)/%.yaml $(OUT)/mesh.h5
	$(ARTIC) simulate --tongue-only --schedule $< --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --plot $(REPORT)/sim_$*.png

# the whole articulator (section III): muscle schedules
$(SIMS)/fig4_%.h5: $(SCHED)/fig4_%.yaml $(OUT)/mesh.h5
	$(ARTIC) simulate --schedule $< --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --plot $(REPORT)/fig4_$*.png \
	  --animate $(REPORT)/fig4_$*.gif

$(SIMS)/art_%.h5: $(SCHED)/art_%.yaml $(OUT)/mesh.h5
	$(ARTIC) simulate --schedule $< --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --plot $(REPORT)/art_$*.png

# muscle function from scattered starts (section IV.A.1, Figs. 5 and 6)
musclefunction: $(OUT)/muscle_function.h5
$(OUT)/muscle_function.h5: $(OUT)/mesh.h5 $(CONFIG) $(SRC)
	$(ARTIC) muscle-function --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --jobs 2 --cache $(OUT)/cache \
	  --plot-dir $(REPORT)

# EP maps (section IV.B), the dynamic map (IV.B.3), target solutions (V)
epmaps: $(OUT)/epmaps.h5
$(OUT)/epmaps.h5: $(OUT)/mesh.h5 $(CONFIG) $(SRC)
	$(ARTIC) ep-map --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --jobs 2 --cache $(OUT)/cache
	$(ARTIC) plot ep-map --maps $@ --out $(REPORT)/fig8_epmap.png

dynamic: $(OUT)/dynamic.h5
$(OUT)/dynamic.h5: $(OUT)/epmaps.h5
	$(ARTIC) dynamic-map --maps $< --out $@

TARGETS   := $(wildcard configs/targets/*.yaml)
SOLUTIONS := $(TARGETS:configs/targets/%.yaml=$(OUT)/solutions/%.yaml)
solve: $(SOLUTIONS)
$(OUT)/solutions/%.yaml: configs/targets/%.yaml $(OUT)/dynamic.h5
	$(ARTIC) solve-target $< --maps $(OUT)/epmaps.h5 --dynamic $(OUT)/dynamic.h5 --mesh $(OUT)/mesh.h5 \
	  --config $(CONFIG) --verify --refine --out $@ || [ $$? -eq 3 ]
	$(ARTIC) plot solution $@ --target $< --maps $(OUT)/epmaps.h5 --dynamic $(OUT)/dynamic.h5 \
	  --out $(REPORT)/fig12_$*.png

# the paper's numeric experiments (section III), each a JSON table
EXPS := jaw-ep fig4 muscle-directions k-closure stress fig7
EXP_FILES := $(EXPS:%=$(OUT)/experiments/%.json)
experiments: $(EXP_FILES)
$(OUT)/experiments/%.json: $(OUT)/mesh.h5
	$(ARTIC) experiment $* --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@
$(OUT)/experiments/fig7.json: $(OUT)/mesh.h5
	$(ARTIC) experiment fig7 --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --plot $(REPORT)/fig7_trajectories.png

sims: $(SIMS)/gravity.h5 $(SIMS)/pull_2n.h5 $(SIMS)/pull_2n_novol.h5 $(SIMS)/stress_7n.h5 \
      $(SIMS)/fig4_ggp.h5 $(SIMS)/fig4_sg.h5 $(SIMS)/art_sg_jo.h5

figures: mesh sims

paper: $(REPORT)/paper.md
$(REPORT)/paper.md: $(OUT)/mesh.h5 $(OUT)/cuboid.json $(SIMS)/gravity.h5 $(SIMS)/pull_2n.h5 \
                    $(SIMS)/pull_2n_novol.h5 $(SIMS)/stress_7n.h5 $(SIMS)/fig4_ggp.h5 $(SIMS)/fig4_sg.h5 \
                    $(SIMS)/art_sg_jo.h5 $(EXP_FILES) $(OUT)/epmaps.h5 $(OUT)/dynamic.h5 $(SOLUTIONS) \
                    $(OUT)/muscle_function.h5
	$(ARTIC) report --data $(OUT) --out $@

# --- checks ---------------------------------------------------------------
test: setup
	$(PY) -m pytest

bench: setup $(OUT)/epmaps.h5 $(OUT)/dynamic.h5
	$(PY) benchmarks/bench_tissue.py
	$(PY) benchmarks/bench_articulator.py
	$(PY) benchmarks/bench_epmap.py
	$(PY) benchmarks/bench_solver.py

clean:
	rm -rf $(OUT)/*.h5 $(OUT)/*.json $(SIMS) $(OUT)/experiments $(OUT)/solutions $(OUT)/cache \
	  $(REPORT)/*.png $(REPORT)/*.gif $(REPORT)/paper.md

# artic: reproducible runs.  `make setup && make paper` builds every stage and the report;
# `make setup && make test` runs the tests.  Stages rerun only when their inputs changed.
# Another speaker: `make paper CONFIG=configs/other.yaml OUT=data/other/` (its report goes to OUT/reports).
# What the paper pipeline builds (schedules, experiments, targets) is listed in $(PIPELINE).
PYTHON   ?= python3
VENV     ?= .venv
CONFIG   ?= configs/default.yaml
OUT      ?= data
override OUT := $(patsubst %/,%,$(OUT))
REPORT   ?= $(if $(filter data,$(OUT)),reports,$(OUT)/reports)
PIPELINE ?= pipelines/paper.yaml
FIG9_JAW ?= JO_2.5

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

# the pipeline's lists (TISSUE_SIMS, NOVOL_SIMS, ART_SIMS, ANIMATED, EXPS, TARGET_NAMES), rendered from YAML
PIPELINE_MK := $(OUT)/.pipeline.mk
ifeq ($(filter setup test clean,$(MAKECMDGOALS)),)
-include $(PIPELINE_MK)
endif
$(PIPELINE_MK): $(PIPELINE) $(SRC) | setup
	@mkdir -p $(OUT)
	$(PY) -m artic_cli.pipeline $(PIPELINE) > $@.tmp && mv $@.tmp $@

# a missing config stops the first stage with one line
$(CONFIG):
	@echo "error: config not found: $@; give an existing file, e.g. CONFIG=configs/default.yaml" >&2; exit 2

# --- stages ---------------------------------------------------------------
mesh: $(OUT)/mesh.h5
$(OUT)/mesh.h5: $(CONFIG) $(SRC) | setup
	$(ARTIC) build-mesh --config $(CONFIG) --out $@ --plot $(REPORT)/fig1_mesh.png

cuboid: $(OUT)/cuboid.json
$(OUT)/cuboid.json: $(CONFIG) $(SRC) | setup
	$(ARTIC) validate cuboid --config $(CONFIG) --out $@

# simulations: the tissue model alone (section II, GG tendon and floor held) and the whole articulator (III)
TISSUE_FILES := $(TISSUE_SIMS:%=$(SIMS)/%.h5)
NOVOL_FILES  := $(NOVOL_SIMS:%=$(SIMS)/%_novol.h5)
ART_FILES    := $(ART_SIMS:%=$(SIMS)/%.h5)
SIM_FILES    := $(TISSUE_FILES) $(NOVOL_FILES) $(ART_FILES)
sims: $(SIM_FILES)
$(TISSUE_FILES): $(SIMS)/%.h5: $(SCHED)/%.yaml $(OUT)/mesh.h5
	$(ARTIC) simulate --tongue-only --schedule $< --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ \
	  --plot $(REPORT)/sim_$*.png
$(NOVOL_FILES): $(SIMS)/%_novol.h5: $(SCHED)/%.yaml $(OUT)/mesh.h5
	$(ARTIC) simulate --tongue-only --schedule $< --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ \
	  --no-volume-constraint
$(ART_FILES): $(SIMS)/%.h5: $(SCHED)/%.yaml $(OUT)/mesh.h5
	$(ARTIC) simulate --schedule $< --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ --plot $(REPORT)/$*.png \
	  $(if $(filter $*,$(ANIMATED)),--animate $(REPORT)/$*.gif)

# the paper's numeric experiments (section III and Fig. 7), each a JSON table
EXP_FILES := $(EXPS:%=$(OUT)/experiments/%.json)
experiments: $(EXP_FILES)
$(OUT)/experiments/%.json: $(OUT)/mesh.h5
	$(ARTIC) experiment $* --mesh $(OUT)/mesh.h5 --config $(CONFIG) --out $@ \
	  $(if $(filter fig7,$*),--plot $(REPORT)/fig7_trajectories.png)

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
	$(ARTIC) plot dynamic-map --maps $< --dynamic $@ --jaw $(FIG9_JAW) --out $(REPORT)/fig9_dynamic_map.png

SOLUTIONS := $(TARGET_NAMES:%=$(OUT)/solutions/%.yaml)
solve: $(SOLUTIONS)
$(OUT)/solutions/%.yaml: configs/targets/%.yaml $(OUT)/dynamic.h5
	$(ARTIC) solve-target $< --maps $(OUT)/epmaps.h5 --dynamic $(OUT)/dynamic.h5 --mesh $(OUT)/mesh.h5 \
	  --config $(CONFIG) --verify --refine --out $@ || [ $$? -eq 3 ]
	$(ARTIC) plot solution $@ --target $< --maps $(OUT)/epmaps.h5 --dynamic $(OUT)/dynamic.h5 \
	  --out $(REPORT)/fig12_$*.png

figures: mesh sims experiments musclefunction epmaps solve

paper: $(REPORT)/paper.md
$(REPORT)/paper.md: $(OUT)/mesh.h5 $(OUT)/cuboid.json $(SIM_FILES) $(EXP_FILES) $(OUT)/muscle_function.h5 \
                    $(OUT)/epmaps.h5 $(OUT)/dynamic.h5 $(SOLUTIONS)
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
	rm -rf $(OUT)/*.h5 $(OUT)/*.json $(SIMS) $(OUT)/experiments $(OUT)/solutions $(OUT)/cache $(PIPELINE_MK) \
	  $(REPORT)/*.png $(REPORT)/*.gif $(REPORT)/paper.md

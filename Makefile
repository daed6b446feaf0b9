# artic: reproducible runs.  `make setup && make paper` builds every stage and the report;
# `make setup && make test` runs the tests.
# Another speaker: `make paper CONFIG=configs/other.yaml OUT=data/other/` (its report goes to OUT/reports).
# The stage rules are generated (OUT/.pipeline.mk) from the stage table in artic_cli/stages/table.py and the
# lists in $(PIPELINE); each depends on what its stage reads: artefacts, config sections, source files.
PYTHON   ?= python3
VENV     ?= .venv
CONFIG   ?= configs/default.yaml
OUT      ?= data
override OUT := $(patsubst %/,%,$(OUT))
REPORT   ?= $(if $(filter data,$(OUT)),reports,$(OUT)/reports)
PIPELINE ?= pipelines/paper.yaml
FIG9_JAW ?= JO_2.5
# `make paper` runs JOBS stages at a time (JOBS=1: one after another); the stages that keep both cores busy by
# themselves run alone (the stage table's `alone`: the EP maps first, the muscle-function study last)
JOBS     ?= 2
ifneq ($(filter paper,$(MAKECMDGOALS)),)
MAKEFLAGS += -j$(JOBS)
# the report's "This run" row: when this make paper started, whether OUT held no artefact then, JOBS (written
# once: make restarts itself after remaking the generated rules)
ifeq ($(MAKE_RESTARTS),)
$(shell mkdir -p $(OUT) && echo "$$(date +%s.%N) $(if $(wildcard $(OUT)/*.h5),0,1) $(JOBS)" > $(OUT)/.paper_run)
endif
export ARTIC_PAPER_RUN := $(shell cat $(OUT)/.paper_run 2>/dev/null)
endif

# one BLAS/OpenMP thread per process: the systems are small, parallelism comes from processes, and a spare
# BLAS thread spinning beside a parallel stage's workers eats half a core
export OPENBLAS_NUM_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
export MKL_NUM_THREADS ?= 1

PY     := $(VENV)/bin/python
ARTIC  := $(VENV)/bin/artic
SRC    := $(shell find artic_cli -name '*.py')

.PHONY: setup test test-fast bench clean
.DELETE_ON_ERROR:

setup: $(VENV)/.installed
$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --upgrade pip
	$(VENV)/bin/pip install --quiet -e '.[test]'
	touch $@

# a missing config stops the first stage with one line
$(CONFIG):
	@echo "error: config not found: $@; give an existing file, e.g. CONFIG=configs/default.yaml" >&2; exit 2

# one file per config section, rewritten only when that section changes
$(OUT)/.config/.stamp: $(CONFIG) $(wildcard artic_cli/config/*.py) | setup
	$(PY) -m artic_cli.pipeline sections $(CONFIG) $(OUT)/.config
	@touch $@
$(OUT)/.config/%.json: $(OUT)/.config/.stamp ;

# the stage and figure rules, rendered from the stage table
PIPELINE_MK := $(OUT)/.pipeline.mk
ifeq ($(filter setup test test-fast clean,$(MAKECMDGOALS)),)
-include $(PIPELINE_MK)
endif
$(PIPELINE_MK): $(PIPELINE) $(SRC) | setup
	@mkdir -p $(OUT)
	$(PY) -m artic_cli.pipeline rules $(PIPELINE) > $@.tmp && mv $@.tmp $@

# --- checks ---------------------------------------------------------------
test: setup
	$(PY) -m pytest

test-fast: setup
	$(PY) -m pytest -m "not slow"

bench: setup $(OUT)/epmaps.h5 $(OUT)/dynamic.h5 $(OUT)/acoustic_maps.h5
	$(PY) benchmarks/run_all.py --out docs/speed.md

clean:
	rm -rf $(OUT)/*.h5 $(OUT)/*.json $(OUT)/sims $(OUT)/experiments $(OUT)/solutions $(OUT)/cache $(OUT)/.stamps \
	  $(OUT)/tracts $(OUT)/acoustics $(OUT)/audio $(OUT)/vowels $(OUT)/utterances \
	  $(OUT)/.config $(OUT)/.paper_run $(PIPELINE_MK) $(REPORT)/*.png $(REPORT)/*.gif $(REPORT)/paper.md $(REPORT)/paper.html

# The chapter's commands. Each target sets up what it needs first.
#   make run    the chapter's pipeline, seed 0, default config -> runs/seed0/metrics.json
#   make test   the test suite
#   make bench  speed figures -> benchmarks/wallclock.csv
#   make meta   re-measure seeds 0-2 and the horizon sweep -> meta.yaml
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: setup run test bench meta clean

setup: $(STAMP)

$(STAMP): requirements.txt pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	$(PY) -m pip install --quiet --no-deps -e .
	touch $(STAMP)

run: setup
	$(PY) -m pusht.dreamer --seed 0 --out runs/seed0

test: setup
	$(PY) -m pytest -q

bench: setup
	$(PY) benchmarks/bench.py

meta: setup
	$(PY) scripts/record_meta.py

clean:
	rm -rf runs .pytest_cache

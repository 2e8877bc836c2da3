# Two entry points for a fresh machine with Python 3.11+ and make: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test

.PHONY: demo test lint experiments bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e .
	touch $@

$(TEST_STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e '.[test]'
	touch $@ $(STAMP)

demo: $(STAMP)  ## simulate an office tour, map it with every method, print the table, write figures
	$(BIN)/sonarcarve demo --out demo-output

test: $(TEST_STAMP)  ## lint, type-check and run the whole test suite (slow experiment runs excluded)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy
	$(BIN)/python -m pytest -n 2 -m "not slow" -q

experiments: $(TEST_STAMP)  ## the paper's full experiments: refreshes docs/RESULTS.md numbers and docs/figures
	$(BIN)/sonarcarve experiments --out docs/experiments --figures docs/figures --results-md docs/RESULTS.md
	$(BIN)/python -m pytest -m slow -q

bench: $(STAMP)  ## every benchmark: throughput, simulator speed, parameter choices (tables for docs/RESULTS.md)
	$(BIN)/python benchmarks/throughput.py
	$(BIN)/python benchmarks/simulate_speed.py
	$(BIN)/python benchmarks/range_tolerance.py
	$(BIN)/python benchmarks/min_transversal.py
	$(BIN)/python benchmarks/specular.py
	$(BIN)/python benchmarks/grid_baseline.py

clean:
	rm -rf $(VENV) demo-output .pytest_cache .mypy_cache .ruff_cache

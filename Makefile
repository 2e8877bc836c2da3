# Two entry points for a fresh machine with Python 3.11+ and make: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test

.PHONY: demo test lint experiments bench fuzz clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

# After installing, `sonarcarve warm` compiles every kernel once into numba's on-disk cache
# (about a minute and a half on 2 cores, one process per core), so the first run of each method
# loads machine code instead of compiling.
$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e '.[all]'
	$(BIN)/sonarcarve warm --quiet
	touch $@

$(TEST_STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e '.[test]'
	$(BIN)/sonarcarve warm --quiet
	touch $@ $(STAMP)

demo: $(STAMP)  ## simulate an office tour, map it with every method, print the table, write figures
	$(BIN)/sonarcarve demo --out demo-output

test: $(TEST_STAMP)  ## lint, type-check, check the import contracts, run the tests and doctests (slow runs excluded)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -n 2 -m "not slow and not fuzz" -q

experiments: $(TEST_STAMP)  ## the paper's full experiments: refreshes docs/RESULTS.md numbers and docs/figures
	$(BIN)/sonarcarve experiments --out docs/experiments --figures docs/figures --results-md docs/RESULTS.md
	$(BIN)/python -m pytest -m slow -q

fuzz: $(TEST_STAMP)  ## thousands of mutated inputs per family through the real CLI (no crash, hang, leftover or changed file)
	FUZZ_CASES=5000 $(BIN)/python -m pytest -n 2 -m fuzz -q tests/fuzz

bench: $(STAMP)  ## the main benchmarks (slow: several take minutes): speed, memory, parameter choices, evidence carving, grids, changing scenes (the held-out and A/B ones run by hand: benchmarks/README.md)
	$(BIN)/python benchmarks/import_time.py
	$(BIN)/python benchmarks/throughput.py
	$(BIN)/python benchmarks/simulate_speed.py
	$(BIN)/python benchmarks/range_tolerance.py
	$(BIN)/python benchmarks/min_transversal.py
	$(BIN)/python benchmarks/specular.py
	$(BIN)/python benchmarks/grid_baseline.py
	$(BIN)/python benchmarks/carve_kernel.py --repeats 9
	$(BIN)/python benchmarks/speed.py --sections ratio latency cold
	$(BIN)/python benchmarks/process_speed.py
	$(BIN)/python benchmarks/soak.py
	$(BIN)/python benchmarks/evidence.py
	$(BIN)/python benchmarks/no_echo.py
	$(BIN)/python benchmarks/grids.py
	$(BIN)/python benchmarks/changing_scenes.py

clean:
	rm -rf $(VENV) demo-output .pytest_cache .mypy_cache .ruff_cache

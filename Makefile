# Two commands do everything on a fresh machine with python3 (3.11+) and make:
#   make demo   - create .venv, install, solve the built-in 30-subtask case, write figures
#   make test   - create .venv with the dev extras if needed, run all tests and notebooks
# More: make lint (ruff + mypy), make coverage (kernels as Python), make fuzz (long
# fuzzing), make campaign (the bad-input table), make bench (benchmarks, peers included),
# make papers (reproduce the five source papers: figures and tables in out/papers),
# make clean (also the kernel cache).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT := out
FUZZ_EXAMPLES ?= 200
PAPER_WORKERS ?= 2

.PHONY: demo test bench papers lint coverage fuzz campaign clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(VENV)/.installed-dev: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@ $(VENV)/.installed

$(VENV)/.installed-bench: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[dev,bench]'
	touch $@ $(VENV)/.installed-dev $(VENV)/.installed

demo: $(VENV)/.installed
	MPLBACKEND=Agg $(BIN)/subtask-opt solve --case random30 --seed 1 \
		--json $(OUT)/random30.json --plot $(OUT)/random30.png
	@echo
	@echo "Figures and JSON are in $(OUT)/: open $(OUT)/random30.png in any image viewer;"
	@echo "$(OUT)/random30.json holds the order, times and the arm's report of every leg."

# --dist loadfile: a test file's tests share its kernels, and on a cold kernel cache both
# workers would otherwise compile most of them (about 520 s instead of 620-820 s here)
test: $(VENV)/.installed-dev
	MPLBACKEND=Agg $(BIN)/python -m pytest -n 2 --dist loadfile --nbmake tests examples

bench: $(VENV)/.installed-bench
	MPLBACKEND=Agg $(BIN)/python -m pytest -n 2 -m bench tests
	$(BIN)/python benchmarks/sequencing.py --json $(OUT)/bench/sequencing.json
	$(BIN)/python benchmarks/fidelity.py --json $(OUT)/bench/fidelity.json
	$(BIN)/python benchmarks/grid.py --json $(OUT)/bench/grid.json
	$(BIN)/python benchmarks/maklink.py --json $(OUT)/bench/maklink.json
	$(BIN)/python benchmarks/reactive.py --json $(OUT)/bench/reactive.json
	$(BIN)/python benchmarks/agv.py --json $(OUT)/bench/agv.json
	$(BIN)/python benchmarks/tsplib.py --json $(OUT)/bench/tsplib.json
	$(BIN)/python benchmarks/batch.py --json $(OUT)/bench/batch.json
	$(BIN)/python benchmarks/elbows.py --json $(OUT)/bench/elbows.json

papers: $(VENV)/.installed
	for p in 000 001 002 003 004; do \
		MPLBACKEND=Agg $(BIN)/subtask-opt reproduce $$p --out $(OUT)/papers \
			--workers $(PAPER_WORKERS) --no-progress || exit 1; \
	done

lint: $(VENV)/.installed-dev
	$(BIN)/ruff check subtask_opt tests benchmarks
	$(BIN)/mypy subtask_opt

# Kernels run as Python (NUMBA_DISABLE_JIT=1) so that they count; the slow tests then
# take their reduced sizes (tests/conftest.py: size, examples; 100 random grids and polygon
# worlds instead of 2,000). Everything the run
# writes stays in .coverage/ (data, caches, temporary files) and htmlcov/ (the report).
COV := $(CURDIR)/.coverage
coverage: $(VENV)/.installed-dev
	rm -rf $(COV) htmlcov && mkdir -p $(COV)
	NUMBA_DISABLE_JIT=1 GRID_WORLDS=100 POLYGON_WORLDS=100 \
	MPLBACKEND=Agg PYTHONDONTWRITEBYTECODE=1 COVERAGE_FILE=$(COV)/data \
	SUBTASK_OPT_CACHE_DIR=$(COV)/kernels HYPOTHESIS_STORAGE_DIRECTORY=$(COV)/hypothesis \
	MPLCONFIGDIR=$(COV)/matplotlib $(BIN)/python -m pytest -n 2 -p no:cacheprovider \
		--basetemp=$(COV)/tmp --cov=subtask_opt --cov-report=term:skip-covered \
		--cov-report=html:htmlcov tests

# make fuzz: every test marked fuzz with FUZZ_EXAMPLES examples each (readers x5/x10, CLI
# options /10), 2,000 random grids and polygon worlds; prints and writes the input counts,
# the slowest input (limit 10 s, FUZZ_TIME_LIMIT_S) and the peak memory to out/fuzz/report.json
fuzz: $(VENV)/.installed-dev
	FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) FUZZ_REPORT=$(OUT)/fuzz/report.json MPLBACKEND=Agg \
		$(BIN)/python -m pytest -n 2 -m fuzz tests

# make campaign: the bad-input campaign (tests/cli/campaign.py): every command x option family
# and the public API given bad values, each in a child with RLIMIT_AS 3 GiB and a 30 s cap;
# prints attempts, tracebacks, hangs, crashes, wrong exits, silent accepts (all must be 0)
campaign: $(VENV)/.installed-dev
	MPLBACKEND=Agg $(BIN)/python -m tests.cli.campaign --attempts 3000 \
		--json $(OUT)/campaign.json

clean:
	-[ -x $(BIN)/python ] && $(BIN)/python -m subtask_opt._kernel_cache --clear
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis .mypy_cache .ruff_cache .coverage \
		.coverage.* htmlcov

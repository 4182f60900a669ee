# Two entry points (README): `make demo` and `make test` (and `make report`, the full report). Both create .venv with the
# dependencies at the versions in constraints.txt first; only python3, gcc and make are
# needed on the machine. The venv's own pip installs only uv (pinned in constraints.txt), and uv
# installs the rest from PyPI, the same versions (11 s of CPU for the demo's dependencies, 3 s more
# for the test tools, measured with an empty uv cache: it downloads in parallel). `make demo`
# installs the package and its dependencies; the targets that need the test tools (pytest, ruff,
# mypy, cmake, ...) add the [test] extras to the same .venv first, so demo then test (or the
# other way round) on one clone share it.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test
UV := $(BIN)/uv pip install --quiet --python $(BIN)/python -c constraints.txt
PYTEST ?= $(BIN)/python -m pytest

.PHONY: demo report test test-fast lint format wheel-check report-docs setup bench bench-build clean

$(STAMP): pyproject.toml constraints.txt
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -c constraints.txt uv
	$(UV) -e .
	touch $(STAMP)

$(TEST_STAMP): $(STAMP)
	$(UV) -e '.[test]'
	touch $(TEST_STAMP)

setup: $(TEST_STAMP)

# The main job: build every scene's FMU and the shipped systems' component FMUs in one queue on
# every core (rbfmu demo --jobs), run each scene through fmpy, build the systems' SSP archives and run
# them in ECOS, print the summary table (the plots drawn on the build processes meanwhile), then a
# short work-precision report on the same FMUs (a few rungs per ladder, labelled as such).
# Everything goes to build/ and out/ (untracked). Its time: README.md.
demo: $(STAMP)
	$(BIN)/rbfmu demo --out out --build-dir build
	$(BIN)/rbfmu report --short --build-dir build --out out/report

# The full work-precision report (about 5 minutes on 2 cores, two scenes at a time: rbfmu report --jobs) into out/report.
report: $(STAMP)
	$(BIN)/rbfmu report --build-dir build --out out/report

# The whole suite (slow and sanitizer tests included), on every core (pytest-xdist; a test
# file's tests stay on one worker, the shipped scenes' FMUs are built once: tests/conftest.py).
test: $(TEST_STAMP)
	$(PYTEST) -q -n auto --dist loadfile

# Daily work: everything but the slow and sanitizer tests.
test-fast: $(TEST_STAMP)
	$(PYTEST) -q -m "not slow and not sanitizer"

lint: $(TEST_STAMP)
	$(BIN)/ruff check modelsrc fmu rbcheck tests
	$(BIN)/ruff format --check modelsrc fmu rbcheck tests
	$(BIN)/mypy

format: $(TEST_STAMP)
	$(BIN)/ruff format modelsrc fmu rbcheck tests
	$(BIN)/ruff check --fix modelsrc fmu rbcheck tests

# The wheel, installed into an empty venv outside the checkout, must build and run an FMU.
wheel-check: $(TEST_STAMP)
	$(BIN)/python tools/wheel_check.py

# Regenerate the committed report in docs/report/ (a few minutes).
report-docs: $(STAMP)
	$(BIN)/rbfmu report --out docs/report

bench: $(STAMP)
	$(BIN)/rbfmu bench

# Build time of every scene's FMU: host only, all platforms first (cold cache) and cached.
bench-build: $(STAMP)
	$(BIN)/python tools/build_timing.py

clean:
	rm -rf build out dist .pytest_cache

# Sweeps: the three maps of docs/sweeps/ (docs/user_guide.md §3.1) and the throughput table.
.PHONY: sweep-docs sweep-bench
sweep-docs: $(STAMP)
	$(BIN)/python -m fmu.sweep.examples --out docs/sweeps --tables out/sweeps

sweep-bench: $(STAMP)
	$(BIN)/python -m fmu.sweep.bench

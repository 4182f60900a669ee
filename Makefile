# Two entry points (README): `make demo` and `make test`. Both create .venv with the
# pinned dependencies first; only python3, gcc and make are needed on the machine.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test setup bench clean

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

# The main job: build every scene's FMU, run it through fmpy, print the summary table
# (out/), then regenerate the work-precision report (docs/report/, a few minutes).
demo: $(STAMP)
	$(BIN)/rbfmu demo
	$(BIN)/rbfmu report

test: $(STAMP)
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/rbfmu bench

clean:
	rm -rf build out .pytest_cache

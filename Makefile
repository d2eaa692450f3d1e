# Two commands do all set-up on a fresh machine: `make scenario` and `make test`.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install test scenario bench lint clean

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

install: $(STAMP)

test: $(STAMP) lint
	$(BIN)/python -m pytest -q -m "not slow" --doctest-modules tapp search iter tests --ignore=tests/bench

scenario: $(STAMP)
	$(BIN)/python -m scenarios.run_all

bench: $(STAMP)
	$(BIN)/pip install --quiet -e ".[test,bench]"
	$(BIN)/python tests/bench/run.py

lint: $(STAMP)
	$(BIN)/ruff check tapp search iter tests scenarios
	$(BIN)/lint-imports

clean:
	rm -rf $(VENV) results .pytest_cache build *.egg-info

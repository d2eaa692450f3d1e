# Two commands do all set-up on a fresh machine: `make scenario` and `make test`.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# The test tools (pytest, the peers, mpmath, ...) on top: make scenario does without them.
TEST_STAMP := $(VENV)/.installed-test

.PHONY: install test test-all scenario readme bench docs lint clean

# uv installs what pip would (the newest releases pyproject.toml admits, from PyPI) in under
# half the time: 19 s instead of 51 s for the test install on this 2-core machine. Byte-compiled
# as pip does: this machine sets PYTHONDONTWRITEBYTECODE, so a module not compiled at install
# is compiled again by every process that imports it (a tapp command took 2.1 s instead of
# 0.9 s). The venv keeps its pip (tests/test_install.py builds the wheel with it).
UV := $(BIN)/uv pip install --quiet --compile-bytecode --python $(BIN)/python
# The checkout's own modules (an editable install), compiled for the same reason: every
# command make scenario runs, and every test worker, imports them (5 % of a command's start).
COMPILE := $(BIN)/python -m compileall -q -j 0 tapp search iter scenarios

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet uv
	$(UV) -e .
	touch $(STAMP)

$(TEST_STAMP): $(STAMP)
	$(UV) -e '.[test]'
	touch $(TEST_STAMP)

install: $(TEST_STAMP)

# On every CPU (at most 4), the modules that share a fixture kept together (tests/conftest.py).
PYTEST := $(BIN)/python -m pytest -q -n auto --doctest-modules tapp search iter tests --ignore=tests/bench

test: $(TEST_STAMP) lint
	$(COMPILE)
	$(PYTEST) -m "not slow"

# Everything, the slow reproductions too: before a release.
test-all: $(TEST_STAMP) lint
	$(COMPILE)
	$(PYTEST)

scenario: $(STAMP)
	$(COMPILE)
	$(BIN)/python -m scenarios.run_all

# The last make scenario's figures into the tracked README and scenarios/readme_figures.json.
readme: $(STAMP)
	$(BIN)/python -m scenarios.readme

bench: $(TEST_STAMP)
	$(UV) -e ".[test,bench]"
	$(BIN)/python tests/bench/run.py

# The reference site into build/site: the API from the docstrings, the input files, the deck's
# command language, the tutorial; --strict, so a broken reference fails (docs/mkdocs.yml).
docs: $(TEST_STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict -f docs/mkdocs.yml

lint: $(TEST_STAMP)
	$(BIN)/ruff check tapp search iter tests scenarios docs
	$(BIN)/lint-imports

clean:
	rm -rf $(VENV) results .pytest_cache build *.egg-info

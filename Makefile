# drive-envelope: set-up and the two entry points of the README (`make demo`, `make test`).
# Both create and reuse a virtual environment in .venv (git-ignored).

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
# every optional engine CI exercises; torch is opt-in (`make test-torch`, see README)
EXTRAS ?= test,all
STAMP := $(VENV)/.installed-$(subst ,,$(EXTRAS))

.PHONY: setup demo test lint typecheck pytest test-torch bench clean

$(STAMP): pyproject.toml Makefile
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --disable-pip-version-check --upgrade pip
	$(BIN)/python -m pip install -q --disable-pip-version-check -e '.[$(EXTRAS)]'
	touch $@

setup: $(STAMP)

demo: setup
	$(BIN)/drive-envelope envelope show examples/envelopes/demo.toml

lint: setup
	$(BIN)/ruff check src tests benchmarks examples
	$(BIN)/ruff format --check src tests benchmarks examples

typecheck: setup
	$(BIN)/mypy

pytest: setup
	$(BIN)/python -m pytest -q

test: lint typecheck pytest

test-torch:
	$(MAKE) EXTRAS=test,all,torch pytest

bench: setup
	$(BIN)/python benchmarks/run_all.py

clean:
	rm -rf $(VENV) build dist .pytest_cache .mypy_cache .ruff_cache

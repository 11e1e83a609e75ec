# drive-envelope: set-up and the two entry points of the README (`make demo`, `make test`).
# Both create and reuse a virtual environment in .venv (git-ignored); the demo installs only what it needs.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
# every optional engine CI exercises, torch and the Isaac Lab adapter's needs included
EXTRAS ?= test,all,isaaclab
# Isaac Lab's PyPI wheel pins numpy<2 and Isaac Sim: install it without its dependencies (the
# adapter needs only isaaclab.actuators, whose imports the `isaaclab` extra provides)
ISAACLAB ?= isaaclab==2.3.2.post1
STAMP := $(VENV)/.installed-$(subst ,,$(EXTRAS))

.PHONY: setup demo test lint typecheck pytest test-mjlab test-isaaclab3 bench clean

# the demo needs the core and matplotlib only; the full set-up (a superset) marks it done too, so
# `make test` then `make demo` installs nothing, and `make demo` then `make test` adds the engines
DEMO_STAMP := $(VENV)/.installed-demo
PIP := $(BIN)/python -m pip install -q --disable-pip-version-check

$(STAMP): pyproject.toml Makefile
	@echo "== set-up: .venv with drive-envelope [$(EXTRAS)] (every engine; minutes on a fresh machine)"
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(PIP) --upgrade pip
	$(PIP) -e '.[$(EXTRAS)]'
	$(PIP) --no-deps '$(ISAACLAB)'
	touch $@ $(DEMO_STAMP)

$(DEMO_STAMP): pyproject.toml Makefile
	@echo "== set-up: .venv with drive-envelope and matplotlib (the demo's needs; \`make test\` adds the engines)"
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(PIP) -e '.[plot]'
	touch $@

# the native MuJoCo actuator plugin, built against the installed mujoco wheel's headers and library
PLUGIN := plugin/mujoco/build/libdrive_envelope_mujoco.so
$(PLUGIN): $(STAMP) $(wildcard plugin/mujoco/*.cc plugin/mujoco/*.h) plugin/mujoco/CMakeLists.txt
	$(BIN)/python -m drive_envelope._src.adapters.mujoco.build --quiet --force

setup: $(STAMP) $(PLUGIN)

# the main job: datasheet -> envelope -> simulated actuator -> plot (files in build/demo/)
demo: $(DEMO_STAMP)
	@echo "== demo: datasheet -> envelope -> simulated actuator -> plot, into build/demo/"
	mkdir -p build/demo
	$(BIN)/drive-envelope derive tmotor-ak80-6 -o build/demo/tmotor-ak80-6.toml
	$(BIN)/drive-envelope envelope show build/demo/tmotor-ak80-6.toml
	$(BIN)/drive-envelope simulate examples/scenarios/actuator_swing.toml --engine reference --output build/demo/actuator_swing.csv
	$(BIN)/drive-envelope plot examples/scenarios/actuator_swing.toml --trajectory build/demo/actuator_swing.csv --output build/demo/actuator_swing.png
	@echo "demo outputs: build/demo/ (envelope file, trajectory CSV, plot PNG)"

lint: setup
	$(BIN)/ruff check src tests benchmarks examples scripts
	$(BIN)/ruff format --check src tests benchmarks examples scripts

typecheck: setup
	$(BIN)/mypy

pytest: setup
	$(BIN)/python -m pytest -q

# mjlab pins MuJoCo 3.11 and MuJoCo Warp 3.11: its tests run in their own environment (.venv-mjlab)
test-mjlab: setup
	PYTHON=$(PYTHON) scripts/test_mjlab.sh

# Isaac Lab 3.0 pins Python 3.12, torch 2.11 and newton 1.6.1: its tests run in .venv-isaaclab3 (2.3 stays in .venv)
test-isaaclab3: setup
	scripts/test_isaaclab3.sh

test: lint typecheck pytest test-mjlab test-isaaclab3

bench: setup
	for f in benchmarks/bench_*.py; do echo "== $$f"; $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) .venv-mjlab .venv-isaaclab3 build dist .pytest_cache .mypy_cache .ruff_cache plugin/mujoco/build

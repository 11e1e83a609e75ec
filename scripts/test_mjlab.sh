#!/usr/bin/env bash
# The mjlab tests in their own virtual environment: mjlab 1.6 pins MuJoCo 3.11 and MuJoCo Warp 3.11,
# the main .venv has MuJoCo 4 (the plugin's). Creates .venv-mjlab once (mjlab, pytest, and this
# project editable without extras: the mjlab adapter needs no MuJoCo of ours), then runs
# tests/mjlab_env on CPU. Fresh install measured: 2 min 41 s, 6.7 GB (torch with its CUDA libraries).
#
#   scripts/test_mjlab.sh [pytest arguments]     PYTHON=python3.11 MJLAB=mjlab==1.6.0 to override
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"
VENV="${MJLAB_VENV:-.venv-mjlab}"
MJLAB="${MJLAB:-mjlab==1.6.0}"
STAMP="$VENV/.installed-${MJLAB//[^A-Za-z0-9.]/_}"
if [ ! -f "$STAMP" ] || [ pyproject.toml -nt "$STAMP" ]; then
  test -x "$VENV/bin/python" || "$PYTHON" -m venv "$VENV"
  echo '*' > "$VENV/.gitignore"  # the environment is never committed, whatever .gitignore says
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check "$MJLAB" pytest
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -e .
  touch "$STAMP"
fi
exec "$VENV/bin/python" -m pytest -q tests/mjlab_env "$@"

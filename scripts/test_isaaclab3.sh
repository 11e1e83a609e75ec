#!/usr/bin/env bash
# The Isaac Lab 3.0 tests in their own virtual environment: Isaac Lab 3.0's wheel pins Python 3.12,
# torch 2.11, warp-lang 1.17 and newton 1.6.1, while the main .venv (Python 3.11, Isaac Lab 2.3,
# newton >= 1.8) keeps testing 2.3. Creates .venv-isaaclab3 once and runs tests/isaaclab3 on CPU.
#
# Isaac Lab is installed without its dependencies (its wheel also pins Isaac Sim's kit extras,
# transformers, open3d, ...): only what isaaclab.actuators, its Newton backend and our adapter import.
# Fresh install measured: 2 min 34 s, 5.7 GB (torch 2.11 with its CUDA libraries; the CPU-only wheel is
# not on PyPI). Python 3.12 comes from $PYTHON312, else `python3.12` on PATH, else pyenv's newest installed 3.12.
#
#   scripts/test_isaaclab3.sh [pytest arguments]     ISAACLAB3=isaaclab==3.0.0 to override
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${ISAACLAB3_VENV:-.venv-isaaclab3}"
ISAACLAB3="${ISAACLAB3:-isaaclab==3.0.0}"
# exactly the pins of Isaac Lab 3.0.0's wheel (its METADATA), so the adapter meets the versions users get
PINS=(
  "torch==2.11.0" "warp-lang==1.17.0" "newton[sim]==1.6.1" "numpy>=2" "usd-core>=25.5,<26.9"
  "newton-usd-schemas>=0.5.0" "prettytable>=3.3.0" "lazy_loader>=0.4" "gymnasium>=1.2.0" "trimesh>=4.6.8"
  "scipy>=1.11.0" "psutil" "packaging" "toml" "rich" "pytest"
)
STAMP="$VENV/.installed-${ISAACLAB3//[^A-Za-z0-9.]/_}"

find_python312() {
  if [ -n "${PYTHON312:-}" ]; then echo "$PYTHON312"; return; fi
  if command -v python3.12 >/dev/null 2>&1 && python3.12 -c 'import venv' 2>/dev/null; then
    command -v python3.12; return
  fi
  local root="${PYENV_ROOT:-$HOME/.pyenv}"
  local found
  found="$(ls -d "$root"/versions/3.12.* 2>/dev/null | sort -V | tail -n 1 || true)"
  if [ -n "$found" ] && [ -x "$found/bin/python" ]; then echo "$found/bin/python"; return; fi
  echo "test_isaaclab3.sh: Isaac Lab 3.0 needs Python 3.12; none found (set PYTHON312=/path/to/python3.12," \
    "or install one: pyenv install 3.12)" >&2
  exit 2
}

if [ ! -f "$STAMP" ] || [ pyproject.toml -nt "$STAMP" ] || [ "$0" -nt "$STAMP" ]; then
  if [ ! -x "$VENV/bin/python" ]; then
    "$(find_python312)" -m venv "$VENV"
  fi
  echo '*' > "$VENV/.gitignore"  # the environment is never committed, whatever .gitignore says
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check "${PINS[@]}"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check --no-deps "$ISAACLAB3"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -e .
  touch "$STAMP"
fi
exec "$VENV/bin/python" -m pytest -q -p no:cacheprovider tests/isaaclab3 "$@"

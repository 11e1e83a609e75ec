"""The public API contract: ``__all__`` snapshot, lazy imports, generated docs kept fresh."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

import drive_envelope
from drive_envelope._src.params.glossary import GLOSSARY_PATH, render_glossary

HEAVY = ("mujoco", "warp", "torch", "pxr", "matplotlib", "ovphysx", "newton", "pyarrow", "pandas", "yaml")

CORE_API = {
    "DriveEnvelopeError",
    "InputError",
    "PerformanceEnvelope",
    "QuadrantCorners",
    "UnitsError",
    "__version__",
    "clamp_drive_impulse",
    "clamp_effort",
    "clamp_effort_implicit",
    "implicit_drive_effort",
    "load_envelope",
    "save_envelope",
}


def _loaded_heavy(code: str) -> list[str]:
    script = (
        f"import sys\n{code}\nprint(__import__('json').dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_core_all_snapshot() -> None:
    """Keep the top-level __all__ equal to the reviewed snapshot."""
    assert set(drive_envelope.__all__) == CORE_API


@pytest.mark.parametrize("name", sorted(CORE_API))
def test_every_exported_name_exists(name: str) -> None:
    """Resolve every name in __all__."""
    assert hasattr(drive_envelope, name)


def test_public_modules_export_what_they_define() -> None:
    """Resolve every name in each light public module's __all__."""
    for module_name in (
        "drive_envelope.units",
        "drive_envelope.io",
        "drive_envelope.params",
        "drive_envelope.errors",
    ):
        module = importlib.import_module(module_name)
        for name in module.__all__:
            assert hasattr(module, name), f"{module_name}.{name}"


def test_import_is_light() -> None:
    """Import drive_envelope without loading any engine or plotting package."""
    assert _loaded_heavy("import drive_envelope") == []


def test_cli_help_is_light() -> None:
    """Build the whole CLI parser (every subcommand) without loading any heavy package."""
    code = (
        "import contextlib, io\n"
        "from drive_envelope._src.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        main(['--help'])\n    except SystemExit:\n        pass"
    )
    assert _loaded_heavy(code) == []


def test_glossary_is_fresh() -> None:
    """Regenerate docs/glossary.md from the parameter table and find no difference."""
    assert Path(GLOSSARY_PATH).read_text(encoding="utf-8") == render_glossary(), (
        "run: python -m drive_envelope._src.params.glossary"
    )

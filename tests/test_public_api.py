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

HEAVY = (
    "mujoco",
    "mujoco_warp",
    "mjlab",
    "isaaclab",
    "warp",
    "torch",
    "pxr",
    "matplotlib",
    "ovphysx",
    "newton",
    "pyarrow",
    "pandas",
    "yaml",
)

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


PUBLIC_MODULES = sorted(
    f"drive_envelope.{path.stem}"
    for path in (Path(drive_envelope.__file__).parent).glob("*.py")
    if not path.stem.startswith("_")
)
SNAPSHOT = Path(__file__).parent / "golden" / "public_api.json"


def _public_api() -> dict[str, list[str]]:
    return {name: sorted(importlib.import_module(name).__all__) for name in PUBLIC_MODULES}


def _snapshot_differences(current: dict[str, list[str]], reviewed: dict[str, list[str]]) -> list[str]:
    """One line per facade whose ``__all__`` differs from the snapshot: every name added and removed."""
    lines = []
    for module in sorted(set(current) | set(reviewed)):
        if module not in reviewed:
            lines.append(f"{module}: a new public module (not in the snapshot)")
        elif module not in current:
            lines.append(f"{module}: in the snapshot but no longer a public module")
        else:
            extra = sorted(set(current[module]) - set(reviewed[module]))
            missing = sorted(set(reviewed[module]) - set(current[module]))
            if extra or missing:
                lines.append(f"{module}: extra {extra}, missing {missing}")
    return lines


@pytest.mark.parametrize("module_name", PUBLIC_MODULES)
def test_public_module_exports_what_it_defines(module_name: str) -> None:
    """Resolve every name in each public module's __all__: every absent name in one failure.

    A name whose optional extra is not installed (an engine adapter's ImportError) is not absent;
    all of them are listed in one skip, after every other name was resolved.
    """
    module = importlib.import_module(module_name)
    absent, optional = [], []
    for name in module.__all__:
        try:
            getattr(module, name)
        except ImportError as exc:  # an engine adapter whose optional extra is not installed
            optional.append(f"{module_name}.{name}: {exc}")
        except AttributeError:
            absent.append(name)
    assert not absent, f"{module_name}.__all__ names what the module lacks: {absent}"
    if optional:
        pytest.skip("; ".join(optional))


def test_snapshot_differences_name_every_facade_and_name() -> None:
    """The snapshot's failure lists every added and removed name of every facade, not the first."""
    reviewed = {"a": ["x", "y"], "b": ["p"], "gone": ["q"]}
    current = {"a": ["x", "z"], "b": ["p", "r"], "new": ["s"]}
    assert _snapshot_differences(current, reviewed) == [
        "a: extra ['z'], missing ['y']",
        "b: extra ['r'], missing []",
        "gone: in the snapshot but no longer a public module",
        "new: a new public module (not in the snapshot)",
    ]


def test_public_api_snapshot() -> None:
    """Keep every public module's __all__ equal to the reviewed snapshot (update it on purpose)."""
    differences = _snapshot_differences(_public_api(), json.loads(SNAPSHOT.read_text(encoding="utf-8")))
    assert not differences, (
        "public API changed: review, then regenerate tests/golden/public_api.json\n" + "\n".join(differences)
    )


@pytest.mark.parametrize("module_name", PUBLIC_MODULES)
def test_public_module_import_is_light(module_name: str) -> None:
    """Import each public module (engine adapters too) without loading any engine package."""
    assert _loaded_heavy(f"import {module_name}") == []


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


@pytest.mark.parametrize("argv", [["--help"], ["derive", "--help"], ["check", "--bogus"], ["simulate"]])
def test_cli_parser_loads_no_numpy(argv: list[str]) -> None:
    """Answer --help and argument errors without NumPy or pint (the startup benchmark's goal)."""
    code = (
        "import contextlib, io, sys\n"
        "from drive_envelope._src.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):\n"
        f"    try:\n        main({argv!r})\n    except SystemExit:\n        pass\n"
        "print(__import__('json').dumps([m for m in ('numpy', 'pint') if m in sys.modules]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert json.loads(out.strip().splitlines()[-1]) == []


def test_glossary_is_fresh() -> None:
    """Regenerate docs/glossary.md from the parameter table and find no difference."""
    assert Path(GLOSSARY_PATH).read_text(encoding="utf-8") == render_glossary(), (
        "run: python -m drive_envelope._src.params.glossary docs/glossary.md"
    )

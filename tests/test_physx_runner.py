"""The PhysX runner's own logic, without PhysX: version gate, cache folder, revolute unwrapping."""

from __future__ import annotations

import importlib.machinery
import math
import sys
import tempfile
import types
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.adapters.physx import runner as physx_runner
from drive_envelope.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"


def _fake_ovphysx(version: str) -> types.ModuleType:
    module = types.ModuleType("ovphysx")
    module.__spec__ = importlib.machinery.ModuleSpec("ovphysx", None)
    module.__version__ = version  # type: ignore[attr-defined]
    return module


@pytest.mark.parametrize(
    ("version", "release"),
    [("0.7.0.74035321", (0, 7)), ("0.3.7", (0, 3)), ("1.0", (1, 0)), ("none", (0, 0)), ("dev", (0, 0))],
)
def test_release_reads_major_and_minor(version: str, release: tuple[int, int]) -> None:
    """Read (major, minor) from a version string, (0, 0) when there is none."""
    assert physx_runner._release(version) == release


def test_old_ovphysx_is_one_line_input_error(monkeypatch: pytest.MonkeyPatch) -> None:
    """Refuse ovphysx 0.3.7 with one line naming the version found and the extra."""
    monkeypatch.setitem(sys.modules, "ovphysx", _fake_ovphysx("0.3.7"))
    with pytest.raises(InputError, match=r"needs ovphysx >= 0\.7 \(found 0\.3\.7\).*drive-envelope\[physx\]"):
        physx_runner.run_jobs([])


def test_missing_ovphysx_is_input_error(monkeypatch: pytest.MonkeyPatch) -> None:
    """Report a missing ovphysx as an InputError, not an ImportError."""
    monkeypatch.setitem(sys.modules, "ovphysx", None)
    with pytest.raises(InputError, match=r"found none"):
        physx_runner.inspect_drives(EXAMPLES / "constant_load_tgs.toml")


def test_inspect_missing_file_is_input_error(tmp_path: Path) -> None:
    """Name the missing USD file before starting PhysX."""
    with pytest.raises(InputError, match="no such file"):
        physx_runner.inspect_drives(tmp_path / "absent.usda")


@pytest.mark.usd
def test_cli_reports_old_ovphysx_and_exits_2(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """Exit 2 with ``drive-envelope: error:`` and no output file when ovphysx is too old."""
    from drive_envelope._src.cli.main import main

    monkeypatch.setitem(sys.modules, "ovphysx", _fake_ovphysx("0.3.7"))
    out = tmp_path / "run.csv"
    scenario = EXAMPLES / "plain_drive_applied_effort.toml"
    assert main(["simulate", str(scenario), "--engine", "physx", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("drive-envelope: error: ") and "0.3.7" in err and "Traceback" not in err
    assert not out.exists()


def test_cache_folder_is_in_temp_not_home_or_repository() -> None:
    """Keep ovphysx's, ovstage's and Warp's caches under the temp folder."""
    folder = physx_runner.cache_folder()
    assert folder.parent == Path(tempfile.gettempdir())
    assert Path.home() not in folder.parents and Path(__file__).resolve().parents[1] not in folder.parents


def test_unwrap_undoes_revolute_wrapping() -> None:
    """Shift wrapped revolute positions by whole turns so they follow the velocity."""
    dt, speed = 0.01, 40.0  # 0.4 rad per step: several wraps over 100 steps
    true = speed * dt * np.arange(101)
    wrapped = (true + math.pi) % (2.0 * math.pi) - math.pi
    velocity = np.full(101, speed)
    np.testing.assert_allclose(physx_runner._unwrap(wrapped, velocity, dt), true, atol=1e-12)

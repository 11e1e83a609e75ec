"""--json on every command that reports (issue 24): plot, usd apply, mujoco apply print one object."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main

REPO = Path(__file__).resolve().parents[1]
GOOD = REPO / "tests" / "corpus" / "good"
GO2 = REPO.parent / "shared" / "data" / "menagerie" / "go2.xml"
ENVELOPE = {  # tests/corpus/good/envelope.toml, as written there
    "name": "corpus",
    "joint": "revolute",
    "max_effort": 10.0,
    "max_actuator_velocity": 5.0,
    "velocity_dependent_resistance": 0.5,
    "speed_effort_gradient": 0.2,
}


def _json(capsys: pytest.CaptureFixture[str], argv: list[str]) -> dict[str, object]:
    assert main(argv) == 0
    out = capsys.readouterr().out
    data = json.loads(out)
    assert isinstance(data, dict)
    return data


def test_plot_json_reports_the_figure(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """plot --json: the output (its missing folder made), the envelope and each trajectory's samples."""
    pytest.importorskip("matplotlib")
    out = tmp_path / "new" / "env.png"
    data = _json(
        capsys, ["plot", str(GOOD / "envelope.toml"), "-t", str(GOOD / "log.csv"), "-o", str(out), "--json"]
    )
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert data["output"] == str(out) and data["envelope"] == ENVELOPE and data["dpi"] == 120
    rows = len((GOOD / "log.csv").read_text(encoding="utf-8").strip().splitlines()) - 1
    assert data["trajectories"] == [{"file": str(GOOD / "log.csv"), "label": "log", "samples": rows}]


def test_usd_apply_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """usd apply --json: one object with the written layer and each drive's envelope (SI)."""
    pytest.importorskip("pxr")
    out = tmp_path / "robot_envelope.usda"
    argv = [
        "usd", "apply", str(REPO / "examples" / "usd" / "robot.usda"), "--joint", "/Robot/joints/shoulder",
        "--envelope", str(GOOD / "envelope.toml"), "-o", str(out), "--json",
    ]  # fmt: skip
    data = _json(capsys, argv)
    assert data["output"] == str(out) and data["mode"] == "layer" and out.is_file()
    assert data["drives"] == [
        {
            "joint": "/Robot/joints/shoulder",
            "instance": "angular",
            "authored_at": "/Robot/joints/shoulder",
            "envelope": ENVELOPE,
        }
    ]
    assert data["with_envelope"] == 1 and data["joint_drives"] == 3


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="needs mujoco")
def test_mujoco_apply_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """mujoco apply --json: the drive that replaced Go2's hip motor, its gains and envelope."""
    if not GO2.is_file():
        pytest.skip("needs ../shared/data/menagerie/go2.xml")
    out = tmp_path / "go2.xml"
    argv = [
        "mujoco", "apply", str(GO2), "--joint", "FL_hip_joint", "--envelope", str(GOOD / "envelope.toml"),
        "--stiffness", "20", "--damping", "0.5", "-o", str(out), "--json",
    ]  # fmt: skip
    data = _json(capsys, argv)
    (drive,) = data["drives"]  # type: ignore[misc]
    assert drive["joint"] == "FL_hip_joint" and drive["replaced"] == "motor 'FL_hip'"
    assert drive["stiffness"] == 20.0 and drive["damping"] == 0.5 and drive["envelope"] == ENVELOPE
    assert data["output"] == str(out) and out.is_file()

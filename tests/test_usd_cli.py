"""``drive-envelope usd apply|show`` on the example robot (usd-core only, no simulator)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main

pytestmark = pytest.mark.usd

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    """A copy of the example robot, its map and the envelope files the map names."""
    (tmp_path / "usd").mkdir()
    (tmp_path / "envelopes").mkdir()
    for name in ("robot.usda", "map.toml", "linear_actuator.toml"):
        shutil.copy(EXAMPLES / "usd" / name, tmp_path / "usd" / name)
    shutil.copy(EXAMPLES / "envelopes" / "demo.toml", tmp_path / "envelopes" / "demo.toml")
    return tmp_path / "usd" / "robot.usda"


def _show(path: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, dict[str, object]]:
    assert main(["usd", "show", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    return {d["joint"]: d for d in data["drives"]}


def test_apply_map_writes_every_joint(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Apply a map file to the whole robot and list the envelopes in SI."""
    out = tmp_path / "robot_env.usda"
    before = robot.read_bytes()
    assert (
        main(["usd", "apply", str(robot), "--map", str(robot.with_name("map.toml")), "--output", str(out)])
        == 0
    )
    assert "wrote 3 drive(s)" in capsys.readouterr().err  # status lines go to stderr
    assert robot.read_bytes() == before  # --output leaves the input alone
    drives = _show(out, capsys)
    shoulder, slide = drives["/Robot/joints/shoulder"]["envelope"], drives["/Robot/joints/slide"]["envelope"]
    assert isinstance(shoulder, dict) and isinstance(slide, dict)
    assert shoulder["max_effort"] == pytest.approx(12.05568, rel=1e-6)
    assert shoulder["max_actuator_velocity"] == pytest.approx(37.69911184, rel=1e-6)  # 360 rpm
    assert slide["velocity_dependent_resistance"] == pytest.approx(40.0, rel=1e-6)
    text = out.read_text(encoding="utf-8")
    assert (
        "PhysxDrivePerformanceEnvelopeAPI:angular" in text
        and "PhysxDrivePerformanceEnvelopeAPI:linear" in text
    )


def test_apply_one_joint_in_place(robot: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Replace the input atomically when no --output is given."""
    envelope = robot.parent.parent / "envelopes" / "demo.toml"
    assert (
        main(["usd", "apply", str(robot), "--joint", "/Robot/joints/elbow", "--envelope", str(envelope)]) == 0
    )
    capsys.readouterr()
    drives = _show(robot, capsys)
    assert drives["/Robot/joints/elbow"]["envelope"] is not None
    assert drives["/Robot/joints/shoulder"]["envelope"] is None
    assert not list(robot.parent.glob(".robot.usda.*"))  # no temporary file left behind


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--joint", "/Robot/joints/nope", "--envelope", "ENV"], "no such prim"),
        (["--joint", "/Robot/joints/slide", "--envelope", "ENV"], "envelope is for a revolute joint"),
        (["--joint", "/Robot/joints/slide"], "needs --datasheet FILE or --envelope FILE"),
        (["--map", "BADMAP"], "matches no joint"),
        (
            ["--joint", "/Robot/joints/elbow", "--envelope", "ENV", "--output", "x.txt"],
            "expected a .usd, .usda or .usdc",
        ),
    ],
)
def test_failed_apply_leaves_input_untouched(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    """Exit 2 with one error line and keep the input byte for byte."""
    envelope = str(robot.parent.parent / "envelopes" / "demo.toml")
    bad_map = tmp_path / "bad_map.toml"
    bad_map.write_text(
        f'[joints]\n"/Robot/joints/shoulder" = {json.dumps(envelope)}\n"/Robot/wheel*" = "x.toml"\n'
    )
    args = [envelope if a == "ENV" else str(bad_map) if a == "BADMAP" else a for a in args]
    before = robot.read_bytes()
    assert main(["usd", "apply", str(robot), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("drive-envelope: error: ") and message in err[0]
    assert robot.read_bytes() == before
    assert sorted(p.name for p in robot.parent.iterdir()) == [
        "linear_actuator.toml",
        "map.toml",
        "robot.usda",
    ]


def test_show_table_lists_drives(robot: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Print one row per drive with the stage units in the header."""
    assert main(["usd", "show", str(robot)]) == 0
    out = capsys.readouterr().out
    assert "metersPerUnit 0.01" in out
    assert all(j in out for j in ("/Robot/joints/shoulder", "/Robot/joints/elbow", "/Robot/joints/slide"))


def test_show_missing_file_is_an_input_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Report a missing asset in one line, exit 2."""
    assert main(["usd", "show", str(tmp_path / "none.usda")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_map_file_validation(tmp_path: Path) -> None:
    """Refuse map entries with unknown keys or two sources."""
    from drive_envelope import InputError
    from drive_envelope.usd import read_map

    bad = tmp_path / "map.toml"
    bad.write_text('[joints]\n"/a" = { envelope = "a.toml", datasheet = "b.toml" }\n')
    with pytest.raises(InputError, match="exactly one of 'envelope' or 'datasheet'"):
        read_map(bad)
    bad.write_text('[joint]\n"/a" = "a.toml"\n')
    with pytest.raises(InputError, match="unknown key 'joint'"):
        read_map(bad)

"""``drive-envelope usd apply|show`` on the example robot: outputs, flags, one-line errors (usd-core only)."""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main

pytestmark = pytest.mark.usd

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ENVELOPE = "ENV"  # replaced by the example's envelope file in each test


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    """A copy of the example robot, its map and the envelope files the map names."""
    (tmp_path / "usd").mkdir()
    (tmp_path / "envelopes").mkdir()
    for name in ("robot.usda", "map.toml", "linear_actuator.toml"):
        shutil.copy(EXAMPLES / "usd" / name, tmp_path / "usd" / name)
    shutil.copy(EXAMPLES / "envelopes" / "demo.toml", tmp_path / "envelopes" / "demo.toml")
    return tmp_path / "usd" / "robot.usda"


def _envelope(robot: Path) -> str:
    return str(robot.parent.parent / "envelopes" / "demo.toml")


def _show(path: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, dict[str, object]]:
    assert main(["usd", "show", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    return {d["joint"]: d for d in data["drives"]}


def _files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def test_apply_map_writes_a_layer_in_another_folder(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Write a small layer elsewhere that finds the robot by a relative path and holds only envelopes."""
    out = tmp_path / "out" / "robot_env.usda"
    out.parent.mkdir()
    before = robot.read_bytes()
    argv = ["usd", "apply", str(robot), "--map", str(robot.with_name("map.toml")), "-o", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "wrote 3 drive(s)" in err and "a layer over" in err and "3 of 3 joint drives" in err
    assert robot.read_bytes() == before  # the asset is never edited: comments and layout stay
    text = out.read_text(encoding="utf-8")
    assert "@../usd/robot.usda@" in text  # the path is right for the new folder (item 2: was @./robot.usda@)
    assert "metersPerUnit = 0.01" in text  # stage metadata repeated: USD reads it from the root layer only
    assert "def " not in text and "Cube" not in text  # only overrides: the robot stays in robot.usda
    drives = _show(out, capsys)
    shoulder, slide = drives["/Robot/joints/shoulder"]["envelope"], drives["/Robot/joints/slide"]["envelope"]
    assert isinstance(shoulder, dict) and isinstance(slide, dict)
    assert shoulder["max_effort"] == pytest.approx(12.05568, rel=1e-6)
    assert shoulder["max_actuator_velocity"] == pytest.approx(37.69911184, rel=1e-6)  # 360 rpm
    assert slide["velocity_dependent_resistance"] == pytest.approx(40.0, rel=1e-6)
    assert drives["/Robot/joints/elbow"]["stiffness"] == pytest.approx(1.0 * 180 / 3.141592653589793 * 1e-4)


def test_layer_survives_moving_the_pair(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Keep working when the asset folder and the layer move together (the path is relative)."""
    out = robot.parent.parent / "layers" / "robot_env.usda"
    out.parent.mkdir()
    assert main(["usd", "apply", str(robot), "--joint", "/Robot/joints/elbow", "--envelope", _envelope(robot),
                 "-o", str(out)]) == 0  # fmt: skip
    capsys.readouterr()
    moved = tmp_path.parent / f"{tmp_path.name}_moved"
    shutil.move(str(tmp_path), str(moved))
    drives = _show(moved / "layers" / "robot_env.usda", capsys)
    assert drives["/Robot/joints/elbow"]["envelope"] is not None and len(drives) == 3


def test_flatten_writes_a_self_contained_copy(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Write the whole robot with its envelopes into one file that needs nothing else."""
    out = tmp_path / "flat.usdc"
    argv = [
        "usd",
        "apply",
        str(robot),
        "--map",
        str(robot.with_name("map.toml")),
        "--flatten",
        "-o",
        str(out),
    ]
    assert main(argv) == 0
    assert "self-contained" in capsys.readouterr().err
    shutil.rmtree(robot.parent)  # the asset is gone: the flat file still has everything
    drives = _show(out, capsys)
    assert len(drives) == 3 and all(d["envelope"] is not None for d in drives.values())


def test_apply_one_joint_in_place(robot: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Edit the asset itself with --in-place, atomically."""
    assert main(["usd", "apply", str(robot), "--joint", "/Robot/joints/elbow", "--envelope", _envelope(robot),
                 "--in-place"]) == 0  # fmt: skip
    assert "in place" in capsys.readouterr().err
    drives = _show(robot, capsys)
    assert drives["/Robot/joints/elbow"]["envelope"] is not None
    assert drives["/Robot/joints/shoulder"]["envelope"] is None
    assert not list(robot.parent.glob(".robot.usda.*"))  # no temporary file left behind


def test_in_place_writes_through_a_symlink(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Edit the file a symlinked asset points to, and keep the link (item 4: the link was replaced)."""
    link = tmp_path / "robot_link.usda"
    link.symlink_to(robot)
    assert main(["usd", "apply", str(link), "--joint", "/Robot/joints/elbow", "--envelope", _envelope(robot),
                 "--in-place"]) == 0  # fmt: skip
    capsys.readouterr()
    assert link.is_symlink() and link.resolve() == robot.resolve()
    assert _show(robot, capsys)["/Robot/joints/elbow"]["envelope"] is not None


def test_read_only_asset_is_refused_unless_forced(
    robot: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Refuse a 0444 asset with one line; --force replaces it and keeps its mode."""
    robot.chmod(0o444)
    before = robot.read_bytes()
    real_access = os.access
    monkeypatch.setattr(
        os, "access", lambda p, mode: real_access(p, mode) and not str(p).endswith("robot.usda")
    )
    argv = [
        "usd",
        "apply",
        str(robot),
        "--joint",
        "/Robot/joints/elbow",
        "--envelope",
        _envelope(robot),
        "--in-place",
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "read-only (pass --force to replace it)" in err[0]
    assert robot.read_bytes() == before
    assert main([*argv, "--force"]) == 0
    assert robot.read_bytes() != before and robot.stat().st_mode & 0o777 == 0o444


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--joint", "/Robot/joints/nope", "--envelope", ENVELOPE, "-o", "OUT"], "no such prim in /"),
        (
            ["--joint", "/Robot/joints/slide", "--envelope", ENVELOPE, "-o", "OUT"],
            "envelope is for a revolute joint",
        ),
        (["--joint", "/Robot/joints/slide", "-o", "OUT"], "needs --datasheet FILE or --envelope FILE"),
        (["--map", "BADMAP", "-o", "OUT"], "key 'joints./Robot/wheel*': matches no joint path"),
        (["--map", "TYPEMAP", "-o", "OUT"], "key 'joints./Robot/joints/sl*': joint '/Robot/joints/slide'"),
        (["--map", "SHADOWMAP", "-o", "OUT"], "key 'joints./Robot/joints/elbow': never used"),
        (
            ["--joint", "/Robot/joints/elbow", "--envelope", ENVELOPE, "-o", "x.txt"],
            "expected a .usd, .usda or .usdc",
        ),
        (
            ["--joint", "/Robot/joints/elbow", "--envelope", ENVELOPE],
            "say where the result goes: -o robot_envelope",
        ),
        (
            ["--joint", "/Robot/joints/elbow", "--envelope", ENVELOPE, "-o", "ASSET"],
            "is the asset itself: use --in-place",
        ),
        (["--joint", "/Robot/joints/elbow", "--envelope", ENVELOPE, "-o", "FOLDER"], "is a folder"),
        (
            ["--joint", "/Robot/joints/elbow", "--envelope", ENVELOPE, "--in-place", "-o", "OUT"],
            "drop -o/--output",
        ),
    ],
)
def test_failed_apply_writes_nothing(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    """Exit 2 with one error line naming the map key or flag, and leave every file as it was."""
    envelope = _envelope(robot)
    maps = {
        "BADMAP": f'"/Robot/joints/shoulder" = {json.dumps(envelope)}\n"/Robot/wheel*" = "tmotor-ak80-6"\n',
        "TYPEMAP": f'"/Robot/joints/sl*" = {json.dumps(envelope)}\n',  # a revolute envelope on the slide
        "SHADOWMAP": f'"/Robot/joints/*" = {json.dumps(envelope)}\n"/Robot/joints/elbow" = "tmotor-ak80-6"\n',
    }
    for name, body in maps.items():
        (robot.parent / f"{name.lower()}.toml").write_text("[joints]\n" + body, encoding="utf-8")
    replace = {
        "ENV": envelope,
        "OUT": str(tmp_path / "out.usda"),
        "ASSET": str(robot),
        "FOLDER": str(tmp_path),
    }
    replace.update({name: str(robot.parent / f"{name.lower()}.toml") for name in maps})
    args = [replace.get(a, a) for a in args]
    before = {path: path.read_bytes() for path in robot.parent.iterdir()}
    listing = _files(tmp_path)
    assert main(["usd", "apply", str(robot), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("drive-envelope: error: ") and message in err[0], err
    assert {path: path.read_bytes() for path in robot.parent.iterdir()} == before
    assert _files(tmp_path) == listing


def test_usdz_in_place_names_no_flag_the_user_did_not_give(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Say a .usdz cannot be edited in place and suggest -o (the old message named an unused --output)."""
    from pxr import UsdUtils

    package = tmp_path / "robot.usdz"
    assert UsdUtils.CreateNewUsdzPackage(str(EXAMPLES / "usd" / "robot.usda"), str(package))
    argv = ["usd", "apply", str(package), "--joint", "/Robot/joints/elbow", "--envelope",
            str(EXAMPLES / "envelopes" / "demo.toml")]  # fmt: skip
    assert main([*argv, "--in-place"]) == 2
    err = capsys.readouterr().err.strip()
    assert "cannot be edited in place" in err and "-o robot_envelope.usda" in err and "--output '" not in err
    assert main([*argv, "-o", str(tmp_path / "robot_envelope.usda")]) == 0  # a layer over the package works
    capsys.readouterr()
    assert _show(tmp_path / "robot_envelope.usda", capsys)["/Robot/joints/elbow"]["envelope"] is not None


def test_malformed_asset_error_has_no_cpp_names(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Report a file USD cannot parse in one line, without ``pxrInternal_...`` text."""
    bad = tmp_path / "bad.usda"
    bad.write_text('#usda 1.0\ndef Xform "R" {\n  def "x" {} }\n', encoding="utf-8")
    apply = ["usd", "apply", str(bad), "--joint", "/R", "--envelope", "x", "-o", str(tmp_path / "o.usda")]
    for argv in (["usd", "show", str(bad)], apply):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert (
            len(err) == 1
            and "bad.usda" in err[0]
            and "pxrInternal" not in err[0]
            and "Traceback" not in err[0]
        )


def test_immutable_output_is_one_line(robot: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                      capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    """Report a target the system refuses to replace (EPERM, an immutable file) in one line; clean up."""
    out = tmp_path / "out.usda"
    out.write_text("old", encoding="utf-8")

    def refuse(src: object, dst: object) -> None:
        raise PermissionError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(os, "replace", refuse)
    argv = [
        "usd",
        "apply",
        str(robot),
        "--joint",
        "/Robot/joints/elbow",
        "--envelope",
        _envelope(robot),
        "-o",
        str(out),
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "out.usda: cannot write: Operation not permitted" in err[0]
    assert out.read_text(encoding="utf-8") == "old" and sorted(p.name for p in tmp_path.iterdir()) == [
        "envelopes", "out.usda", "usd"]  # fmt: skip


def _mount_small_tmpfs(folder: Path) -> bool:
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    result = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=16k", "tmpfs", str(folder)], capture_output=True
    )
    return result.returncode == 0


def test_full_disk_is_one_line(robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Report a full disk in one line and leave no temporary file (a real 16 KiB tmpfs, filled)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if not _mount_small_tmpfs(disk):
        pytest.skip("needs root and mount to make a small full file system")
    try:
        (disk / "fill").write_bytes(b"\0" * 14 * 1024)
        argv = ["usd", "apply", str(robot), "--map", str(robot.with_name("map.toml")), "--flatten", "-o",
                str(disk / "out.usda")]  # fmt: skip
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert (
            err[-1]
            == f"drive-envelope: error: {disk / 'out.usda'}: cannot write: no space left on the device"
        )
        assert sorted(p.name for p in disk.iterdir()) == ["fill"]
    finally:
        subprocess.run(["umount", str(disk)], check=False)


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


def test_broken_sublayer_is_a_warning_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Report a sublayer USD cannot load as one warning line (USD printed its own multi-line text)."""
    top = tmp_path / "top.usda"
    top.write_text(
        '#usda 1.0\n(\n    subLayers = [@./missing.usda@]\n)\ndef Xform "R"\n{\n}\n', encoding="utf-8"
    )
    assert main(["usd", "show", str(top)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("drive-envelope: warning: ") and "missing.usda" in err[0]
    assert "pxrInternal" not in err[0]


def test_real_immutable_output_is_one_line(
    robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Report a real immutable file (chattr +i) in one line and keep it (needs root and chattr)."""
    out = tmp_path / "locked.usda"
    out.write_text("old", encoding="utf-8")
    if os.geteuid() != 0 or shutil.which("chattr") is None:
        pytest.skip("needs root and chattr to make an immutable file")
    if subprocess.run(["chattr", "+i", str(out)], capture_output=True).returncode != 0:
        pytest.skip("this file system does not support immutable files")
    try:
        argv = ["usd", "apply", str(robot), "--joint", "/Robot/joints/elbow", "--envelope", _envelope(robot)]
        assert main([*argv, "-o", str(out), "--force"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "locked.usda: cannot write: Operation not permitted" in err[0]
        assert out.read_text(encoding="utf-8") == "old" and not list(tmp_path.glob(".locked.usda.*"))
    finally:
        subprocess.run(["chattr", "-i", str(out)], check=False)


def test_usd_apply_inline_map_on_the_fr3(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Apply an inline map to Newton's FR3 and read it back (needs usd-core and the shared assets)."""
    pytest.importorskip("pxr")
    asset = Path(__file__).resolve().parents[2] / "shared/data/newton-assets/fr3/fr3_usd/fr3.usda"
    if not asset.is_file():
        pytest.skip("no shared newton-assets")
    body = '[joints]\n"fr3_joint1" = { max_effort = "12 N*m", max_actuator_velocity = "2.6 rad/s" }\n'
    out = tmp_path / "fr3_envelope.usda"
    inline_map = tmp_path / "map.toml"
    inline_map.write_text(body, encoding="utf-8")
    assert main(["usd", "apply", str(asset), "--map", str(inline_map), "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["usd", "show", str(out), "--json"]) == 0
    drives = {d["joint"]: d for d in json.loads(capsys.readouterr().out)["drives"]}
    envelope = drives["/fr3/Physics/fr3_joint1"]["envelope"]
    assert envelope["max_effort"] == 12.0 and envelope["max_actuator_velocity"] == pytest.approx(
        2.6, rel=1e-6
    )

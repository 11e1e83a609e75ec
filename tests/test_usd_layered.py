"""``usd apply`` on Newton's real assets: the layered default, --flatten, D6 refusals, shipped maps.

The assets are read where they are (``../shared/data/newton-assets``, read-only) and every output
goes to the test's temporary folder, so each layer reaches its asset across folders, as a user's
``robot_envelope.usda`` next to a project does.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main

ASSETS = Path(__file__).resolve().parents[2] / "shared" / "data" / "newton-assets"
pytestmark = [
    pytest.mark.usd,
    pytest.mark.skipif(
        not ASSETS.is_dir(), reason="needs ../shared/data/newton-assets (Newton's USD assets)"
    ),
]
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ENVELOPE = str(EXAMPLES / "envelopes" / "demo.toml")
WAIST = "/nv_humanoid/joints/lower_waist"
D6_JOINT = "/test_joint_d6_revolute_actuated/Joints/actuated_d6_revolute_joint"


def _drives(path: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, dict[str, object]]:
    capsys.readouterr()
    assert main(["usd", "show", str(path), "--json"]) == 0
    return {f"{d['joint']}:{d['instance']}": d for d in json.loads(capsys.readouterr().out)["drives"]}


def _prims(path: Path) -> list[str]:
    from pxr import Usd

    stage = Usd.Stage.Open(str(path))
    return [str(p.GetPath()) for p in stage.Traverse(Usd.TraverseInstanceProxies())]


def _map(folder: Path, body: str) -> str:
    path = folder / "map.toml"
    path.write_text(f"[joints]\n{body}", encoding="utf-8")
    return str(path)


def test_anymal_layer_keeps_everything(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Write a layer over the crate-format ANYmal: every prim and drive there, 12 envelopes, no NO."""
    out = tmp_path / "anymal_envelope.usda"
    body = "".join(f'"*_{dof}" = {json.dumps(ENVELOPE)}\n' for dof in ("HAA", "HFE", "KFE"))
    assert (
        main(["usd", "apply", str(ASSETS / "anymal_c.usd"), "--map", _map(tmp_path, body), "-o", str(out)])
        == 0
    )
    err = capsys.readouterr().err
    assert "not an articulation joint" not in err and "12 of 12 joint drives" in err
    assert _prims(out) == _prims(ASSETS / "anymal_c.usd")  # nothing lost: 288 prims, instances included
    drives = _drives(out, capsys)
    assert len(drives) == 12 and all(d["articulation"] and d["envelope"] for d in drives.values())
    assert out.stat().st_size < 8000  # overrides only (the asset is a 2.5 MB crate file)


def test_ant_clones_layer_and_flat_copy(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Reach all 64 referenced ants from a layer, and write a flat copy that stands alone."""
    body = f'"*_leg" = {json.dumps(ENVELOPE)}\n'
    layer, flat = tmp_path / "layer.usda", tmp_path / "flat" / "ants.usdc"
    flat.parent.mkdir()
    for extra, out in (([], layer), (["--flatten"], flat)):
        argv = ["usd", "apply", str(ASSETS / "t_ant_multi.usda"), "--map", _map(tmp_path, body), *extra]
        assert main([*argv, "-o", str(out)]) == 0
    moved = tmp_path / "elsewhere"
    shutil.copytree(flat.parent, moved)
    for result in (layer, moved / "ants.usdc"):
        drives = _drives(result, capsys)
        legs = [d for key, d in drives.items() if "_leg:" in key]
        assert len(drives) == 512 and len(legs) == 256 and all(d["envelope"] for d in legs)


def test_fr3_payload_and_shipped_map(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Apply the shipped franka-fr3 map by name to the FR3 conversion (joints in a payload's sublayer)."""
    out = tmp_path / "fr3_envelope.usda"
    assert main(["usd", "apply", str(ASSETS / "fr3" / "fr3_usd" / "fr3.usda"), "--map", "franka-fr3",
                 "-o", str(out)]) == 0  # fmt: skip
    drives = _drives(out, capsys)
    assert len(drives) == 7
    # Franka's published limits (the shipped map's catalog entries): 87 N*m on joints 1-4, 12 on 5-7
    assert drives["/fr3/Physics/fr3_joint2:angular"]["max_effort"] == pytest.approx(87.0)
    assert drives["/fr3/Physics/fr3_joint6:angular"]["max_effort"] == pytest.approx(12.0)


@pytest.mark.parametrize(
    ("asset", "joint", "instance", "message"),
    [
        ("humanoid.usda", WAIST, "rotZ", "locks rotZ (PhysicsLimitAPI:rotZ low 1 > high -1)"),
        ("humanoid.usda", WAIST, "transX", "never on transX"),
        ("t_test_joint_d6_revolute_actuated.usda", D6_JOINT, "rotX", "locks rotX"),
    ],
)
def test_d6_axes_physx_drops_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], asset: str, joint: str, instance: str, message: str
) -> None:
    """Refuse the real D6 joints' locked and translational axes in one line; write nothing."""
    out = tmp_path / "out.usda"
    argv = [
        "usd",
        "apply",
        str(ASSETS / asset),
        "--joint",
        joint,
        "--envelope",
        ENVELOPE,
        "--instance",
        instance,
    ]
    assert main([*argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not out.exists()


def test_d6_free_axis_is_written(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Write the D6 test joint's one free axis (rotY); warn that it is not in an articulation."""
    out = tmp_path / "out.usda"
    joint = D6_JOINT
    argv = ["usd", "apply", str(ASSETS / "t_test_joint_d6_revolute_actuated.usda"), "--joint", joint,
            "--envelope", ENVELOPE, "--instance", "rotY", "-o", str(out)]  # fmt: skip
    assert main(argv) == 0
    assert "does not make it an articulation joint" in capsys.readouterr().err
    assert _drives(out, capsys)[f"{joint}:rotY"]["envelope"] is not None

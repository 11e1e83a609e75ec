"""Joints inside instanced prims: authored on the prototype's source, or a one-line message.

Layouts: a robot cloned by internal references to a class prim (``references = </RobotProto>``,
instanceable), and clones that reference another file, as Newton's ``t_ant_multi.usda`` references
``ant.usda`` (made instanceable by a layer over it, as a scene would).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from drive_envelope import InputError, PerformanceEnvelope

pytestmark = pytest.mark.usd

ASSETS = Path(__file__).resolve().parents[2] / "shared" / "data" / "newton-assets"
ENV = PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=20.0)


def _robot(stage, path: str) -> None:
    from pxr import Sdf, UsdGeom, UsdPhysics

    UsdPhysics.ArticulationRootAPI.Apply(stage.GetPrimAtPath(path))
    for body in ("base", "link"):
        UsdPhysics.RigidBodyAPI.Apply(UsdGeom.Xform.Define(stage, f"{path}/{body}").GetPrim())
    joint = UsdPhysics.RevoluteJoint.Define(stage, f"{path}/hinge")
    joint.CreateBody0Rel().SetTargets([Sdf.Path(f"{path}/base")])
    joint.CreateBody1Rel().SetTargets([Sdf.Path(f"{path}/link")])


@pytest.fixture
def scene(tmp_path: Path) -> Path:
    """scene.usda: two clones of an internal class prototype and two instances of robot.usda."""
    import physx_usd_schemas  # noqa: F401
    from pxr import Usd, UsdGeom

    robot = Usd.Stage.CreateNew(str(tmp_path / "robot.usda"))
    UsdGeom.SetStageMetersPerUnit(robot, 1.0)
    robot.SetDefaultPrim(UsdGeom.Xform.Define(robot, "/Robot").GetPrim())
    _robot(robot, "/Robot")
    robot.Save()
    stage = Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.CreateClassPrim("/RobotProto")
    _robot(stage, "/RobotProto")
    for i in range(2):
        clone = stage.DefinePrim(f"/World/clone_{i}")
        clone.GetReferences().AddInternalReference("/RobotProto")
        clone.SetInstanceable(True)
        other = stage.DefinePrim(f"/World/file_{i}")
        other.GetReferences().AddReference("./robot.usda")
        other.SetInstanceable(True)
    stage.Save()
    return tmp_path / "scene.usda"


def test_internal_prototype_gets_the_override(scene: Path) -> None:
    """Author a clone's joint on the class prototype (a non-instanced path): every clone reads it."""
    from drive_envelope.usd import EnvelopeAuthoringWarning, list_drives, open_overlay, write_envelope

    stage = open_overlay(scene)
    with pytest.warns(
        EnvelopeAuthoringWarning, match=r"authored on its prototype's source '/RobotProto/hinge'"
    ):
        write_envelope(stage, "/World/clone_0/hinge", ENV)
    text = stage.GetRootLayer().ExportToString()
    assert 'over "RobotProto"' in text and "clone_0" not in text
    clones = {r.joint_path: r for r in list_drives(stage) if "clone" in r.joint_path}
    assert set(clones) == {"/World/clone_0/hinge", "/World/clone_1/hinge"}
    assert all(
        r.envelope is not None and r.envelope.max_effort == pytest.approx(12.0) for r in clones.values()
    )
    assert not any(r.in_articulation for r in clones.values())  # PhysX does not simulate instanced bodies


def test_external_prototype_names_the_file_and_prim(scene: Path) -> None:
    """Refuse in one line, naming robot.usda and /Robot/hinge (apply used to die with a traceback)."""
    from drive_envelope.usd import open_overlay, write_envelope

    stage = open_overlay(scene)
    with pytest.raises(InputError) as info:
        write_envelope(stage, "/World/file_1/hinge", ENV)
    message = str(info.value)
    assert "'/Robot/hinge'" in message and str(scene.with_name("robot.usda")) in message
    assert "instanceable = false on '/World/file_1'" in message and "\n" not in message


def test_map_matches_instance_proxies_and_authors_once(
    scene: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Match clone joints by their instance-proxy paths (the map used to match nothing) and write once."""
    from drive_envelope import save_envelope
    from drive_envelope._src.cli.main import main

    save_envelope(ENV, tmp_path / "env.toml")
    (tmp_path / "map.toml").write_text('[joints]\n"/World/clone_*/hinge" = "env.toml"\n', encoding="utf-8")
    out = tmp_path / "scene_env.usda"
    argv = ["usd", "apply", str(scene), "--map", str(tmp_path / "map.toml"), "-o", str(out)]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert captured.out.count("[authored on /RobotProto/hinge]") == 1  # one edit for the shared prototype
    assert captured.err.count("prototype's source") == 1
    assert main(["usd", "show", str(out), "--json"]) == 0
    drives = {d["joint"]: d for d in json.loads(capsys.readouterr().out)["drives"]}
    assert drives["/World/clone_1/hinge"]["envelope"]["max_effort"] == pytest.approx(12.0)
    assert "/World/file_0/hinge" not in drives  # the file instances were not matched: no drive there


def test_shared_prototype_cannot_take_two_envelopes(scene: Path) -> None:
    """Refuse different envelopes for two clones of one prototype: they are one joint in the file."""
    from drive_envelope._src.adapters.usd.apply import Assignment, apply_envelopes
    from drive_envelope.usd import open_overlay

    other = PerformanceEnvelope(max_effort=3.0)
    where = "map.toml: key 'joints.x'"
    assignments = [
        Assignment(joint_path="/World/clone_0/hinge", envelope=ENV),
        Assignment(joint_path="/World/clone_1/hinge", envelope=other, where=where),
    ]
    with pytest.raises(InputError, match=r"map\.toml: key 'joints\.x': .*one joint of a shared prototype"):
        apply_envelopes(open_overlay(scene), assignments)


@pytest.mark.skipif(not ASSETS.is_dir(), reason="needs ../shared/data/newton-assets (Newton's USD assets)")
def test_instanced_ant_clones_point_to_ant_usda(tmp_path: Path) -> None:
    """Name ant.usda's /ant/joints/... for Newton's 64 ant clones once a scene makes them instanceable."""
    from pxr import Sdf, Usd

    from drive_envelope.usd import open_overlay, write_envelope

    layer = Sdf.Layer.CreateNew(str(tmp_path / "instanced.usda"))
    layer.subLayerPaths.append(str(ASSETS / "t_ant_multi.usda"))
    stage = Usd.Stage.Open(layer)
    for i in range(64):
        stage.OverridePrim(f"/World/envs/env_{i}/Robot").SetInstanceable(True)
    layer.Save()
    overlay = open_overlay(tmp_path / "instanced.usda")
    with pytest.raises(
        InputError, match=r"'/ant/joints/front_left_leg' in .*ant\.usda: no opinion in this stage"
    ):
        write_envelope(overlay, "/World/envs/env_7/Robot/joints/front_left_leg", ENV)

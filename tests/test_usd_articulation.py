"""Articulation membership decided the way PhysX parses it, on every layout real assets use.

The layouts are the ones of Newton's assets: the root API on an Xform above the robot (``ant.usda``,
``cartpole.usda``), on a rigid body (``anymal_c.usd``, an Isaac Sim URDF import; ``humanoid.usda``),
on a world-anchoring fixed joint, plus each case PhysX's rules single out (a revolute joint to the
world, loops, excluded and disabled joints, kinematic and instanced bodies, nested roots). The
expectations are derived by hand from omni.physx's source (see the articulation module) and checked
against real PhysX: ``test_layouts_match_real_physx`` loads every layout in ovphysx and compares
the joints it reports as articulation DOFs.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

pytestmark = pytest.mark.usd

ASSETS = Path(__file__).resolve().parents[2] / "shared" / "data" / "newton-assets"
R, P, F, D = "revolute", "prismatic", "fixed", "distance"

# name: (root API prim, joints as (name, type, body0, body1, options)); bodies a, b, c, free under /R
LAYOUTS: dict[str, tuple[str, list[tuple[str, str, str, str, str]]]] = {
    "xform": ("/R", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j2", R, "b", "c", ""),
                     ("loop", R, "c", "a", "excluded"), ("off", R, "a", "c", "disabled"),
                     ("spare", P, "free", "", "")]),
    "body": ("/R/b", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j2", R, "b", "c", "")]),
    "fixed_joint": ("/R/root", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j2", P, "b", "c", "")]),
    "inner_joint": ("/R/j2", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j2", R, "b", "c", "")]),
    "no_root": ("", [("root", F, "", "a", ""), ("j1", R, "a", "b", "")]),
    "kinematic_root": ("/R/a", [("j1", R, "a", "b", ""), ("j2", R, "b", "c", "")]),
    "disabled_articulation": ("/R", [("root", F, "", "a", ""), ("j1", R, "a", "b", "")]),
    "nested": ("/R", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j2", R, "b", "c", "")]),
    "pendulum": ("/R", [("hinge", R, "", "a", ""), ("j1", R, "a", "b", "")]),
    "pendulum_body_root": ("/R/a", [("hinge", R, "", "a", ""), ("j1", R, "a", "b", "")]),
    "loop": ("/R", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j2", R, "b", "c", ""),
                    ("j3", R, "c", "a", "")]),
    "world_mid": ("/R", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j2", R, "b", "c", ""),
                         ("w", R, "c", "", "")]),
    "same_pair": ("/R", [("root", F, "", "a", ""), ("j1", R, "a", "b", ""), ("j1b", P, "a", "b", "")]),
    "floating": ("/R", [("j1", R, "a", "b", ""), ("j2", R, "b", "c", "")]),
    "floating_loop": ("/R", [("j1", R, "a", "b", ""), ("j2", R, "b", "c", ""), ("j3", R, "c", "a", "")]),
    "two_world": ("/R", [("w1", R, "", "a", ""), ("j1", R, "a", "b", ""), ("w2", P, "c", "", ""),
                         ("j2", R, "b", "c", "")]),
    "distance": ("/R", [("root", F, "", "a", ""), ("j1", D, "a", "b", ""), ("j2", R, "a", "c", "")]),
    "instanced": ("/R", [("root", F, "", "a", ""), ("j1", R, "a", "b", "")]),
}  # fmt: skip
EXPECTED = {
    # the fixed world joint anchors the base (no DOF); never the excluded or disabled joint; the free
    # body's prismatic world joint anchors a second, fixed-base articulation: no DOF either
    "xform": {"j1", "j2"},
    "body": {"j1", "j2"},  # floating from b; the world joint on a is a plain joint to a link
    "fixed_joint": {"j1", "j2"},
    "inner_joint": set(),  # a root API on a joint between two bodies starts nothing
    "no_root": set(),
    "kinematic_root": set(),  # "ArticulationRootAPI definition on a kinematic rigid body"
    "disabled_articulation": set(),  # physxArticulation:articulationEnabled = false
    "nested": {"j1", "j2"},  # the inner root is ignored
    "pendulum": {"j1"},  # the revolute world joint fixes the base: it is no DOF
    "pendulum_body_root": {"j1"},  # floating from a: the world hinge is a plain joint
    "loop": {"j1", "j2"},  # "closed articulation ... will be now excluded"
    "world_mid": {"j1", "j2"},  # a second world joint, from a non-root link, is a plain joint
    "same_pair": {"j1"},  # the second joint between the same bodies is left out
    "floating": {"j1", "j2"},
    "floating_loop": {"j1", "j2"},
    "two_world": {"j1", "j2"},  # w1 (the heavier, first) anchors the base; w2 joins c to the world
    "distance": {"j2"},  # a distance joint cannot be in an articulation
    "instanced": set(),  # the clones' bodies are inside instances: PhysX does not simulate them
}


def _layout(name: str, *, masses: bool = False):
    """The stage of one layout (with masses and a scene when PhysX is to load it)."""
    import physx_usd_schemas  # noqa: F401
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics

    root_api, joints = LAYOUTS[name]
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.Scene.Define(stage, "/physicsScene")
    robot = (
        stage.CreateClassPrim("/R") if name == "instanced" else UsdGeom.Xform.Define(stage, "/R").GetPrim()
    )
    for body in ("a", "b", "c", "free"):
        prim = UsdGeom.Xform.Define(stage, f"/R/{body}").GetPrim()
        api = UsdPhysics.RigidBodyAPI.Apply(prim)
        if name == "kinematic_root" and body == "a":
            api.CreateKinematicEnabledAttr(True)
        if masses:
            mass = UsdPhysics.MassAPI.Apply(prim)
            mass.CreateMassAttr(1.0)
            mass.CreateDiagonalInertiaAttr(Gf.Vec3f(1.0, 1.0, 1.0))
    schemas = {R: UsdPhysics.RevoluteJoint, P: UsdPhysics.PrismaticJoint, F: UsdPhysics.FixedJoint,
               D: UsdPhysics.DistanceJoint}  # fmt: skip
    for joint_name, kind, body0, body1, option in joints:
        joint = schemas[kind].Define(stage, f"/R/{joint_name}")
        for rel, body in ((joint.CreateBody0Rel(), body0), (joint.CreateBody1Rel(), body1)):
            if body:
                rel.SetTargets([Sdf.Path(f"/R/{body}")])
        if option == "excluded":
            joint.CreateExcludeFromArticulationAttr(True)
        if option == "disabled":
            joint.CreateJointEnabledAttr(False)
    if root_api:
        UsdPhysics.ArticulationRootAPI.Apply(stage.GetPrimAtPath(root_api))
    if name == "nested":
        UsdPhysics.ArticulationRootAPI.Apply(stage.GetPrimAtPath("/R/b"))
    if name == "disabled_articulation":
        robot.ApplyAPI("PhysxArticulationAPI")
        robot.CreateAttribute("physxArticulation:articulationEnabled", Sdf.ValueTypeNames.Bool).Set(False)
    if name == "instanced":
        for i in range(2):
            clone = stage.DefinePrim(f"/World/env_{i}")
            clone.GetReferences().AddInternalReference("/R")
            clone.SetInstanceable(True)
    return stage


def _dofs(stage, found) -> set[str]:
    """Joint names of ``found`` that carry a DOF (fixed joints have none)."""
    from pxr import UsdPhysics

    return {p.rpartition("/")[2] for p in found if not stage.GetPrimAtPath(p).IsA(UsdPhysics.FixedJoint)}


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_membership_on_each_layout(name: str) -> None:
    """Find the articulation joints of each layout as PhysX's rules say."""
    from drive_envelope._src.adapters.usd.articulation import articulated_joints

    stage = _layout(name)
    assert _dofs(stage, articulated_joints(stage)) == EXPECTED[name]


@pytest.mark.physx
def test_layouts_match_real_physx(tmp_path: Path) -> None:
    """Load every layout in real PhysX (ovphysx): its articulation DOFs are exactly the joints found."""
    from drive_envelope._src.adapters.physx.runner import inspect_drives
    from drive_envelope._src.adapters.usd.articulation import articulated_joints

    differ = {}
    for name in sorted(LAYOUTS):
        stage = _layout(name, masses=True)
        path = tmp_path / f"{name}.usda"
        stage.GetRootLayer().Export(str(path))
        loaded = {key.partition("[")[0].rpartition("/")[2] for key in inspect_drives(path)}
        ours = _dofs(stage, articulated_joints(stage))
        if loaded != ours or ours != EXPECTED[name]:
            differ[name] = (sorted(loaded), sorted(ours))
    assert not differ, differ


def _parser_dofs(stage) -> set[str] | None:
    """OpenUSD's UsdPhysics parser: the non-fixed joints of its articulations (None without one)."""
    from pxr import Sdf, UsdPhysics

    parse = getattr(UsdPhysics, "UsdPhysicsLoadStageFromPrimRange", None)
    if parse is None:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = parse(stage, [Sdf.Path.absoluteRootPath])
    found = set()
    for kind, (_, descs) in result.items():
        if kind == UsdPhysics.ObjectType.Articulation:
            for desc in descs:
                found.update(str(path) for path in desc.articulatedJoints)
    return {
        path
        for path in found
        if not stage.GetPrimAtPath(path).IsA(UsdPhysics.FixedJoint)
        and not UsdPhysics.Joint(stage.GetPrimAtPath(path)).GetExcludeFromArticulationAttr().Get()
    }


REAL = {
    # asset: articulation joints with a DOF
    "anymal_c.usd": 12,  # root API on the base body; all 12 revolute joints (the old rule found 4)
    "humanoid.usda": 12,  # root API on the torso body: 5 revolute + 7 D6 (3 fixed joints carry no DOF)
    "cartpole.usda": 3,  # root API on the Xform, a fixed rootJoint to the world
    "ant.usda": 8,
    "t_revolute_articulation.usda": 1,
    "t_test_joint_d6_revolute_actuated.usda": 0,  # no articulation root at all
    "t_ant_multi.usda": 512,  # 64 referenced (not instanced) ants
}


@pytest.mark.skipif(not ASSETS.is_dir(), reason="needs ../shared/data/newton-assets (Newton's USD assets)")
@pytest.mark.parametrize("name", sorted(REAL))
def test_real_assets(name: str) -> None:
    """Count the articulation joints of Newton's assets; on these trees OpenUSD's parser agrees."""
    from pxr import Usd, UsdPhysics

    from drive_envelope._src.adapters.usd.articulation import articulated_joints

    stage = Usd.Stage.Open(str(ASSETS / name))
    found = {p for p in articulated_joints(stage) if not stage.GetPrimAtPath(p).IsA(UsdPhysics.FixedJoint)}
    assert len(found) == REAL[name]
    expected = _parser_dofs(stage)
    if expected is not None:
        assert found == expected


@pytest.mark.skipif(not ASSETS.is_dir(), reason="needs ../shared/data/newton-assets (Newton's USD assets)")
def test_anymal_drives_are_all_articulated_and_show_says_yes(capsys: pytest.CaptureFixture[str]) -> None:
    """Mark all 12 ANYmal drives as articulation joints (the old ancestor-only rule said NO for 8)."""
    from drive_envelope._src.cli.main import main
    from drive_envelope.usd import list_drives, open_stage

    records = list_drives(open_stage(ASSETS / "anymal_c.usd"))
    assert len(records) == 12 and all(r.in_articulation for r in records)
    assert main(["usd", "show", str(ASSETS / "anymal_c.usd")]) == 0
    assert " NO " not in capsys.readouterr().out


@pytest.mark.skipif(not ASSETS.is_dir(), reason="needs ../shared/data/newton-assets (Newton's USD assets)")
def test_no_articulation_warning_on_humanoid_d6_joint() -> None:
    """Author a D6 axis of the humanoid (root API on the torso body) without the false warning."""
    from drive_envelope import PerformanceEnvelope
    from drive_envelope.usd import EnvelopeAuthoringWarning, open_overlay, write_envelope

    stage = open_overlay(ASSETS / "humanoid.usda")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        write_envelope(stage, "/nv_humanoid/joints/lower_waist", PerformanceEnvelope(max_effort=5.0), "rotX")
    messages = [str(w.message) for w in caught if issubclass(w.category, EnvelopeAuthoringWarning)]
    assert not any("articulation" in m for m in messages), messages


def test_warning_names_why_physx_drops_the_envelope() -> None:
    """Warn on the pendulum's world hinge: it anchors the articulation and carries no DOF."""
    from drive_envelope import PerformanceEnvelope
    from drive_envelope.usd import EnvelopeAuthoringWarning, write_envelope

    stage = _layout("pendulum")
    with pytest.warns(EnvelopeAuthoringWarning, match="does not make it an articulation joint"):
        write_envelope(stage, "/R/hinge", PerformanceEnvelope(max_effort=5.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_envelope(stage, "/R/j1", PerformanceEnvelope(max_effort=5.0))


@pytest.mark.skipif(not ASSETS.is_dir(), reason="needs ../shared/data/newton-assets (Newton's USD assets)")
@pytest.mark.parametrize("root", ["/cartPole/rootJoint", "/cartPole/rail"])
def test_cartpole_with_its_root_on_the_root_joint_or_the_rail(root: str) -> None:
    """Keep the cartpole's 3 DOFs articulated with the root API moved to its fixed rootJoint or a body."""
    from pxr import UsdPhysics

    from drive_envelope._src.adapters.usd.articulation import articulated_joints
    from drive_envelope.usd import open_overlay

    stage = open_overlay(ASSETS / "cartpole.usda")
    stage.GetPrimAtPath("/cartPole").RemoveAPI(UsdPhysics.ArticulationRootAPI)
    UsdPhysics.ArticulationRootAPI.Apply(stage.GetPrimAtPath(root))
    found = articulated_joints(stage)
    assert found >= {"/cartPole/railCartJoint", "/cartPole/cartPoleJoint", "/cartPole/polePoleJoint"}

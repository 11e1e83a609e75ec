"""PhysX itself reads back what ``drive_envelope.usd`` writes (real PhysX through ovphysx 0.7, CPU).

maxForce, the drive gains and the three envelope values are read from PhysX's joint properties
(ovphysx 0.7's ``ARTICULATION_JOINT`` attributes ``jointMaxForce``, ``jointStiffness``,
``jointMaxActuatorVelocity``, ``jointVelocityDependentResistance``, ``jointSpeedEffortGradient``:
live PhysX state, angular values folded back to degrees as USD stores them). The envelope is also
read from PhysX's behaviour against closed forms (SEMANTICS.md): the velocity settles exactly on
maxActuatorVelocity, the first step from rest exerts ``maxEffort / (1 + r*R*dt)``, and against a
constant load ``L`` the speed settles on ``maxActuatorVelocity - speedEffortGradient*L``. They run
in a centimetre-gram stage, so the degree conversion and the stage-unit scaling are both exercised
(the parity tests use SI stages).
"""

from __future__ import annotations

import math
import shutil
import warnings
from pathlib import Path

import pytest

from drive_envelope import PerformanceEnvelope
from drive_envelope._src.scenario.spec import DriveSpec, JointSpec, LoadSpec, Scenario, SimulationSpec

pytestmark = [pytest.mark.physx, pytest.mark.usd]

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
DT = 1.0 / 240.0


def _scenario(joint: str, envelope: PerformanceEnvelope, inertia: float, load: float = 0.0) -> Scenario:
    return Scenario(
        name=joint,
        joint=JointSpec(type=joint, inertia=inertia),  # type: ignore[arg-type]
        drive=DriveSpec(damping=1.0e3, target_velocity=100.0, max_effort=envelope.max_effort),
        envelope=envelope,
        load=LoadSpec(external_effort=load),
        simulation=SimulationSpec(
            dt=DT, duration=0.25, solver="pgs", position_iterations=4, velocity_iterations=1
        ),
    )


REVOLUTE = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=6.0, velocity_dependent_resistance=0.4)
GRADIENT = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=6.0, speed_effort_gradient=0.1)
PRISMATIC = PerformanceEnvelope(
    joint="prismatic", max_effort=80.0, max_actuator_velocity=0.8, velocity_dependent_resistance=20.0
)
CASES = [
    _scenario("revolute", REVOLUTE, 0.05),
    _scenario("revolute", GRADIENT, 0.05, load=-2.0),
    _scenario("prismatic", PRISMATIC, 2.0),
]


@pytest.fixture(scope="module")
def runs() -> list[object]:
    """The cases in a centimetre-gram stage (the parity tests cover SI stages)."""
    from drive_envelope._src.adapters.physx.stand import simulate_many
    from drive_envelope.usd import StageUnits

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate_many(CASES, units=StageUnits(meters_per_unit=0.01, kilograms_per_unit=0.001))  # type: ignore[return-value]


def test_velocity_settles_on_max_actuator_velocity(runs: list[object]) -> None:
    """Read maxActuatorVelocity (degrees on angular drives, stage units on linear ones)."""
    assert runs[0].velocity[-1] == pytest.approx(6.0, rel=2e-6)  # type: ignore[attr-defined]
    assert runs[2].velocity[-1] == pytest.approx(0.8, rel=2e-6)  # type: ignore[attr-defined]


def test_first_step_effort_reads_resistance(runs: list[object]) -> None:
    """Read velocityDependentResistance from the first step's effort maxEffort/(1 + r*R*dt)."""
    assert runs[0].effort[1] == pytest.approx(10.0 / (1.0 + 0.4 * DT / 0.05), rel=2e-6)  # type: ignore[attr-defined]
    assert runs[2].effort[1] == pytest.approx(80.0 / (1.0 + 20.0 * DT / 2.0), rel=2e-6)  # type: ignore[attr-defined]


def test_loaded_speed_reads_speed_effort_gradient(runs: list[object]) -> None:
    """Read speedEffortGradient from the loaded steady speed v_max - G*L = 6 - 0.1*2."""
    trajectory = runs[1]
    assert trajectory.velocity[-1] == pytest.approx(5.8, rel=2e-6)  # type: ignore[attr-defined]
    assert trajectory.effort[-1] == pytest.approx(2.0, rel=1e-4)  # type: ignore[attr-defined]


@pytest.fixture(scope="module")
def robot_dofs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, float]]:
    """What PhysX loaded for the example robot after ``drive-envelope usd apply --map``."""
    from drive_envelope._src.adapters.physx.runner import inspect_drives
    from drive_envelope._src.cli.main import main

    folder = tmp_path_factory.mktemp("robot")
    (folder / "usd").mkdir()
    (folder / "envelopes").mkdir()
    for name in ("robot.usda", "map.toml", "linear_actuator.toml"):
        shutil.copy(EXAMPLES / "usd" / name, folder / "usd" / name)
    shutil.copy(EXAMPLES / "envelopes" / "demo.toml", folder / "envelopes" / "demo.toml")
    robot, out = folder / "usd" / "robot.usda", folder / "robot_env.usda"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        argv = ["usd", "apply", str(robot), "--map", str(robot.with_name("map.toml")), "--output", str(out)]
        assert main(argv) == 0
    return inspect_drives(out)


def test_physx_loads_max_force_and_gains_of_applied_robot(robot_dofs: dict[str, dict[str, float]]) -> None:
    """Find maxForce in stage units and the per-degree gains as authored in PhysX's joint properties."""
    shoulder, slide = robot_dofs["/Robot/joints/shoulder"], robot_dofs["/Robot/joints/slide"]
    # centimetre stage: torques in kg*cm^2/s^2 (1e4 per N*m), forces in kg*cm/s^2 (100 per N)
    assert shoulder["max_force"] / 1e4 == pytest.approx(12.05568, rel=1e-6)
    assert slide["max_force"] / 1e2 == pytest.approx(120.0, rel=1e-6)
    # ovphysx 0.7 reports angular gains per degree, as USD stores them (the example writes 2)
    assert shoulder["stiffness"] == pytest.approx(2.0, rel=1e-6)


def test_physx_loads_envelope_of_applied_robot(robot_dofs: dict[str, dict[str, float]]) -> None:
    """Read the three envelope values back from PhysX's joint properties and convert them to SI."""
    deg = math.pi / 180.0
    shoulder, slide = robot_dofs["/Robot/joints/shoulder"], robot_dofs["/Robot/joints/slide"]
    # demo.toml: 360 rpm = 37.699 rad/s, G = 0.570248 (rad/s)/(N*m) (see `drive-envelope usd show`);
    # angular values come back per degree, torques in kg*cm^2/s^2 (1e4 per N*m)
    assert shoulder["max_actuator_velocity"] * deg == pytest.approx(12.0 * math.pi, rel=1e-6)
    assert shoulder["speed_effort_gradient"] * deg * 1e4 == pytest.approx(0.570248, rel=1e-5)
    assert shoulder["velocity_dependent_resistance"] == 0.0
    # linear_actuator.toml: 0.25 m/s = 25 cm/s; 40 N*s/m = 40 kg/s, the same number in kg-cm-s
    assert slide["max_actuator_velocity"] == pytest.approx(25.0, rel=1e-6)
    assert slide["velocity_dependent_resistance"] == pytest.approx(40.0, rel=1e-6)
    assert slide["speed_effort_gradient"] == 0.0


# -- real assets: PhysX reads what the layered output of `usd apply` authors -------------------------

ASSETS = Path(__file__).resolve().parents[2] / "shared" / "data" / "newton-assets"
needs_assets = pytest.mark.skipif(not ASSETS.is_dir(), reason="needs ../shared/data/newton-assets")
AK80 = PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=12.0 * math.pi, speed_effort_gradient=0.5)
SLIDE = PerformanceEnvelope(joint="prismatic", max_effort=100.0, max_actuator_velocity=0.5,
                            velocity_dependent_resistance=40.0)  # fmt: skip


def _apply(asset: Path, folder: Path, body: str, *, physics_only: bool = False) -> Path:
    """``usd apply ASSET --map`` into ``folder`` (envelopes AK80 and SLIDE); returns the layer written."""
    from drive_envelope import save_envelope
    from drive_envelope._src.cli.main import main

    save_envelope(AK80, folder / "ak80.toml")
    save_envelope(SLIDE, folder / "slide.toml")
    (folder / "map.toml").write_text("[joints]\n" + body, encoding="utf-8")
    out = folder / f"{asset.stem}_envelope.usda"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["usd", "apply", str(asset), "--map", str(folder / "map.toml"), "-o", str(out)]) == 0
    if not physics_only:
        return out
    # anymal_c.usd's visual materials name OmniPBR.mdl, which ovstage spends about a minute looking
    # for; a layer that deactivates the visuals keeps PhysX's load to a second (no physics in them)
    from pxr import Sdf, Usd

    check = Sdf.Layer.CreateNew(str(folder / "physics_only.usda"))
    check.subLayerPaths.append(f"./{out.name}")
    check.pseudoRoot.SetInfo("metersPerUnit", 1.0)
    stage, written = Usd.Stage.Open(check), Usd.Stage.Open(str(out))
    for prim in written.Traverse():
        if prim.GetName() == "visuals":
            stage.OverridePrim(prim.GetPath()).SetActive(False)
    check.Save()
    return folder / "physics_only.usda"


def _assert_ak80(dof: dict[str, float]) -> None:
    """The AK80 envelope as PhysX folds it back to USD's units (metre stage): per degree."""
    deg = math.pi / 180.0
    assert dof["max_force"] == pytest.approx(12.0, rel=1e-6)
    assert dof["max_actuator_velocity"] * deg == pytest.approx(12.0 * math.pi, rel=1e-6)
    assert dof["speed_effort_gradient"] * deg == pytest.approx(0.5, rel=1e-6)


@needs_assets
def test_physx_reads_the_layer_over_anymal(tmp_path: Path) -> None:
    """Load all 12 ANYmal DOFs with the envelope (8 of them were reported outside the articulation)."""
    from drive_envelope._src.adapters.physx.runner import inspect_drives

    layer = _apply(ASSETS / "anymal_c.usd", tmp_path, '"*_HAA" = "ak80.toml"\n"*_HFE" = "ak80.toml"\n'
                   '"*_KFE" = "ak80.toml"\n', physics_only=True)  # fmt: skip
    dofs = inspect_drives(layer)
    assert len(dofs) == 12
    for dof in dofs.values():
        _assert_ak80(dof)


@needs_assets
def test_physx_reads_the_layer_over_humanoid_d6_axis(tmp_path: Path) -> None:
    """Give one rotational axis of a D6 joint the envelope; PhysX leaves the joint's other axes alone."""
    from drive_envelope._src.adapters.physx.runner import inspect_drives

    entry = '"/nv_humanoid/joints/lower_waist" = { envelope = "ak80.toml", instance = "rotX" }\n'
    layer = _apply(ASSETS / "humanoid.usda", tmp_path, entry)
    dofs = {k: v for k, v in inspect_drives(layer).items() if k.startswith("/nv_humanoid/joints/lower_waist")}
    enveloped = [v for v in dofs.values() if v["max_force"] == pytest.approx(12.0)]
    assert len(dofs) == 2 and len(enveloped) == 1
    _assert_ak80(enveloped[0])


@needs_assets
def test_physx_reads_the_layer_over_cartpole_and_fr3(tmp_path: Path) -> None:
    """Read a prismatic envelope (cartpole, no degrees) and FR3's joints through its payload and sublayers."""
    from drive_envelope._src.adapters.physx.runner import inspect_drives

    (tmp_path / "cartpole").mkdir()
    (tmp_path / "fr3").mkdir()
    cart = inspect_drives(_apply(ASSETS / "cartpole.usda", tmp_path / "cartpole",
                                 '"railCartJoint" = "slide.toml"\n'))["/cartPole/railCartJoint"]  # fmt: skip
    assert cart["max_force"] == pytest.approx(100.0) and cart["max_actuator_velocity"] == pytest.approx(0.5)
    assert cart["velocity_dependent_resistance"] == pytest.approx(40.0)
    fr3 = inspect_drives(
        _apply(ASSETS / "fr3" / "fr3_usd" / "fr3.usda", tmp_path / "fr3", '"fr3_joint*" = "ak80.toml"\n')
    )
    assert len(fr3) == 7
    for dof in fr3.values():
        _assert_ak80(dof)


@needs_assets
def test_physx_reads_the_layer_over_64_referenced_ants(tmp_path: Path) -> None:
    """Reach all 512 joints of 64 clones that reference ant.usda (overrides on each clone's path)."""
    from drive_envelope._src.adapters.physx.runner import inspect_drives

    dofs = inspect_drives(_apply(ASSETS / "t_ant_multi.usda", tmp_path, '"*_leg" = "ak80.toml"\n'))
    legs = {k: v for k, v in dofs.items() if k.endswith("_leg")}
    assert len(dofs) == 512 and len(legs) == 256
    for dof in legs.values():
        _assert_ak80(dof)
    assert all(v["max_force"] != pytest.approx(12.0) for k, v in dofs.items() if k.endswith("_foot"))


def test_physx_reads_an_internal_prototype_override_on_every_clone(tmp_path: Path) -> None:
    """Simulate nothing inside instances, and every clone's envelope once they are made non-instanceable."""
    from pxr import Sdf, Usd, UsdGeom, UsdPhysics

    from drive_envelope import save_envelope
    from drive_envelope._src.adapters.physx.runner import inspect_drives
    from drive_envelope._src.cli.main import main

    stage = Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.Scene.Define(stage, "/physicsScene")
    stage.CreateClassPrim("/Proto")
    UsdPhysics.ArticulationRootAPI.Apply(stage.GetPrimAtPath("/Proto"))
    for body in ("base", "link"):
        prim = UsdGeom.Xform.Define(stage, f"/Proto/{body}").GetPrim()
        UsdPhysics.RigidBodyAPI.Apply(prim)
        UsdPhysics.MassAPI.Apply(prim).CreateMassAttr(1.0)
    root = UsdPhysics.FixedJoint.Define(stage, "/Proto/root")
    root.CreateBody1Rel().SetTargets([Sdf.Path("/Proto/base")])
    hinge = UsdPhysics.RevoluteJoint.Define(stage, "/Proto/hinge")
    hinge.CreateBody0Rel().SetTargets([Sdf.Path("/Proto/base")])
    hinge.CreateBody1Rel().SetTargets([Sdf.Path("/Proto/link")])
    for i in range(3):
        clone = stage.DefinePrim(f"/World/clone_{i}")
        clone.GetReferences().AddInternalReference("/Proto")
        clone.SetInstanceable(True)
    stage.Save()
    save_envelope(AK80, tmp_path / "ak80.toml")
    out = tmp_path / "scene_envelope.usda"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        argv = ["usd", "apply", str(tmp_path / "scene.usda"), "--joint", "/World/clone_1/hinge", "--envelope",
                str(tmp_path / "ak80.toml"), "-o", str(out)]  # fmt: skip
        assert main(argv) == 0
    assert inspect_drives(out) == {}  # instanced: PhysX simulates no body, hence no DOF, there
    deinstanced = Sdf.Layer.CreateNew(str(tmp_path / "deinstanced.usda"))
    deinstanced.subLayerPaths.append(f"./{out.name}")
    deinstanced.pseudoRoot.SetInfo("metersPerUnit", 1.0)
    view = Usd.Stage.Open(deinstanced)
    for i in range(3):
        view.OverridePrim(f"/World/clone_{i}").SetInstanceable(False)
    deinstanced.Save()
    dofs = inspect_drives(tmp_path / "deinstanced.usda")
    assert sorted(dofs) == [f"/World/clone_{i}/hinge" for i in range(3)]
    for dof in dofs.values():
        _assert_ak80(dof)

"""``drive_envelope.newton.add_envelopes_from_usd``: the PhysX envelopes of a USD asset as Newton actuators.

Newton 1.8's ``add_usd`` drops ``PhysxDrivePerformanceEnvelopeAPI``; the function reads every
drive of the same stage through the USD adapter and adds ``DrivePD`` + ``ClampingPerformanceEnvelope``
on that DOF. Golden values: the per-degree USD numbers are converted by hand here (2 N*m/deg =
114.59 N*m/rad), and cross-checked with the gains Newton's own importer derives from the same
drive. Real assets (``../shared/data/newton-assets``): the ANYmal C (crate file, floating base, 12
revolute drives), the humanoid (D6 joints: one DOF per rotX|Y|Z axis) and Newton's D6 test joint
(outside any articulation: PhysX ignores its envelope, so does the import). Newton needs its
importer extra (``newton[importers]``: newton-usd-schemas).
"""

from __future__ import annotations

import math
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

pytestmark = [pytest.mark.newton, pytest.mark.usd]

REPO = Path(__file__).resolve().parents[1]
ASSETS = REPO.parent / "shared" / "data" / "newton-assets"
ELBOW = de.PerformanceEnvelope(
    max_effort=5.0, max_actuator_velocity=4.0, velocity_dependent_resistance=0.2, speed_effort_gradient=0.5
)
SLIDER = de.PerformanceEnvelope(
    joint="prismatic", max_effort=80.0, max_actuator_velocity=0.3, speed_effort_gradient=0.002
)


@pytest.fixture(autouse=True)
def physx_schemas() -> None:
    """Register the PhysX schemas before Newton opens any stage (USD builds its registry once)."""
    pytest.importorskip("newton_usd_schemas", reason="Newton's add_usd needs newton[importers]")
    from drive_envelope.usd import register_schemas

    register_schemas()


def _asset(name: str) -> Path:
    path = ASSETS / name
    if not path.is_file():
        pytest.skip(f"needs ../shared/data/newton-assets/{name} (Newton's example assets; absent here)")
    return path


def _robot(path: Path, *, drive_type: str = "force", meters_per_unit: float = 1.0) -> Path:
    """A floating base with an elbow (revolute, Z) and a slider (prismatic, X), envelopes authored."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics

    from drive_envelope.usd import save_stage, write_envelope

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, meters_per_unit)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    root = UsdGeom.Xform.Define(stage, "/Robot").GetPrim()
    UsdPhysics.ArticulationRootAPI.Apply(root)
    for name, z in (("base", 0.0), ("arm", 0.5), ("carriage", 1.0)):
        prim = UsdGeom.Xform.Define(stage, f"/Robot/{name}").GetPrim()
        UsdGeom.Xformable(prim).AddTranslateOp().Set(Gf.Vec3d(0.0, 0.0, z))
        UsdPhysics.RigidBodyAPI.Apply(prim)
        mass = UsdPhysics.MassAPI.Apply(prim)
        mass.CreateMassAttr().Set(1.0)
        mass.CreateDiagonalInertiaAttr().Set(Gf.Vec3f(0.01, 0.01, 0.01))
    for joint_name, schema, parent, child, instance, gains in (
        ("elbow", UsdPhysics.RevoluteJoint, "base", "arm", "angular", (2.0, 0.1)),  # per degree
        ("slider", UsdPhysics.PrismaticJoint, "arm", "carriage", "linear", (300.0, 20.0)),
    ):
        joint = schema.Define(stage, f"/Robot/{joint_name}")
        joint.CreateAxisAttr().Set("Z" if joint_name == "elbow" else "X")
        joint.CreateBody0Rel().SetTargets([Sdf.Path(f"/Robot/{parent}")])
        joint.CreateBody1Rel().SetTargets([Sdf.Path(f"/Robot/{child}")])
        joint.CreateLocalPos0Attr().Set(Gf.Vec3f(0.0, 0.0, 0.25))
        joint.CreateLocalPos1Attr().Set(Gf.Vec3f(0.0, 0.0, -0.25))
        drive = UsdPhysics.DriveAPI.Apply(joint.GetPrim(), instance)
        drive.CreateTypeAttr().Set(drive_type)
        drive.CreateStiffnessAttr().Set(gains[0])
        drive.CreateDampingAttr().Set(gains[1])
        write_envelope(stage, f"/Robot/{joint_name}", ELBOW if joint_name == "elbow" else SLIDER)
    save_stage(stage, path, flatten=True)
    return path


def _builder(path: Path) -> Any:
    import newton

    builder = newton.ModelBuilder()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Newton's importer notes about the minimal test asset
        builder.add_usd(str(path))
    return builder


def test_adds_pd_and_envelope_per_drive_with_si_gains(tmp_path: Path) -> None:
    """Add one actuator per drive: gains per radian, envelope in SI, Newton's own drive turned off."""
    from newton import JointTargetMode

    from drive_envelope.newton import add_envelopes_from_usd

    builder = _builder(_robot(tmp_path / "robot.usda"))
    elbow = builder.joint_label.index("/Robot/elbow")
    elbow_dof = builder.joint_qd_start[elbow]
    newton_kp = builder.joint_target_ke[elbow_dof]  # what Newton's importer made of 2 N*m/deg
    added = add_envelopes_from_usd(builder, tmp_path / "robot.usda")
    assert [(a.joint_path, a.instance) for a in added] == [
        ("/Robot/elbow", "angular"),
        ("/Robot/slider", "linear"),
    ]
    first = added[0]
    assert first.stiffness == pytest.approx(2.0 * 180.0 / math.pi) == pytest.approx(newton_kp)
    assert first.damping == pytest.approx(0.1 * 180.0 / math.pi)
    assert added[1].stiffness == pytest.approx(300.0) and added[1].damping == pytest.approx(20.0)
    for record, expected in zip(added, (ELBOW, SLIDER), strict=True):
        for field in (
            "max_effort",
            "max_actuator_velocity",
            "velocity_dependent_resistance",
            "speed_effort_gradient",
        ):
            assert getattr(record.envelope, field) == pytest.approx(getattr(expected, field), rel=1e-6)
        assert record.dof_index == builder.joint_qd_start[record.joint_index]
        assert record.coord_index == builder.joint_q_start[record.joint_index]
        assert record.coord_index == record.dof_index + 1  # the floating base: 7 coordinates, 6 DOFs
        assert builder.joint_target_ke[record.dof_index] == 0.0 == builder.joint_target_kd[record.dof_index]
        assert builder.joint_target_mode[record.dof_index] == int(JointTargetMode.EFFORT)
    assert add_envelopes_from_usd(builder, tmp_path / "robot.usda") == []  # already actuated: nothing new
    model = builder.finalize(device="cpu")
    (actuator,) = model.actuators
    assert actuator.indices.numpy().tolist() == [a.dof_index for a in added]
    assert actuator.pos_indices.numpy().tolist() == [a.coord_index for a in added]
    clamp = actuator.clamping[0]
    np.testing.assert_allclose(clamp.max_effort.numpy(), [5.0, 80.0])
    np.testing.assert_allclose(clamp.max_actuator_velocity.numpy(), [4.0, 0.3], rtol=1e-6)
    np.testing.assert_allclose(actuator.drive.kp.numpy(), [first.stiffness, 300.0], rtol=1e-6)


def test_explicit_step_applies_the_clamped_pd_law(tmp_path: Path) -> None:
    """Step the added actuator: the elbow's effort is the PD law clamped by its envelope."""
    from drive_envelope.newton import add_envelopes_from_usd

    builder = _builder(_robot(tmp_path / "robot.usda"))
    added = add_envelopes_from_usd(builder, tmp_path / "robot.usda")
    model = builder.finalize(device="cpu")
    state, control = model.state(), model.control()
    elbow = added[0]
    target = np.zeros(model.joint_coord_count, dtype=np.float32)
    target[elbow.coord_index] = 0.02  # rad: kp * 0.02 = 2.29 N*m, inside the envelope at rest
    control.joint_target_q.assign(target)
    velocity = np.zeros(model.joint_dof_count, dtype=np.float32)
    velocity[elbow.dof_index] = 3.0
    state.joint_qd.assign(velocity)
    control.joint_f.zero_()
    model.actuators[0].step(state, control, dt=0.01)
    request = elbow.stiffness * 0.02 - elbow.damping * 3.0
    expected = float(de.clamp_effort(ELBOW, np.array([request]), np.array([3.0]))[0])
    assert abs(expected) < abs(request)  # the envelope binds at 3 rad/s: L = (4 - 3)/0.5 = 2
    assert float(control.joint_f.numpy()[elbow.dof_index]) == pytest.approx(expected, rel=1e-5)


def test_replicated_worlds_carry_the_actuators(tmp_path: Path) -> None:
    """Copy the actuators with the robot when the builder is replicated into several worlds."""
    import newton

    from drive_envelope.newton import add_envelopes_from_usd

    robot = _builder(_robot(tmp_path / "robot.usda"))
    added = add_envelopes_from_usd(robot, tmp_path / "robot.usda")
    scene = newton.ModelBuilder()
    scene.replicate(robot, 3)
    model = scene.finalize(device="cpu")
    dofs = robot.joint_dof_count
    expected = [a.dof_index + world * dofs for world in range(3) for a in added]
    assert sorted(model.actuators[0].indices.numpy().tolist()) == sorted(expected)


def test_bad_input_is_one_line_naming_the_file(tmp_path: Path) -> None:
    """Refuse non-SI stages, acceleration drives and joints the builder lacks, naming file and joint."""
    import newton

    from drive_envelope.newton import add_envelopes_from_usd

    centimetres = _robot(tmp_path / "cm.usda", meters_per_unit=0.01)
    with pytest.raises(InputError, match=r"cm\.usda: metersPerUnit = 0\.01.*Newton imports USD only in SI"):
        add_envelopes_from_usd(newton.ModelBuilder(), centimetres)
    accel = _robot(tmp_path / "accel.usda", drive_type="acceleration")
    with pytest.raises(
        InputError, match=r"accel\.usda: joint '/Robot/elbow' \(angular\): drive type 'acceleration'"
    ):
        add_envelopes_from_usd(_builder(accel), accel)
    robot = _robot(tmp_path / "robot.usda")
    with pytest.raises(InputError, match=r"no joint with this label in the builder; call builder\.add_usd"):
        add_envelopes_from_usd(newton.ModelBuilder(), robot)
    with pytest.raises(InputError, match=r"missing\.usda: no such file"):
        add_envelopes_from_usd(newton.ModelBuilder(), tmp_path / "missing.usda")


def test_the_natural_script_works_whatever_the_schema_order(tmp_path: Path) -> None:
    """Issue 23 item 14: add_usd before any register_schemas(); the envelopes are read from the layers."""
    robot = _robot(tmp_path / "robot.usda")
    code = (
        "import newton, warnings\n"
        "warnings.simplefilter('ignore')\n"
        "from drive_envelope.newton import add_envelopes_from_usd\n"
        f"b = newton.ModelBuilder(); b.add_usd({str(robot)!r})\n"
        f"for a in add_envelopes_from_usd(b, {str(robot)!r}):\n"
        "    e = a.envelope\n"
        "    print(a.instance, repr(e.max_effort), repr(e.max_actuator_velocity))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    found = {
        words[0]: (float(words[1]), float(words[2]))
        for words in (line.split() for line in out.splitlines())
        if words and words[0] in ("angular", "linear")  # Warp prints its banner too
    }
    assert set(found) == {"angular", "linear"}
    for inst, env in (("angular", ELBOW), ("linear", SLIDER)):  # USD stores floats: float32 digits
        assert found[inst] == pytest.approx((env.max_effort, env.max_actuator_velocity), rel=1e-6)


def _apply(asset: Path, out: Path, *args: str) -> Path:
    from drive_envelope._src.cli.main import main

    assert main(["usd", "apply", str(asset), *args, "-o", str(out)]) == 0
    return out


def test_anymal_gets_twelve_envelope_actuators(tmp_path: Path) -> None:
    """Import the ANYmal C after `usd apply --map`: 12 leg DOFs with the catalog envelopes, base skipped."""
    from drive_envelope.newton import add_envelopes_from_usd

    layer = _apply(
        _asset("anymal_c.usd"),
        tmp_path / "anymal_envelope.usda",
        "--map",
        str(REPO / "examples" / "newton" / "anymal_map.toml"),
    )
    builder = _builder(layer)
    added = add_envelopes_from_usd(builder, layer)
    assert len(added) == 12 and sorted(a.dof_index for a in added) == list(range(6, 18))
    from drive_envelope.datasheet import resolve_envelope

    hip = resolve_envelope("myactuator-rmd-x8-120")
    knee = resolve_envelope("myactuator-rmd-x12-320")
    for record in added:
        expected = knee if record.joint_path.endswith("_KFE") else hip
        assert record.envelope.max_effort == pytest.approx(expected.max_effort, rel=1e-6)
        assert record.envelope.speed_effort_gradient == pytest.approx(
            expected.speed_effort_gradient, rel=1e-5
        )
        assert record.coord_index == record.dof_index + 1
    model = builder.finalize(device="cpu")
    by_dof = sorted(added, key=lambda a: a.dof_index)
    caps = np.array([a.envelope.max_effort for a in by_dof])
    # explicit mode, from rest: a 500 N*m request is cut to each actuator's max_effort
    effort, _ = _leg_step(model, implicit=False, dt=0.005)
    np.testing.assert_allclose(effort[6:], caps, rtol=1e-6)
    # implicit mode with gravity: each DOF's effort is min(request, L(v_end)) at the coupled end velocity
    effort, v_end = _leg_step(model, implicit=True, dt=0.001)
    limits = np.array([a.envelope.effort_limit(np.array([v_end[a.dof_index]]))[0] for a in by_dof])
    np.testing.assert_allclose(effort[6:], np.minimum(500.0, limits), rtol=1e-5, atol=1e-3)
    assert np.any(limits < caps - 1.0)  # the speed lines bind on some legs within the step


def _leg_step(model: Any, *, implicit: bool, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """One actuator step from rest with 500 N*m feed-forward on every leg DOF.

    Returns the effort per DOF and the end-of-step velocity the implicit solve predicts from the
    coupled response (``qd + A (p - dt b)``, recomputed here from Newton's inverse mass matrix).
    """
    from newton.actuators import Actuator, JointSpaceResponse

    from drive_envelope.newton import BiasForce

    actuator = model.actuators[0]
    response = JointSpaceResponse(model)
    if implicit:
        options = Actuator.ImplicitOptions(residual_tol=1e-9, update_tol=1e-12, max_iters=32)
        actuator.set_effort_mode_implicit(response=response, options=options)
    state, control = model.state(), model.control()
    feedforward = np.zeros(model.joint_dof_count, dtype=np.float32)
    feedforward[6:] = 500.0
    control.joint_act.assign(feedforward)
    control.joint_f.zero_()
    response.refresh(state)
    bias = BiasForce(model).compute(state)
    actuator.step(state, control, dt=dt, bias_force=bias)
    effort = control.joint_f.numpy().astype(np.float64)
    inverse_mass = response.inverse_blocks.numpy()[0].astype(np.float64)
    v_end = inverse_mass @ (effort * dt - dt * bias.numpy().astype(np.float64))
    return effort, v_end


def test_humanoid_d6_axis_maps_to_its_own_dof(tmp_path: Path) -> None:
    """Put the envelope on the DOF of the D6 axis it was authored on (rotY of the right thigh)."""
    from drive_envelope.newton import add_envelopes_from_usd

    envelope = tmp_path / "thigh.toml"
    de.save_envelope(ELBOW, envelope)
    layer = _apply(
        _asset("humanoid.usda"),
        tmp_path / "humanoid_envelope.usda",
        "--joint",
        "/nv_humanoid/joints/right_thigh",
        "--instance",
        "rotY",
        "--envelope",
        str(envelope),
    )
    builder = _builder(layer)
    (record,) = add_envelopes_from_usd(builder, layer)
    assert record.instance == "rotY"
    assert [float(c) for c in builder.joint_axis[record.dof_index]] == [0.0, 1.0, 0.0]
    assert record.dof_index == builder.joint_qd_start[record.joint_index] + 1  # rotX, rotY, rotZ


def test_envelope_outside_an_articulation_is_ignored_with_a_warning(tmp_path: Path) -> None:
    """Skip, as PhysX does, the envelope of Newton's D6 test joint, which is in no articulation."""
    from drive_envelope.newton import EnvelopeImportWarning, add_envelopes_from_usd

    envelope = tmp_path / "joint.toml"
    de.save_envelope(ELBOW, envelope)
    joint = "/test_joint_d6_revolute_actuated/Joints/actuated_d6_revolute_joint"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # usd apply's own warning about the same joint
        layer = _apply(
            _asset("t_test_joint_d6_revolute_actuated.usda"),
            tmp_path / "d6.usda",
            "--joint",
            joint,
            "--instance",
            "rotY",
            "--envelope",
            str(envelope),
        )
    builder = _builder(layer)
    with pytest.warns(EnvelopeImportWarning, match="not an articulation joint; PhysX ignores its envelope"):
        assert add_envelopes_from_usd(builder, layer) == []


def test_newton_add_envelopes_refuses_a_finalized_builder(tmp_path: Path) -> None:
    newton = pytest.importorskip("newton")
    from drive_envelope.newton import add_envelopes_from_usd

    builder = newton.ModelBuilder()
    builder.finalize(device="cpu")
    with pytest.raises(
        InputError, match=r"builder: already finalized.*call add_envelopes_from_usd before finalize"
    ):
        add_envelopes_from_usd(builder, tmp_path / "robot.usda")


def test_newton_add_envelopes_takes_a_builder_with_worlds(tmp_path: Path) -> None:
    """``begin_world``/``end_world`` are not taken for ``finalize`` (the check reads past them)."""
    newton = pytest.importorskip("newton")
    from drive_envelope.newton import add_envelopes_from_usd

    builder = newton.ModelBuilder()
    builder.begin_world()
    builder.end_world()
    with pytest.raises(InputError, match=r"missing\.usda: no such file"):
        add_envelopes_from_usd(builder, tmp_path / "missing.usda")


def test_newton_add_envelopes_names_wrong_argument_types(tmp_path: Path) -> None:
    newton = pytest.importorskip("newton")
    from drive_envelope.newton import add_envelopes_from_usd

    with pytest.raises(InputError, match=r"builder: expected a newton\.ModelBuilder, got NoneType"):
        add_envelopes_from_usd(None, tmp_path / "robot.usda")
    with pytest.raises(InputError, match=r"source: expected a USD file path .* or a Usd\.Stage, got int"):
        add_envelopes_from_usd(newton.ModelBuilder(), 42)

"""Authoring and reading PhysxDrivePerformanceEnvelopeAPI with PhysX's unit conventions (usd-core only).

Golden values: the degree conversions are the ones PhysX itself reports after reading USD
(SEMANTICS.md: 180 deg/s -> pi rad/s, 0.02 N*m*s/deg -> 1.14592 N*m*s/rad, 18 (deg/s)/(N*m) ->
0.314159 (rad/s)/(N*m)); the stage-unit factors are worked by hand in each test.
"""

from __future__ import annotations

import math
import warnings

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drive_envelope import InputError, PerformanceEnvelope

pytestmark = pytest.mark.usd


def _stage(meters_per_unit: float = 1.0, kilograms_per_unit: float = 1.0, *, articulation: bool = True):
    """A robot whose base carries a revolute, a prismatic, a D6 and a fixed joint, each to its own link."""
    import physx_usd_schemas  # noqa: F401
    from pxr import Sdf, Usd, UsdGeom, UsdPhysics

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, meters_per_unit)
    UsdPhysics.SetStageKilogramsPerUnit(stage, kilograms_per_unit)
    root = UsdGeom.Xform.Define(stage, "/Robot").GetPrim()
    if articulation:
        UsdPhysics.ArticulationRootAPI.Apply(root)
    UsdPhysics.RigidBodyAPI.Apply(UsdGeom.Xform.Define(stage, "/Robot/base").GetPrim())
    for name, schema in (
        ("hinge", UsdPhysics.RevoluteJoint),
        ("slider", UsdPhysics.PrismaticJoint),
        ("d6", UsdPhysics.Joint),
        ("weld", UsdPhysics.FixedJoint),
    ):
        link = f"/Robot/{name}_link"
        UsdPhysics.RigidBodyAPI.Apply(UsdGeom.Xform.Define(stage, link).GetPrim())
        joint = schema.Define(stage, f"/Robot/{name}")
        joint.CreateBody0Rel().SetTargets([Sdf.Path("/Robot/base")])
        joint.CreateBody1Rel().SetTargets([Sdf.Path(link)])
    return stage


ANGULAR = PerformanceEnvelope(
    max_effort=12.0, max_actuator_velocity=math.pi, velocity_dependent_resistance=1.1459155902616465,
    speed_effort_gradient=0.3141592653589793,
)  # fmt: skip
LINEAR = PerformanceEnvelope(
    joint="prismatic", max_effort=300.0, max_actuator_velocity=0.5, velocity_dependent_resistance=40.0,
    speed_effort_gradient=0.001,
)  # fmt: skip


def _attr(stage, path: str, name: str) -> float:
    return float(stage.GetPrimAtPath(path).GetAttribute(name).Get())


def test_write_angular_envelope_in_degrees() -> None:
    """Store angular envelopes per degree: 180 deg/s, 0.02 N*m*s/deg, 18 (deg/s)/(N*m)."""
    from drive_envelope.usd import write_envelope

    stage = _stage()
    assert write_envelope(stage, "/Robot/hinge", ANGULAR) == "angular"
    prim = stage.GetPrimAtPath("/Robot/hinge")
    assert prim.HasAPI("PhysxDrivePerformanceEnvelopeAPI", "angular")
    assert "PhysicsDriveAPI:angular" in prim.GetAppliedSchemas()
    assert _attr(stage, "/Robot/hinge", "drive:angular:physics:maxForce") == 12.0
    base = "physxDrivePerformanceEnvelope:angular:"
    assert _attr(stage, "/Robot/hinge", base + "maxActuatorVelocity") == pytest.approx(180.0, rel=1e-7)
    assert _attr(stage, "/Robot/hinge", base + "velocityDependentResistance") == pytest.approx(0.02, rel=1e-7)
    assert _attr(stage, "/Robot/hinge", base + "speedEffortGradient") == pytest.approx(18.0, rel=1e-7)


def test_write_linear_envelope_in_centimetre_gram_stage() -> None:
    """Scale linear values by metersPerUnit 0.01 and kilogramsPerUnit 0.001 (cm, g)."""
    from drive_envelope.usd import write_envelope

    stage = _stage(0.01, 0.001)
    assert write_envelope(stage, "/Robot/slider", LINEAR) == "linear"
    # 1 N = 1 kg*m/s^2 = 1000 g * 100 cm / s^2 = 1e5 stage force units
    assert _attr(stage, "/Robot/slider", "drive:linear:physics:maxForce") == pytest.approx(
        300.0 * 1e5, rel=1e-7
    )
    base = "physxDrivePerformanceEnvelope:linear:"
    assert _attr(stage, "/Robot/slider", base + "maxActuatorVelocity") == pytest.approx(50.0, rel=1e-7)
    # N*s/m = kg/s = 1000 g/s; (m/s)/N = s/kg = 1e-3 s/g
    assert _attr(stage, "/Robot/slider", base + "velocityDependentResistance") == pytest.approx(
        4.0e4, rel=1e-7
    )
    assert _attr(stage, "/Robot/slider", base + "speedEffortGradient") == pytest.approx(1.0e-6, rel=1e-7)


def test_write_angular_efforts_scale_with_length_squared() -> None:
    """Scale torques by 1/(kilogramsPerUnit * metersPerUnit^2) on a centimetre stage."""
    from drive_envelope.usd import write_envelope

    stage = _stage(0.01, 1.0)
    write_envelope(stage, "/Robot/hinge", ANGULAR)
    # 1 N*m = 1 kg*m^2/s^2 = 1e4 kg*cm^2/s^2
    assert _attr(stage, "/Robot/hinge", "drive:angular:physics:maxForce") == pytest.approx(12.0e4, rel=1e-7)
    base = "physxDrivePerformanceEnvelope:angular:"
    assert _attr(stage, "/Robot/hinge", base + "maxActuatorVelocity") == pytest.approx(180.0, rel=1e-7)
    assert _attr(stage, "/Robot/hinge", base + "velocityDependentResistance") == pytest.approx(
        0.02e4, rel=1e-7
    )
    assert _attr(stage, "/Robot/hinge", base + "speedEffortGradient") == pytest.approx(18.0e-4, rel=1e-7)


def test_read_inverts_write_with_unit_metadata() -> None:
    """Read back the written envelope in SI on revolute and prismatic joints."""
    from drive_envelope.usd import read_envelope, write_envelope

    stage = _stage(0.01, 0.001)
    write_envelope(stage, "/Robot/hinge", ANGULAR)
    write_envelope(stage, "/Robot/slider", LINEAR)
    for path, env in (("/Robot/hinge", ANGULAR), ("/Robot/slider", LINEAR)):
        back = read_envelope(stage, path)
        assert back.joint == env.joint and back.name == path
        for field in (
            "max_effort",
            "max_actuator_velocity",
            "velocity_dependent_resistance",
            "speed_effort_gradient",
        ):
            assert getattr(back, field) == pytest.approx(getattr(env, field), rel=2e-7), field


@settings(max_examples=40, deadline=None)
@given(
    max_effort=st.floats(1e-3, 1e4),
    velocity=st.one_of(st.just(math.inf), st.floats(1e-3, 1e3)),
    resistance=st.floats(0.0, 1e2),
    gradient=st.floats(0.0, 1e1),
    meters=st.sampled_from([1.0, 0.01, 0.001, 0.3048]),
    kilograms=st.sampled_from([1.0, 0.001, 2.0]),
    prismatic=st.booleans(),
)
def test_round_trip_property(
    max_effort: float,
    velocity: float,
    resistance: float,
    gradient: float,
    meters: float,
    kilograms: float,
    prismatic: bool,
) -> None:
    """Round-trip any envelope through any stage units to float32 precision."""
    from drive_envelope.usd import read_envelope, write_envelope

    env = PerformanceEnvelope(
        joint="prismatic" if prismatic else "revolute", max_effort=max_effort, max_actuator_velocity=velocity,
        velocity_dependent_resistance=resistance, speed_effort_gradient=gradient,
    )  # fmt: skip
    stage = _stage(meters, kilograms)
    path = "/Robot/slider" if prismatic else "/Robot/hinge"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_envelope(stage, path, env)
    back = read_envelope(stage, path)
    for field in (
        "max_effort",
        "max_actuator_velocity",
        "velocity_dependent_resistance",
        "speed_effort_gradient",
    ):
        assert getattr(back, field) == pytest.approx(getattr(env, field), rel=3e-7, abs=1e-30), field


def test_unauthored_max_actuator_velocity_reads_inf() -> None:
    """Read an applied API without authored values as (maxForce, inf, 0, 0)."""
    from pxr import UsdPhysics

    from drive_envelope.usd import read_envelope

    stage = _stage()
    prim = stage.GetPrimAtPath("/Robot/hinge")
    UsdPhysics.DriveAPI.Apply(prim, "angular").CreateMaxForceAttr().Set(5.0)
    prim.ApplyAPI("PhysxDrivePerformanceEnvelopeAPI", "angular")
    env = read_envelope(stage, "/Robot/hinge")
    values = (
        env.max_effort,
        env.max_actuator_velocity,
        env.velocity_dependent_resistance,
        env.speed_effort_gradient,
    )
    assert values == (5.0, math.inf, 0.0, 0.0)


def test_infinite_velocity_is_written_as_inf() -> None:
    """Write an unlimited maxActuatorVelocity as inf, which PhysX reads as no speed limit."""
    from drive_envelope.usd import read_envelope, write_envelope

    stage = _stage()
    write_envelope(stage, "/Robot/hinge", PerformanceEnvelope(max_effort=3.0))
    assert (
        _attr(stage, "/Robot/hinge", "physxDrivePerformanceEnvelope:angular:maxActuatorVelocity") == math.inf
    )
    assert read_envelope(stage, "/Robot/hinge").max_actuator_velocity == math.inf


def test_unlimited_max_force_keeps_the_speed_line() -> None:
    """An envelope on an unlimited maxForce (PhysX's FLT_MAX) reads back with max_effort inf and its
    speed line, as PhysX applies it; list_drives reports the same envelope."""
    from drive_envelope.usd import list_drives, read_envelope, write_envelope

    stage = _stage()
    speed_line = PerformanceEnvelope(
        max_effort=math.inf, max_actuator_velocity=3.0, speed_effort_gradient=0.1
    )
    write_envelope(stage, "/Robot/hinge", speed_line)
    envelope = read_envelope(stage, "/Robot/hinge")
    assert (envelope.max_effort, envelope.speed_effort_gradient) == (math.inf, pytest.approx(0.1))
    assert envelope.max_actuator_velocity == pytest.approx(3.0)
    (record,) = [r for r in list_drives(stage) if r.joint_path == "/Robot/hinge"]
    assert record.envelope is not None and record.envelope.max_effort == math.inf


def test_d6_axes_need_an_instance() -> None:
    """Require rotX|rotY|rotZ on D6 joints and write the chosen axis."""
    from drive_envelope.usd import read_envelope, write_envelope

    stage = _stage()
    with pytest.raises(InputError, match="D6 joint needs an instance, one of rotX, rotY, rotZ"):
        write_envelope(stage, "/Robot/d6", ANGULAR)
    assert write_envelope(stage, "/Robot/d6", ANGULAR, instance="rotY") == "rotY"
    assert read_envelope(stage, "/Robot/d6", instance="rotY").max_actuator_velocity == pytest.approx(math.pi)


def test_a_d6_joint_without_an_instance_lists_its_driven_axes() -> None:
    """Name the axes the D6 joint has drives on, so the map entry can say which one."""
    from pxr import UsdPhysics

    from drive_envelope.usd import write_envelope

    stage = _stage()
    UsdPhysics.DriveAPI.Apply(stage.GetPrimAtPath("/Robot/d6"), "rotY")
    with pytest.raises(InputError, match=r"one of rotX, rotY, rotZ \(it has drives on rotY\)"):
        write_envelope(stage, "/Robot/d6", ANGULAR)


@pytest.mark.parametrize("axis", ["transX", "transY", "transZ"])
def test_d6_translation_axis_is_refused(axis: str) -> None:
    """Refuse a D6 translation axis: PhysX never reads an envelope there (it was a warning only)."""
    from drive_envelope.usd import write_envelope

    stage = _stage()
    with pytest.raises(
        InputError, match=rf"\({axis}\): PhysX reads the envelope only on rotX/rotY/rotZ"
    ) as info:
        write_envelope(stage, "/Robot/d6", LINEAR, instance=axis)
    assert "\n" not in str(info.value)
    assert not stage.GetPrimAtPath("/Robot/d6").GetAppliedSchemas()  # nothing was authored


def test_d6_locked_axis_is_refused() -> None:
    """Refuse an axis the joint locks (PhysicsLimitAPI low > high), as in Newton's D6 test asset."""
    from pxr import UsdPhysics

    from drive_envelope.usd import write_envelope

    stage = _stage()
    limit = UsdPhysics.LimitAPI.Apply(stage.GetPrimAtPath("/Robot/d6"), "rotZ")
    limit.CreateLowAttr(1.0)
    limit.CreateHighAttr(-1.0)
    with pytest.raises(InputError, match=r"locks rotZ \(PhysicsLimitAPI:rotZ low 1 > high -1\)"):
        write_envelope(stage, "/Robot/d6", ANGULAR, instance="rotZ")
    limit.GetHighAttr().Set(1.0)  # limited, not locked: fine
    assert write_envelope(stage, "/Robot/d6", ANGULAR, instance="rotZ") == "rotZ"


@pytest.mark.parametrize(
    ("meters", "kilograms", "field"),
    [(1e-20, 1.0, "max_effort"), (1.0, 1e-40, "max_effort"), (1.0, 1e-35, "velocity_dependent_resistance")],
)
def test_value_beyond_float32_after_unit_scaling_is_refused(
    meters: float, kilograms: float, field: str
) -> None:
    """Refuse an effort that overflows float32 in stage units (USD would store maxForce = inf)."""
    from drive_envelope.usd import write_envelope

    env = PerformanceEnvelope(max_effort=12.0, velocity_dependent_resistance=1e6, max_actuator_velocity=10.0)
    stage = _stage(meters, kilograms)
    with pytest.raises(InputError, match=rf"{field} .* beyond the largest float32") as info:
        write_envelope(stage, "/Robot/hinge", env)
    assert "metersPerUnit" in str(info.value) and "\n" not in str(info.value)
    assert not stage.GetPrimAtPath("/Robot/hinge").GetAppliedSchemas()


@pytest.mark.parametrize(
    ("path", "env", "instance", "message"),
    [
        ("/Robot/hinge", LINEAR, None, "envelope is for a prismatic joint"),
        ("/Robot/slider", ANGULAR, None, "envelope is for a revolute joint"),
        ("/Robot/hinge", ANGULAR, "linear", "instance 'linear' is not valid on a revolute joint"),
        ("/Robot/weld", ANGULAR, None, "has no drive envelope"),
        ("/Robot/nope", ANGULAR, None, "no such prim"),
        ("/Robot/base", ANGULAR, None, "is not a UsdPhysics joint"),
        ("/Robot/d6", LINEAR, "transZ", "never on transZ"),
    ],
)
def test_bad_targets_raise_one_line(
    path: str, env: PerformanceEnvelope, instance: str | None, message: str
) -> None:
    """Refuse mismatched joints, instances and envelopes with one line naming the joint."""
    from drive_envelope.usd import write_envelope

    with pytest.raises(InputError, match=message) as info:
        write_envelope(_stage(), path, env, instance)
    assert "\n" not in str(info.value)


def test_write_takes_a_source_as_set_envelope_does_and_names_anything_else() -> None:
    """A catalog name (or file) is resolved like mujoco.set_envelope's; a dict or None is one line.

    Both were ``AttributeError: 'dict' object has no attribute 'joint'`` before.
    """
    from drive_envelope.datasheet import resolve_envelope
    from drive_envelope.usd import read_envelope, write_envelope

    by_name, by_value = _stage(), _stage()
    assert write_envelope(by_name, "/Robot/hinge", "tmotor-ak80-6") == "angular"
    write_envelope(by_value, "/Robot/hinge", resolve_envelope("tmotor-ak80-6"))
    assert read_envelope(by_name, "/Robot/hinge") == read_envelope(by_value, "/Robot/hinge")
    for bad in ({"max_effort": 3.0}, None):
        with pytest.raises(
            InputError, match=r"write_envelope: argument 'envelope': expected an envelope"
        ) as info:
            write_envelope(_stage(), "/Robot/hinge", bad)  # type: ignore[arg-type]
        assert "\n" not in str(info.value)
    with pytest.raises(InputError, match=r"'tmotor-ak80-7': no such file or catalog actuator \(did you mean"):
        write_envelope(_stage(), "/Robot/hinge", "tmotor-ak80-7")
    with pytest.raises(InputError, match="envelope is for a prismatic joint"):
        write_envelope(_stage(), "/Robot/hinge", "actuonix-l16-35-6-r")


@pytest.mark.parametrize("bad", [None, "examples/usd/robot.usda"])
def test_list_drives_and_stage_units_name_an_argument_that_is_not_a_stage(bad: object) -> None:
    """None or a path was USD's multi-line ``Tf.ErrorException`` ('Invalid UsdStage')."""
    from drive_envelope.usd import list_drives, stage_units

    for call in (list_drives, stage_units):
        with pytest.raises(
            InputError, match=r"^argument 'stage': expected a Usd\.Stage \(drive_envelope\.usd\.open_stage"
        ) as info:
            call(bad)  # type: ignore[arg-type]
        assert "\n" not in str(info.value) and type(bad).__name__ in str(info.value)


def test_read_without_api_raises() -> None:
    """Refuse to read an envelope that was never applied."""
    from drive_envelope.usd import read_envelope

    with pytest.raises(InputError, match="no PhysxDrivePerformanceEnvelopeAPI:angular applied"):
        read_envelope(_stage(), "/Robot/hinge")


def test_warn_outside_articulation() -> None:
    """Warn that PhysX strips the envelope from a joint outside any articulation."""
    from drive_envelope.usd import EnvelopeAuthoringWarning, write_envelope

    with pytest.warns(EnvelopeAuthoringWarning, match="does not make it an articulation joint"):
        write_envelope(_stage(articulation=False), "/Robot/hinge", ANGULAR)


def test_warn_on_disagreeing_max_force_and_per_radian_gains() -> None:
    """Warn when the drive's maxForce differs and when its gains look per radian."""
    from pxr import UsdPhysics

    from drive_envelope.usd import EnvelopeAuthoringWarning, write_envelope

    stage = _stage()
    drive = UsdPhysics.DriveAPI.Apply(stage.GetPrimAtPath("/Robot/hinge"), "angular")
    drive.CreateMaxForceAttr().Set(20.0)
    drive.CreateStiffnessAttr().Set(100.0)  # 100 N*m per degree: saturates 12 N*m at 0.12 degree
    drive.CreateDampingAttr().Set(0.05)  # 2.9 N*m*s/rad: fine
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        write_envelope(stage, "/Robot/hinge", ANGULAR)
    messages = [str(w.message) for w in caught if issubclass(w.category, EnvelopeAuthoringWarning)]
    assert any("replacing maxForce 20 with max_effort 12" in m for m in messages)
    assert any("stiffness 100 per degree" in m for m in messages)
    assert not any("damping" in m for m in messages)


def test_no_warnings_for_a_clean_articulation_joint() -> None:
    """Stay silent for a fresh drive inside an articulation."""
    from drive_envelope.usd import write_envelope

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_envelope(_stage(), "/Robot/hinge", ANGULAR)


def test_list_drives_reports_si_values() -> None:
    """List every drive with SI gains and its envelope, None where the API is absent."""
    from pxr import UsdPhysics

    from drive_envelope.usd import list_drives, write_envelope

    stage = _stage(0.01, 1.0)
    write_envelope(stage, "/Robot/hinge", ANGULAR)
    drive = UsdPhysics.DriveAPI.Apply(stage.GetPrimAtPath("/Robot/slider"), "linear")
    drive.CreateMaxForceAttr().Set(500.0)  # 5 N in a centimetre stage
    drive.CreateDampingAttr().Set(100.0)  # kg/s: 100 N*s/m
    records = {r.joint_path: r for r in list_drives(stage)}
    assert set(records) == {"/Robot/hinge", "/Robot/slider"}
    hinge, slider = records["/Robot/hinge"], records["/Robot/slider"]
    assert hinge.in_articulation and hinge.instance == "angular"
    assert hinge.envelope is not None and hinge.envelope.max_effort == pytest.approx(12.0)
    assert (
        slider.envelope is None
        and slider.max_effort == pytest.approx(5.0)
        and slider.damping == pytest.approx(100.0)
    )


def test_write_on_a_prim_and_relative_path() -> None:
    """Accept the joint prim itself, or a path relative to a given prim."""
    from drive_envelope.usd import read_envelope, write_envelope

    stage = _stage()
    write_envelope(stage.GetPrimAtPath("/Robot/hinge"), None, ANGULAR)
    write_envelope(stage.GetPrimAtPath("/Robot"), "slider", LINEAR)
    assert read_envelope(stage.GetPrimAtPath("/Robot/slider")).max_effort == 300.0


def test_non_numeric_envelope_attribute_is_one_line() -> None:
    """Report an asset's envelope attribute that holds a string, naming the joint and attribute."""
    import physx_usd_schemas  # noqa: F401
    from pxr import Sdf, Usd

    from drive_envelope.usd import list_drives

    layer = Sdf.Layer.CreateAnonymous(".usda")
    layer.ImportFromString(
        '#usda 1.0\ndef PhysicsRevoluteJoint "hinge" (\n'
        '    prepend apiSchemas = ["PhysicsDriveAPI:angular",\n'
        '                          "PhysxDrivePerformanceEnvelopeAPI:angular"]\n)\n{\n'
        "    float drive:angular:physics:maxForce = 5\n"
        '    string physxDrivePerformanceEnvelope:angular:maxActuatorVelocity = "fast"\n}\n'
    )
    name = "physxDrivePerformanceEnvelope:angular:maxActuatorVelocity"
    with pytest.raises(InputError, match=rf"joint '/hinge' \(angular\): {name} is 'fast'; expected a number"):
        list_drives(Usd.Stage.Open(layer))


def test_a_usd_joint_path_with_a_typo_names_the_nearest_joints() -> None:
    from pxr import Usd, UsdPhysics

    from drive_envelope._src.adapters.usd.authoring import resolve_joint
    from drive_envelope._src.adapters.usd.stage import register_schemas

    register_schemas()  # before the first stage, as every entry point does
    stage = Usd.Stage.CreateInMemory()
    UsdPhysics.RevoluteJoint.Define(stage, "/Robot/Arm/RevoluteJoint")
    UsdPhysics.PrismaticJoint.Define(stage, "/Robot/Rail/Slider")
    with pytest.raises(
        InputError, match=r"'/Robot/Arm/RevolutJoint': no such prim .*did you mean '/Robot/Arm/RevoluteJoint'"
    ):
        resolve_joint(stage, "/Robot/Arm/RevolutJoint")
    with pytest.raises(
        InputError, match=r"'/RevoluteJoint': no such prim .*did you mean '/Robot/Arm/RevoluteJoint'\?\)"
    ):
        resolve_joint(stage, "RevoluteJoint")  # a bare name is relative to the root
    with pytest.raises(
        InputError, match=r"'/Zzz': no such prim .*; it has 2 joint\(s\), e\.g\. '/Robot/Arm/RevoluteJoint'"
    ):
        resolve_joint(stage, "/Zzz")
    with pytest.raises(  # the link's path, not its joint's (Newton's cartpole: /cartPole is an Xform)
        InputError,
        match=r"'/Robot/Rail': prim of type '' is not a UsdPhysics joint \(did you mean '/Robot/Rail/Slider'",
    ):
        resolve_joint(stage, "/Robot/Rail")

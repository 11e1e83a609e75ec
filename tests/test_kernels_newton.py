"""Newton integration (drive_envelope.newton): ClampingPerformanceEnvelope in explicit and implicit mode.

References: the core ``clamp_effort`` (explicit) and ``clamp_effort_implicit`` (PhysX's implicit
clamp); Newton's own ``ClampingDCMotor`` where the two models coincide. Newton works in float32
(efforts, velocities) and float64 inside its implicit solve: tolerance ``rtol = 1e-5`` explicit,
``rtol = 1e-4`` implicit (the solve stops at an absolute residual, tightened here to 1e-9 N*m*s).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

pytestmark = pytest.mark.newton

INERTIA = 0.01
"""Inertia of the test link about the joint axis [kg*m^2]: response 1/INERTIA."""


def _f32(values: Any) -> Any:
    import warp as wp

    return wp.array(np.asarray(values, dtype=np.float32), dtype=wp.float32, device="cpu")


def _clamp(env: de.PerformanceEnvelope, n: int) -> Any:
    from drive_envelope.newton import ClampingPerformanceEnvelope

    return ClampingPerformanceEnvelope(
        max_effort=_f32([env.max_effort] * n),
        max_actuator_velocity=_f32([env.max_actuator_velocity] * n),
        velocity_dependent_resistance=_f32([env.velocity_dependent_resistance] * n),
        speed_effort_gradient=_f32([env.speed_effort_gradient] * n),
    )


def _modify(clamp: Any, effort: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    import warp as wp

    n = effort.shape[0]
    order = np.arange(n, dtype=np.uint32)[::-1].copy()  # velocities indexed through vel_indices
    indices = wp.array(order, dtype=wp.uint32, device="cpu")
    dst = wp.zeros(n, dtype=wp.float32, device="cpu")
    clamp.modify_forces(
        _f32(effort), dst, _f32(np.zeros(n)), _f32(velocity[order]), indices, indices, device="cpu"
    )
    return dst.numpy()


def test_resolve_arguments_fills_defaults_and_reads_units() -> None:
    """Fill the defaults and convert strings with units to SI (revolute or prismatic by dimension)."""
    from drive_envelope.newton import ClampingPerformanceEnvelope

    args = ClampingPerformanceEnvelope.resolve_arguments({"max_effort": 3, "max_actuator_velocity": "60 rpm"})
    assert args == {
        "max_effort": 3.0,
        "max_actuator_velocity": pytest.approx(2.0 * math.pi),
        "velocity_dependent_resistance": 0.0,
        "speed_effort_gradient": 0.0,
    }
    linear = ClampingPerformanceEnvelope.resolve_arguments(
        {"max_effort": "200 N", "max_actuator_velocity": "0.5 m/s"}
    )
    assert linear["max_effort"] == 200.0 and linear["max_actuator_velocity"] == 0.5


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ({"max_effort": 1.0, "speed_gradient": 0.1}, "did you mean 'speed_effort_gradient'"),
        ({"max_actuator_velocity": 1.0}, "missing argument 'max_effort'"),
        ({"max_effort": -1.0}, "max_effort must be >= 0"),
        ({"max_effort": 1.0, "max_actuator_velocity": "3 Hz"}, "angle"),
    ],
)
def test_resolve_arguments_rejects_bad_input(args: dict[str, object], message: str) -> None:
    """Raise one InputError line naming the argument and the value."""
    from drive_envelope.newton import ClampingPerformanceEnvelope

    with pytest.raises(InputError, match=message):
        ClampingPerformanceEnvelope.resolve_arguments(args)


def test_explicit_clamp_matches_reference() -> None:
    """Clamp at the measured velocity exactly as the core clamp_effort does."""
    env = de.PerformanceEnvelope(
        max_effort=5.0,
        max_actuator_velocity=4.0,
        velocity_dependent_resistance=0.3,
        speed_effort_gradient=0.5,
    )
    rng = np.random.default_rng(11)
    effort = rng.normal(0.0, 6.0, 2000).astype(np.float32)
    velocity = rng.normal(0.0, 4.0, 2000).astype(np.float32)
    result = _modify(_clamp(env, 2000), effort, velocity)
    expected = de.clamp_effort(env, effort.astype(np.float64), velocity.astype(np.float64))
    np.testing.assert_allclose(result, expected, rtol=1e-5, atol=1e-5 * env.max_effort)


def test_matches_dc_motor_when_driving_and_not_when_braking() -> None:
    """Agree with ClampingDCMotor in the driving quadrants; allow less braking effort at speed."""
    from newton.actuators import ClampingDCMotor

    sat, v_lim, max_e = 4.0, 10.0, 3.0
    env = de.PerformanceEnvelope(
        max_effort=max_e, max_actuator_velocity=v_lim, speed_effort_gradient=v_lim / sat
    )
    velocity = np.linspace(-9.5, 9.5, 39).astype(np.float32)
    request = np.where(velocity >= 0.0, 50.0, -50.0).astype(np.float32)  # effort along the motion
    dc = ClampingDCMotor(
        saturation_effort=_f32([sat] * 39),
        velocity_limit=_f32([v_lim] * 39),
        max_motor_effort=_f32([max_e] * 39),
    )
    ours = _clamp(env, 39)
    np.testing.assert_allclose(
        _modify(ours, request, velocity), _modify(dc, request, velocity), rtol=1e-6, atol=1e-6
    )
    braking = -request
    ours_brake = np.abs(_modify(ours, braking, velocity))
    dc_brake = np.abs(_modify(dc, braking, velocity))
    np.testing.assert_allclose(dc_brake, max_e)  # DC braking stays at the cap at any speed
    assert np.all(ours_brake <= dc_brake)
    beyond_corner = np.abs(velocity) > v_lim * (1.0 - max_e / sat)  # where the speed line binds
    assert np.all(ours_brake[beyond_corner] < dc_brake[beyond_corner])  # the envelope's shrinks


def _model(envelope: dict[str, float], kd: float) -> Any:
    import newton
    import warp as wp
    from newton.actuators import DrivePD

    from drive_envelope.newton import ClampingPerformanceEnvelope

    builder = newton.ModelBuilder(gravity=(0.0, 0.0, 0.0))
    inertia = wp.mat33(INERTIA, 0.0, 0.0, 0.0, INERTIA, 0.0, 0.0, 0.0, INERTIA)
    link = builder.add_link(inertia=inertia, mass=1.0)
    joint = builder.add_joint_revolute(parent=-1, child=link, axis=newton.Axis.Z)
    builder.add_articulation([joint])
    builder.add_actuator(DrivePD, index=0, kp=0.0, kd=kd, clamping=[(ClampingPerformanceEnvelope, envelope)])
    return builder.finalize(device="cpu")


ENVELOPE = {
    "max_effort": 2.0,
    "max_actuator_velocity": 12.0,
    "velocity_dependent_resistance": 0.05,
    "speed_effort_gradient": 1.5,
}


def _step(implicit: bool, velocity: float, target_velocity: float, dt: float) -> tuple[float, float]:
    """One actuator step from ``velocity``; returns (effort [N*m], response A [1/(kg*m^2)])."""
    from newton.actuators import Actuator, JointSpaceResponse

    model = _model(ENVELOPE, kd=5.0)
    actuator = model.actuators[0]
    response = JointSpaceResponse(model)
    if implicit:
        options = Actuator.ImplicitOptions(residual_tol=1e-9, update_tol=1e-9)
        actuator.set_effort_mode_implicit(response=response, options=options)
    state, control = model.state(), model.control()
    state.joint_qd.assign(np.array([velocity], dtype=np.float32))
    control.joint_target_qd.assign(np.array([target_velocity], dtype=np.float32))
    control.joint_f.zero_()
    response.refresh(state)
    actuator.step(state, control, dt=dt)
    return float(control.joint_f.numpy()[0]), float(response.inverse_blocks.numpy()[0, 0, 0])


def test_builder_explicit_mode_gives_clamped_pd_effort() -> None:
    """Apply the PD law clamped by the envelope at the measured velocity through add_actuator."""
    effort, _ = _step(implicit=False, velocity=6.0, target_velocity=100.0, dt=0.01)
    env = de.PerformanceEnvelope(**ENVELOPE)
    assert effort == pytest.approx(
        float(de.clamp_effort(env, np.array([5.0 * 94.0]), np.array([6.0]))[0]), rel=1e-5
    )


@pytest.mark.slow
@pytest.mark.parametrize("velocity", [0.0, 6.0, 11.9, -4.0, 13.0])
def test_implicit_mode_matches_physx_clamp(velocity: float) -> None:
    """Reproduce PhysX's implicit clamp of a saturated request, letting go above the speed limit."""
    dt = 0.02
    effort, response = _step(implicit=True, velocity=velocity, target_velocity=100.0, dt=dt)
    assert response == pytest.approx(1.0 / INERTIA, rel=1e-4)
    env = de.PerformanceEnvelope(**ENVELOPE)
    expected = de.clamp_effort_implicit(
        env, np.array([1.0e4]), np.array([velocity]), np.array([response]), dt
    )[0]
    assert effort == pytest.approx(float(expected), rel=1e-4, abs=1e-5)
    if velocity > ENVELOPE["max_actuator_velocity"]:
        assert effort == 0.0


def test_implicit_entry_point_is_the_shared_effort_clamp() -> None:
    """Evaluate evaluate_clamp in float64 with the shared clamp_effort_func: the core's numbers, NaN -> 0."""
    import warp as wp

    from drive_envelope.newton import ClampingPerformanceEnvelope

    evaluate = ClampingPerformanceEnvelope.evaluate_clamp

    @wp.kernel
    def entry_point(
        value: wp.array(dtype=wp.float64),
        qd: wp.array(dtype=wp.float64),
        params: wp.array2d(dtype=wp.float32),
        out: wp.array(dtype=wp.float64),
    ):
        i = wp.tid()
        out[i] = evaluate(value[i], wp.float64(0.0), qd[i], params, 0, 0)

    env = de.PerformanceEnvelope(
        max_effort=5.0,
        max_actuator_velocity=4.0,
        velocity_dependent_resistance=0.25,
        speed_effort_gradient=0.5,
    )
    rng = np.random.default_rng(5)
    value = np.append(rng.normal(0.0, 6.0, 500), [np.nan, 1.0])
    qd = np.append(rng.normal(0.0, 4.0, 500), [0.0, np.nan])
    row = [
        env.max_effort,
        env.max_actuator_velocity,
        env.velocity_dependent_resistance,
        env.speed_effort_gradient,
    ]
    params = wp.array(np.array([row], dtype=np.float32), dtype=wp.float32, device="cpu")
    out = wp.zeros(len(value), dtype=wp.float64, device="cpu")
    inputs = [wp.array(value, dtype=wp.float64, device="cpu"), wp.array(qd, dtype=wp.float64, device="cpu")]
    wp.launch(entry_point, dim=len(value), inputs=[*inputs, params], outputs=[out], device="cpu")
    np.testing.assert_array_equal(out.numpy(), de.clamp_effort(env, value, qd))
    assert out.numpy()[-2:].tolist() == [0.0, 0.0]  # a NaN effort or velocity lets the drive go

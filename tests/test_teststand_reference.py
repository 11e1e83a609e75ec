"""Closed-form checks of the reference engine (the float64 model of the PhysX articulation solver).

Every expected value here is computed by hand from the envelope equations and PhysX's implicit
clamp, not by the engine's own code path.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drive_envelope import PerformanceEnvelope, implicit_drive_effort
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.spec import Scenario, scenario_from_mapping
from drive_envelope._src.teststand.engines.reference import simulate, step

DT = 0.01


def make(
    *,
    solver: str = "pgs",
    inertia: float = 0.5,
    drive: dict[str, Any] | None = None,
    envelope: dict[str, Any] | None = None,
    load: dict[str, Any] | None = None,
    duration: float = 0.2,
    dt: float = DT,
    position_iterations: int = 4,
    velocity_iterations: int = 1,
    initial_velocity: float = 0.0,
    initial_position: float = 0.0,
) -> Scenario:
    data: dict[str, Any] = {
        "joint": {
            "inertia": inertia,
            "initial_velocity": initial_velocity,
            "initial_position": initial_position,
        },
        "drive": drive
        if drive is not None
        else {"damping": 1000.0, "target_velocity": 100.0, "max_effort": 10.0},
        "simulation": {
            "dt": dt,
            "duration": duration,
            "solver": solver,
            "position_iterations": position_iterations,
            "velocity_iterations": velocity_iterations,
        },
    }
    if envelope is not None:
        data["envelope"] = envelope
    if load is not None:
        data["load"] = load
    return scenario_from_mapping(data)


SOLVERS = [("pgs", 1), ("pgs", 0), ("tgs", 1), ("tgs", 3)]


@pytest.mark.parametrize(("solver", "vel_iters"), SOLVERS)
def test_first_step_effort_from_rest_is_max_effort_over_one_plus_r_dt_over_inertia(
    solver: str, vel_iters: int
) -> None:
    """From rest with resistance R only eq. 1 binds: effort = max_effort / (1 + R*dt/inertia)."""
    inertia, resistance = 0.5, 1.1459
    scenario = make(
        solver=solver,
        velocity_iterations=vel_iters,
        inertia=inertia,
        envelope={"max_actuator_velocity": 100.0, "velocity_dependent_resistance": resistance},
        duration=DT,
    )
    trajectory = simulate(scenario)
    expected = 10.0 / (1.0 + resistance * DT / inertia)
    assert trajectory.effort[1] == pytest.approx(expected, rel=1e-12)
    assert trajectory.velocity[1] == pytest.approx(expected * DT / inertia, rel=1e-12)


def test_tgs_without_velocity_iterations_clamps_per_substep() -> None:
    """TGS with 0 velocity iterations sums N per-substep clamps: X_N = (E/(R r)) (1 - (1 + R s r)^-N)."""
    inertia, resistance, substeps = 0.5, 1.1459, 4
    scenario = make(
        solver="tgs",
        velocity_iterations=0,
        position_iterations=substeps,
        inertia=inertia,
        envelope={"max_actuator_velocity": 100.0, "velocity_dependent_resistance": resistance},
        duration=DT,
    )
    r, s = 1.0 / inertia, DT / substeps
    c = resistance * s * r
    impulse = 10.0 / (resistance * r) * (1.0 - (1.0 + c) ** -substeps)
    effort = simulate(scenario).effort[1]
    assert effort == pytest.approx(impulse / DT, rel=1e-12)
    assert effort > 10.0 / (1.0 + resistance * DT / inertia)  # more than the whole-step limit (PGS)


@pytest.mark.parametrize(("solver", "vel_iters"), SOLVERS)
def test_velocity_settles_exactly_on_max_actuator_velocity(solver: str, vel_iters: int) -> None:
    """A drive asking for 100 rad/s reaches max_actuator_velocity = 3 exactly and never exceeds it."""
    scenario = make(
        solver=solver, velocity_iterations=vel_iters, inertia=0.05, envelope={"max_actuator_velocity": 3.0}
    )
    trajectory = simulate(scenario)
    assert np.all(trajectory.velocity <= 3.0 + 1e-12)
    assert trajectory.velocity[-1] == pytest.approx(3.0, abs=1e-12)
    assert trajectory.effort[-1] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize(("solver", "vel_iters"), [("pgs", 1), ("tgs", 1), ("tgs", 0)])
def test_steady_state_under_constant_load_sits_on_eq2(solver: str, vel_iters: int) -> None:
    """Against a constant load L: effort -> L and velocity -> max_actuator_velocity - G*L."""
    load, vmax, gradient = 4.0, 6.0, 0.3
    scenario = make(
        solver=solver,
        velocity_iterations=vel_iters,
        inertia=0.05,
        drive={"damping": 100.0, "target_velocity": 20.0, "max_effort": 10.0},
        envelope={
            "max_actuator_velocity": vmax,
            "velocity_dependent_resistance": 0.2,
            "speed_effort_gradient": gradient,
        },
        load={"external_effort": -load},
        duration=0.6,
    )
    trajectory = simulate(scenario)
    assert trajectory.velocity[-1] == pytest.approx(vmax - gradient * load, abs=1e-9)
    assert trajectory.effort[-1] == pytest.approx(load, abs=1e-9)


@pytest.mark.parametrize(("solver", "vel_iters"), [("pgs", 1), ("tgs", 1), ("tgs", 0)])
def test_braking_effort_is_limited_like_driving_effort(solver: str, vel_iters: int) -> None:
    """Braking from v0 with resistance R: PGS |effort| = (E - R v0) / (1 - R r dt); less at higher speed.

    TGS clamps each substep at its own (falling) speed: x_k = s (E - R v0) (1 - R r s)^-k, summed over
    the N substeps; the velocity iteration's whole-step bound does not bind because it is larger.
    """
    inertia, resistance, substeps = 0.05, 1.0, 4
    r, s = 1.0 / inertia, DT / substeps

    def first_effort(v0: float) -> float:
        scenario = make(
            solver=solver,
            velocity_iterations=vel_iters,
            position_iterations=substeps,
            inertia=inertia,
            initial_velocity=v0,
            drive={"damping": 1000.0, "target_velocity": 0.0, "max_effort": 10.0},
            envelope={"max_actuator_velocity": 100.0, "velocity_dependent_resistance": resistance},
            duration=DT,
        )
        return float(simulate(scenario).effort[1])

    for v0 in (3.0, 6.0):
        if solver == "pgs":
            expected = (10.0 - resistance * v0) / (1.0 - resistance * r * DT)
        else:
            c = resistance * r * s
            expected = (
                s * (10.0 - resistance * v0) * sum((1.0 - c) ** -k for k in range(1, substeps + 1)) / DT
            )
        assert first_effort(v0) == pytest.approx(-expected, rel=1e-12)
    assert abs(first_effort(6.0)) < abs(first_effort(3.0)) < 10.0


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
def test_external_load_beyond_envelope_makes_the_drive_let_go(solver: str) -> None:
    """Above max_actuator_velocity with a load pushing on, effort is exactly 0 and the joint runs away."""
    inertia, push, v0 = 0.05, 1.0, 8.0
    scenario = make(
        solver=solver,
        inertia=inertia,
        initial_velocity=v0,
        drive={"damping": 100.0, "target_velocity": 0.0, "max_effort": 10.0},
        envelope={"max_actuator_velocity": 6.0, "velocity_dependent_resistance": 0.2},
        load={"external_effort": push},
        duration=0.2,
    )
    trajectory = simulate(scenario)
    assert np.all(trajectory.effort == 0.0)
    np.testing.assert_allclose(trajectory.velocity, v0 + trajectory.time * push / inertia, rtol=1e-12)


def test_plain_drive_limits_drive_plus_applied_effort_together() -> None:
    """No [envelope]: drive + applied effort stay within +-max_effort; the drive cancels the excess."""
    scenario = make(
        inertia=0.05,
        drive={"stiffness": 100.0, "damping": 10.0, "target_position": 1.0, "max_effort": 10.0},
        load={"applied_effort": 15.0},
        duration=0.03,
    )
    trajectory = simulate(scenario)
    np.testing.assert_allclose(trajectory.effort[1:], 10.0, rtol=1e-12)
    np.testing.assert_allclose(trajectory.velocity, trajectory.time * 10.0 / 0.05, rtol=1e-12)


@pytest.mark.parametrize(("solver", "vel_iters"), SOLVERS)
def test_applied_effort_plus_drive_stays_inside_the_envelope(solver: str, vel_iters: int) -> None:
    """Every (velocity, effort) step of a drive with an applied effort satisfies both envelope curves."""
    env = {"max_actuator_velocity": 6.0, "velocity_dependent_resistance": 0.5, "speed_effort_gradient": 0.2}
    scenario = make(
        solver=solver,
        velocity_iterations=vel_iters,
        inertia=0.05,
        drive={"stiffness": 50.0, "damping": 5.0, "target_position": 2.0, "max_effort": 10.0},
        envelope=env,
        load={"applied_effort": 6.0},
    )
    trajectory = simulate(scenario)
    envelope = PerformanceEnvelope(max_effort=10.0, **env)
    inside = envelope.contains(trajectory.velocity[1:], trajectory.effort[1:], atol=1e-9)
    if vel_iters == 0 and solver == "tgs":
        assert np.all(np.abs(trajectory.effort) <= 10.0 + 1e-9)  # per substep: eq. 1 cap still holds
    else:
        assert np.all(inside)
    assert np.max(trajectory.effort) > 6.0  # the drive did add effort


def test_zero_max_effort_turns_the_drive_off_and_leaves_applied_effort_unlimited() -> None:
    """max_effort = 0: the drive gives nothing and a 50 N*m applied effort acts in full."""
    scenario = make(
        inertia=0.5,
        drive={"stiffness": 100.0, "damping": 10.0, "target_position": -1.0, "max_effort": 0.0},
        load={"applied_effort": 50.0},
        duration=0.1,
    )
    trajectory = simulate(scenario)
    np.testing.assert_allclose(trajectory.effort[1:], 50.0, rtol=1e-12)
    np.testing.assert_allclose(trajectory.velocity, trajectory.time * 100.0, rtol=1e-12)


def test_unlimited_drive_step_equals_the_implicit_drive_law() -> None:
    """Without max_effort the first PGS step's effort is the unclamped implicit spring-damper effort."""
    drive = {"stiffness": 300.0, "damping": 20.0, "target_position": 1.0, "target_velocity": 0.5}
    scenario = make(inertia=0.2, drive=drive, duration=DT, initial_position=0.1, initial_velocity=-0.3)
    expected = implicit_drive_effort(
        stiffness=300.0,
        damping=20.0,
        position_error=0.9,
        velocity=-0.3,
        target_velocity=0.5,
        response=5.0,
        dt=DT,
    )
    assert simulate(scenario).effort[1] == pytest.approx(float(expected), rel=1e-12)


def test_pgs_positions_follow_semi_implicit_euler() -> None:
    """PGS integrates q1 = q0 + v1*dt with the end-of-step velocity."""
    scenario = make(
        inertia=0.05,
        drive={"stiffness": 200.0, "damping": 10.0, "target_position": 1.0, "max_effort": 10.0},
        envelope={
            "max_actuator_velocity": 6.0,
            "velocity_dependent_resistance": 0.5,
            "speed_effort_gradient": 0.2,
        },
    )
    t = simulate(scenario)
    np.testing.assert_allclose(t.position[1:], t.position[:-1] + t.velocity[1:] * DT, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("substeps", [1, 4, 7])
def test_tgs_positions_integrate_per_substep(substeps: int) -> None:
    """TGS with a constant effort F: q1 = q0 + s*(N*v0 + r*F*s*N*(N+1)/2) with s = dt/N; PGS differs."""
    v0, effort, inertia = 0.3, 2.0, 0.5
    r, s = 1.0 / inertia, DT / substeps
    common = {
        "inertia": inertia,
        "initial_velocity": v0,
        "drive": {"max_effort": 0.0},
        "load": {"external_effort": effort},
    }
    tgs = step(make(solver="tgs", position_iterations=substeps, **common), 0.0, v0)  # type: ignore[arg-type]
    pgs = step(make(solver="pgs", position_iterations=substeps, **common), 0.0, v0)  # type: ignore[arg-type]
    n = substeps
    assert tgs.position == pytest.approx(s * (n * v0 + r * effort * s * n * (n + 1) / 2), rel=1e-13)
    assert pgs.position == pytest.approx(DT * (v0 + r * effort * DT), rel=1e-13)
    assert tgs.velocity == pytest.approx(pgs.velocity, rel=1e-13)


def test_acceleration_drive_equals_force_drive_with_gains_times_inertia() -> None:
    """An acceleration drive behaves as a force drive whose gains are multiplied by the inertia."""
    inertia = 0.25
    env = {"max_actuator_velocity": 6.0, "velocity_dependent_resistance": 0.5, "speed_effort_gradient": 0.2}
    for solver in ("pgs", "tgs"):
        accel = make(
            solver=solver,
            inertia=inertia,
            drive={
                "type": "acceleration",
                "stiffness": 400.0,
                "damping": 40.0,
                "target_position": 1.0,
                "max_effort": 10.0,
            },
            envelope=env,
        )
        force = make(
            solver=solver,
            inertia=inertia,
            drive={"stiffness": 100.0, "damping": 10.0, "target_position": 1.0, "max_effort": 10.0},
            envelope=env,
        )
        a, f = simulate(accel), simulate(force)
        np.testing.assert_allclose(a.velocity, f.velocity, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(a.effort, f.effort, rtol=1e-10, atol=1e-12)


def test_pgs_and_tgs_differ_only_where_substeps_matter() -> None:
    """With velocity iterations the first step from rest agrees; the trajectories then differ (positions)."""
    env = {"max_actuator_velocity": 6.0, "velocity_dependent_resistance": 0.5, "speed_effort_gradient": 0.2}
    drive = {"stiffness": 200.0, "damping": 10.0, "target_position": 1.0, "max_effort": 10.0}
    pgs = simulate(make(solver="pgs", inertia=0.05, drive=drive, envelope=env, duration=1.0))
    tgs = simulate(make(solver="tgs", inertia=0.05, drive=drive, envelope=env, duration=1.0))
    assert pgs.effort[1] == pytest.approx(tgs.effort[1], rel=1e-12)  # both clamped to the same bound
    assert not np.allclose(pgs.position, tgs.position)
    assert pgs.position[-1] == pytest.approx(1.0, abs=1e-3)
    assert tgs.position[-1] == pytest.approx(1.0, abs=1e-3)


def test_prismatic_joint_uses_the_same_laws_in_newtons_and_metres() -> None:
    """A prismatic joint with mass m reaches the same first-step closed form in N and m/s."""
    scenario = scenario_from_mapping(
        {
            "joint": {"type": "prismatic", "inertia": "2 kg"},
            "drive": {"damping": "1e5 N*s/m", "target_velocity": "10 m/s", "max_effort": "200 N"},
            "envelope": {"max_actuator_velocity": "5 m/s", "velocity_dependent_resistance": "50 N*s/m"},
            "simulation": {"dt": DT, "duration": DT, "solver": "pgs"},
        }
    )
    trajectory = simulate(scenario)
    assert trajectory.joint == "prismatic"
    assert trajectory.effort[1] == pytest.approx(200.0 / (1.0 + 50.0 * DT / 2.0), rel=1e-12)


def test_row_zero_is_the_initial_state() -> None:
    """Row 0 holds the initial position and velocity with effort 0; one row per step follows."""
    scenario = make(initial_position=0.25, initial_velocity=-0.5, duration=0.1)
    trajectory = simulate(scenario)
    assert len(trajectory) == 11
    assert (trajectory.time[0], trajectory.position[0], trajectory.velocity[0], trajectory.effort[0]) == (
        0.0,
        0.25,
        -0.5,
        0.0,
    )
    assert trajectory.time[-1] == pytest.approx(0.1)


@settings(max_examples=40, deadline=None)
@given(
    inertia=st.floats(0.01, 5.0),
    max_effort=st.floats(0.5, 50.0),
    vmax=st.floats(0.5, 20.0),
    # no subnormals: 1/R overflows in the core clamp (PhysX's float32 flushes them to 0 anyway)
    resistance=st.one_of(st.just(0.0), st.floats(1e-6, 2.0)),
    gradient=st.one_of(st.just(0.0), st.floats(1e-6, 0.5)),
    target=st.floats(-20.0, 20.0),
    solver=st.sampled_from(["pgs", "tgs"]),
    applied=st.floats(-20.0, 20.0),
)
def test_every_step_from_rest_stays_inside_the_envelope(
    inertia: float,
    max_effort: float,
    vmax: float,
    resistance: float,
    gradient: float,
    target: float,
    solver: str,
    applied: float,
) -> None:
    """Without an external load every step's (velocity, total effort) satisfies both curves."""
    env = {
        "max_actuator_velocity": vmax,
        "velocity_dependent_resistance": resistance,
        "speed_effort_gradient": gradient,
    }
    scenario = make(
        solver=solver,
        inertia=inertia,
        drive={"stiffness": 50.0, "damping": 20.0, "target_position": target, "max_effort": max_effort},
        envelope=env,
        load={"applied_effort": applied},
        duration=0.1,
    )
    trajectory = simulate(scenario)
    envelope = PerformanceEnvelope(max_effort=max_effort, **env)
    scale = max(1.0, max_effort, vmax)
    assert np.all(envelope.contains(trajectory.velocity, trajectory.effort, atol=1e-9 * scale))
    assert np.all(np.isfinite(trajectory.effort))
    assert not math.isnan(float(trajectory.position[-1]))


def test_an_overflow_names_the_step_it_happened_in() -> None:
    """One InputError line naming the first step (PGS) whose state overflows float64."""
    free = {"stiffness": 1.0, "max_effort": 0.0}  # the drive off: the load alone moves the joint
    # v grows by 1e305 / 2e-3 * 0.005 = 2.5e305 a step, q after n steps by n*(n+1)/2 * 0.005 * 2.5e305:
    # beyond float64's 1.798e308 after 536 steps, so in the step from t = 535 * 0.005 s
    late = make(inertia=2e-3, drive=free, load={"external_effort": 1e305}, dt=0.005, duration=5.0)
    message = r"joint state \(position, velocity, effort\) overflowed float64 in the step from t = 2\.675 s"
    with pytest.raises(InputError, match=message):
        simulate(late)


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
def test_an_overflowing_drive_law_or_request_is_refused(solver: str) -> None:
    """The law of a drive that is off, and an infinite request whose clamp would be finite."""
    law = make(solver=solver, drive={"damping": 1e308, "target_velocity": 5.0, "max_effort": 0.0})
    with pytest.raises(InputError, match=r"implicit drive law .* from t = 0 s"):
        step(law, 0.0, 0.0)  # dt * damping * target_velocity is inf
    request = make(solver=solver, inertia=1e-10, load={"external_effort": 1e308})
    with pytest.raises(
        InputError, match=r"the drive's impulse request overflowed float64 in the step from t = 0 s"
    ):
        simulate(request)

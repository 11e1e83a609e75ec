"""The ``reference`` engine: a float64 NumPy model of the PhysX articulation solver for one DOF.

This is the executable specification of the test stand. It follows PhysX 5.6+ line by line for a
single joint on a fixed base (``physx/source/lowleveldynamics``):

* drive parameters: ``computeImplicitDriveParams`` (``shared/DyCpuGpuArticulation.h``), set up once
  per step from the position error at the start of the step; TGS uses the substep ``stepDt`` for the
  spring and ``dt`` for the target-velocity offset;
* each solver iteration runs the drive block of ``solveInternalJointConstraintRecursive``
  (``src/DyFeatherstoneArticulation.cpp``): ``computeDriveImpulse`` with the accumulated impulse, the
  joint's delta position and the elapsed time, then ``clampDriveImpulse`` on the TOTAL actuator
  impulse (drive + applied joint effort), or the legacy ``+-maxForce`` clamp when ``maxEffort = 0``;
* PGS (``DySolverCore.cpp``): applied and external efforts enter the velocity once over ``dt``; the
  drive is recomputed and clamped every position and velocity iteration; the joint position
  integrates with the velocity after the position iterations, ``q1 = q0 + v*dt``;
* TGS with external forces every substep (``DyTGSDynamics.cpp``, as PhysX runs through USD): each
  position iteration is a substep that applies the efforts over ``stepDt``, clamps the substep's
  drive impulse per step (``isPerStep``: budget ``maxEffort*stepDt``) and integrates the position;
  each velocity iteration re-clamps the whole-step total at the current velocity without a new
  drive request.

Response ``r = 1/inertia`` (one link on a fixed base). Everything is float64; PhysX computes in
float32, so results agree to float32 precision, not bit for bit. A drive law, drive request or state
that overflows float64 (absurd gains, loads or inertias) stops the run with one :class:`InputError`
line naming the time: a clamp fed an infinite request would otherwise give a finite, wrong effort.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np

from drive_envelope._src.envelope.clamp import clamp_drive_impulse
from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

__all__ = [
    "ImplicitDriveDesc",
    "JointState",
    "compute_drive_impulse",
    "implicit_drive_desc",
    "simulate",
    "step",
]

_PROGRESS_EVERY = 4096  # steps between progress reports


class _Overflow(ArithmeticError):
    """A drive quantity overflowed float64 (the message names which)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class ImplicitDriveDesc:
    """PhysX ``ArticulationImplicitDriveDesc``: the linear law of the implicit drive for one step.

    The unclamped drive impulse is ``accumulated*impulse_multiplier + v*vel_multiplier +
    target_vel_plus_initial_bias - delta_position*bias_coefficient + elapsed*target_pos_bias``
    [N*m*s or N*s].
    """

    target_vel_plus_initial_bias: float
    """Constant term: damping toward the target velocity plus the initial spring error [N*m*s or N*s]."""
    bias_coefficient: float
    """Impulse per unit joint displacement within the step [N*m*s/rad or N*s/m]."""
    vel_multiplier: float
    """Impulse per unit joint velocity (negative) [N*m*s/(rad/s) or N*s/(m/s)]."""
    impulse_multiplier: float
    """Weight of the impulse accumulated so far: ``1 - x`` for PGS, 1 for TGS [-]."""
    target_pos_bias: float
    """Impulse per second of elapsed time (TGS: the target moves with the target velocity) [N*m or N]."""


def implicit_drive_desc(
    *,
    drive_type: DriveType,
    stiffness: float,
    damping: float,
    dt: float,
    sim_dt: float,
    response: float,
    geom_error: float,
    target_velocity: float,
    is_tgs: bool,
) -> ImplicitDriveDesc:
    """Port of PhysX ``computeImplicitDriveParams`` (force and acceleration drives).

    Args:
        drive_type: ``"force"`` or ``"acceleration"``.
        stiffness: Drive stiffness [N*m/rad or N/m] (force) or [1/s^2] (acceleration).
        damping: Drive damping [N*m*s/rad or N*s/m] (force) or [1/s] (acceleration).
        dt: Step over which the spring is integrated: the substep for TGS, the step for PGS [s].
        sim_dt: The simulation step [s].
        response: Joint velocity change per unit impulse, ``1/inertia`` [rad/s/(N*m*s) or m/s/(N*s)].
        geom_error: ``target_position - position`` at the start of the step [rad or m].
        target_velocity: Drive target velocity [rad/s or m/s].
        is_tgs: Whether the TGS solver runs the drive.
    """
    a = dt * (dt * stiffness + damping)
    b = dt * (damping * target_velocity)
    initial_bias = geom_error - (sim_dt - dt) * target_velocity  # equals geom_error for PGS
    if drive_type == "force":
        x = 1.0 / (1.0 + a * response) if response > 0.0 else 0.0
        scale = 1.0
    else:
        x = 1.0 / (1.0 + a)
        scale = 1.0 / response  # PhysX's recipResponse: the gains act per unit inertia
    bias_coefficient = stiffness * x * scale * dt
    return ImplicitDriveDesc(
        target_vel_plus_initial_bias=x * b * scale + bias_coefficient * initial_bias,
        bias_coefficient=bias_coefficient,
        vel_multiplier=-x * a * scale,
        impulse_multiplier=1.0 if is_tgs else 1.0 - x,
        target_pos_bias=bias_coefficient * target_velocity if is_tgs else 0.0,
    )


def compute_drive_impulse(
    desc: ImplicitDriveDesc, accumulated: float, joint_velocity: float, delta_position: float, elapsed: float
) -> float:
    """Port of PhysX ``computeDriveImpulse``: the unclamped drive impulse [N*m*s or N*s].

    Args:
        desc: The step's drive law.
        accumulated: Drive impulse accumulated this step [N*m*s or N*s].
        joint_velocity: Current joint velocity [rad/s or m/s].
        delta_position: Joint displacement since the start of the step (TGS; 0 for PGS) [rad or m].
        elapsed: Time elapsed in the step (TGS; 0 for PGS) [s].
    """
    return (
        accumulated * desc.impulse_multiplier
        + joint_velocity * desc.vel_multiplier
        + desc.target_vel_plus_initial_bias
        - delta_position * desc.bias_coefficient
        + elapsed * desc.target_pos_bias
    )


@dataclass(frozen=True, kw_only=True, slots=True)
class JointState:
    """The joint at the end of a step and the step's actuator effort."""

    position: float
    """Joint position [rad or m]."""
    velocity: float
    """Joint velocity [rad/s or m/s]."""
    effort: float
    """Step-average total actuator effort: accumulated drive impulse / dt + applied effort [N*m or N]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class _Setup:
    """Constants of one run, taken from the scenario once."""

    scenario: Scenario
    response: float
    envelope: PerformanceEnvelope | None  # None: the envelope branch without limits (maxForce = inf)
    drive_off: bool  # maxEffort = 0: PhysX's legacy branch clamps the drive to +-0


def _clamp_total(
    setup: _Setup, velocity: float, applied0: float, request: float, external: float, timestep: float
) -> float:
    """``clampDriveImpulse`` on the total actuator impulse, minus the applied joint impulse."""
    env = setup.envelope
    if env is None:
        return request
    total = clamp_drive_impulse(
        velocity,
        applied0 + external,
        request + external,
        setup.response,
        env.max_actuator_velocity,
        env.max_effort * timestep,
        env.speed_effort_gradient / timestep,
        env.velocity_dependent_resistance * timestep,
    )
    return float(total) - external


def _solve_drive(
    setup: _Setup,
    velocity: float,
    drive_impulse: float,
    desc: ImplicitDriveDesc,
    *,
    delta_position: float,
    elapsed: float,
    timestep: float,
    per_step: bool,
    tgs_velocity_iteration: bool,
) -> tuple[float, float]:
    """One pass of the drive block; returns the new joint velocity and accumulated drive impulse."""
    if setup.drive_off:
        return velocity, drive_impulse
    applied0 = 0.0 if per_step else drive_impulse
    if tgs_velocity_iteration:
        request = applied0  # TGS velocity iterations only re-clamp what the substeps applied
    else:
        request = compute_drive_impulse(desc, applied0, velocity, delta_position, elapsed)
        if not math.isfinite(request):
            raise _Overflow("the drive's impulse request")
    external = setup.scenario.load.applied_effort * timestep
    clamped = _clamp_total(setup, velocity, applied0, request, external, timestep)
    delta = clamped - applied0
    return velocity + delta * setup.response, drive_impulse + delta


def _desc(setup: _Setup, position: float, dt: float, sim_dt: float, is_tgs: bool) -> ImplicitDriveDesc:
    drive = setup.scenario.drive
    desc = implicit_drive_desc(
        drive_type=drive.type,
        stiffness=drive.stiffness,
        damping=drive.damping,
        dt=dt,
        sim_dt=sim_dt,
        response=setup.response,
        geom_error=drive.target_position - position,
        target_velocity=drive.target_velocity,
        is_tgs=is_tgs,
    )
    if not all(math.isfinite(getattr(desc, f.name)) for f in fields(desc)):
        raise _Overflow("the implicit drive law (drive.stiffness, drive.damping and the targets)")
    return desc


def _pgs_step(setup: _Setup, position: float, velocity: float) -> JointState:
    sim, load = setup.scenario.simulation, setup.scenario.load
    dt = sim.dt
    # computeUnconstrainedVelocities: joint force and external load act once over the whole step
    velocity += setup.response * (load.applied_effort + load.external_effort) * dt
    desc = _desc(setup, position, dt, dt, is_tgs=False)
    impulse = 0.0
    for _ in range(sim.position_iterations):
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=0.0, elapsed=0.0, timestep=dt,
            per_step=False, tgs_velocity_iteration=False,
        )  # fmt: skip
    position_velocity = velocity  # PGS integrates positions with the position-iteration velocity
    for _ in range(sim.velocity_iterations):
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=0.0, elapsed=0.0, timestep=dt,
            per_step=False, tgs_velocity_iteration=False,
        )  # fmt: skip
    return JointState(
        position=position + position_velocity * dt,
        velocity=velocity,
        effort=impulse / dt + load.applied_effort,
    )


def _tgs_step(setup: _Setup, position: float, velocity: float) -> JointState:
    sim, load = setup.scenario.simulation, setup.scenario.load
    dt = sim.dt
    step_dt = dt / sim.position_iterations
    desc = _desc(setup, position, step_dt, dt, is_tgs=True)
    impulse, delta_position, elapsed = 0.0, 0.0, 0.0
    for _ in range(sim.position_iterations):
        # applyTgsSubstepForces: joint force and external load act over each substep
        velocity += setup.response * (load.applied_effort + load.external_effort) * step_dt
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=delta_position, elapsed=elapsed,
            timestep=step_dt, per_step=True, tgs_velocity_iteration=False,
        )  # fmt: skip
        delta_position += velocity * step_dt  # updateDeltaMotion
        elapsed += step_dt
    for _ in range(sim.velocity_iterations):
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=delta_position, elapsed=elapsed,
            timestep=dt, per_step=False, tgs_velocity_iteration=True,
        )  # fmt: skip
    return JointState(
        position=position + delta_position,
        velocity=velocity,
        effort=impulse / dt + load.applied_effort,
    )


def _setup(scenario: Scenario) -> _Setup:
    max_effort = scenario.drive.max_effort
    return _Setup(
        scenario=scenario,
        response=1.0 / scenario.joint.inertia,
        envelope=scenario.effective_envelope(),
        drive_off=max_effort == 0.0,
    )


def step(scenario: Scenario, position: float, velocity: float) -> JointState:
    """Advance the scenario's joint by one time step from ``(position, velocity)``.

    Args:
        scenario: The scenario (drive, envelope, load, solver settings).
        position: Joint position at the start of the step [rad or m].
        velocity: Joint velocity at the start of the step [rad/s or m/s].

    Returns:
        The state at the end of the step and the step's total actuator effort.

    Raises:
        InputError: a drive quantity or the state overflows float64.
    """
    setup = _setup(scenario)
    advance = _tgs_step if scenario.simulation.solver == "tgs" else _pgs_step
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # the state is checked finite
        return _advance(scenario, setup, advance, float(position), float(velocity), 0.0)


def _advance(
    scenario: Scenario,
    setup: _Setup,
    advance: Callable[[_Setup, float, float], JointState],
    position: float,
    velocity: float,
    time: float,
) -> JointState:
    """One step, with every overflow turned into one line naming the time [s]."""
    try:
        state = advance(setup, position, velocity)
    except (_Overflow, ZeroDivisionError, OverflowError) as exc:
        what = str(exc) if isinstance(exc, _Overflow) else "a drive quantity"
        raise _overflow_error(scenario, what, time) from None
    # the implicit drive is unconditionally stable: only absurd inputs overflow float64
    if not all(math.isfinite(value) for value in (state.position, state.velocity, state.effort)):
        raise _overflow_error(scenario, "the joint state (position, velocity, effort)", time)
    return state


def _overflow_error(scenario: Scenario, what: str, time: float) -> InputError:
    return InputError(
        f"scenario {scenario.name or ''!r}: {what} overflowed float64 in the step from t = {time:g} s; "
        "expected values whose products stay finite (check joint.inertia, the drive gains, targets and loads)"
    )


def simulate(scenario: Scenario, *, progress: Callable[[int, int], None] | None = None) -> Trajectory:
    """Run the whole scenario with the reference model.

    Args:
        scenario: The scenario.
        progress: Called as ``progress(done, total)`` every few thousand steps and at the end.

    Returns:
        ``steps + 1`` rows: the initial state (effort 0) and the state after each step.

    Raises:
        InputError: a drive quantity or the state overflows float64.
    """
    setup = _setup(scenario)
    sim = scenario.simulation
    advance = _tgs_step if sim.solver == "tgs" else _pgs_step
    count = sim.steps
    time = np.arange(count + 1, dtype=np.float64) * sim.dt
    position = np.empty(count + 1)
    velocity = np.empty(count + 1)
    effort = np.zeros(count + 1)
    position[0], velocity[0] = scenario.joint.initial_position, scenario.joint.initial_velocity
    # every state is checked finite, so NumPy's overflow warnings would only repeat the error
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for i in range(count):
            state = _advance(scenario, setup, advance, float(position[i]), float(velocity[i]), float(time[i]))
            position[i + 1], velocity[i + 1], effort[i + 1] = state.position, state.velocity, state.effort
            if progress is not None and (i + 1) % _PROGRESS_EVERY == 0:
                progress(i + 1, count)
    if progress is not None:
        progress(count, count)
    return Trajectory(
        time=time,
        position=position,
        velocity=velocity,
        effort=effort,
        joint=scenario.joint.type,
        engine="reference",
        name=scenario.name,
        metadata=_metadata(scenario),
    )


def _metadata(scenario: Scenario) -> dict[str, object]:
    sim = scenario.simulation
    return {
        "solver": sim.solver,
        "dt": sim.dt,
        "position_iterations": sim.position_iterations,
        "velocity_iterations": sim.velocity_iterations,
        "precision": "float64",
    }

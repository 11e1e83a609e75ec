"""The ``reference`` engine: a float64 NumPy model of the PhysX articulation solver for one DOF.

This is the executable specification of the test stand. It follows PhysX 5.6+ line by line for a
single joint on a fixed base (``physx/source/lowleveldynamics``):

* drive parameters: ``computeImplicitDriveParams`` (``shared/DyCpuGpuArticulation.h``), set up once
  per step from the position error at the start of the step; TGS uses the substep ``stepDt`` for the
  spring and ``dt`` for the target-velocity offset;
* each solver iteration runs the per-DOF block of ``solveInternalJointConstraintRecursive``
  (``src/DyFeatherstoneArticulation.cpp``) in its order: the drive (``computeDriveImpulse`` with the
  accumulated impulse, the joint's delta position and the elapsed time, then ``clampDriveImpulse``
  on the TOTAL actuator impulse, drive + applied joint effort, or the legacy ``+-maxForce`` clamp
  when ``maxEffort = 0``), then joint friction (PhysX 5.6's model, ``computeFrictionImpulse``: the
  impulse that stops the joint, friction accumulated this step included, kept whole below
  ``staticFrictionEffort*dt`` and clipped to ``(dynamicFrictionEffort +
  viscousFrictionCoefficient*|v|)*dt`` above it, with ``v`` the velocity after the drive); each
  term's impulse changes the joint velocity before the next;
* PGS (``DySolverCore.cpp``): applied and external efforts and gravity enter the velocity once
  over ``dt``; drive and friction are recomputed every position and velocity iteration (their
  impulses accumulate over the step); the joint position integrates with the velocity after the
  position iterations, ``q1 = q0 + v*dt``; at least one velocity iteration runs (PhysX reports the
  velocity of one more sweep when 0 are configured);
* TGS with external forces every substep (``DyTGSDynamics.cpp``, as PhysX runs through USD): each
  position iteration is a substep that applies the efforts and gravity over ``stepDt``
  (``applyTgsSubstepForces``), clamps the substep's drive impulse per step (``isPerStep``: budget
  ``maxEffort*stepDt``), solves friction per substep (budgets ``*stepDt``, nothing accumulated) and
  integrates the position; each velocity iteration re-clamps the whole-step drive total at the
  current velocity without a new drive request, then solves friction against the whole step's
  accumulated friction impulse with budgets ``*dt``.

Gravity on a ``[pendulum]`` is an external effort evaluated at the start of the step
(``computeLinkStates`` forms the link's gravity force once per step; TGS applies that force every
substep). Its centripetal force is radial and adds nothing along a fixed revolute axis. Response
``r = 1/(inertia + armature + pendulum m*d^2)`` (one link on a fixed base; armature adds to the
joint-space inertia, ``computeArticulatedSpatialInertiaAndZ``). A :class:`DriveSchedule` gives
per-step targets and power state (an unpowered step has zero drive gains).

Everything is float64; PhysX computes in float32, so results agree to float32 precision, not bit
for bit. A drive law, drive request or state that overflows float64 (absurd gains, loads or
inertias) stops the run with one :class:`InputError` line naming the time: a clamp fed an infinite
request would otherwise give a finite, wrong effort.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np

from drive_envelope._src.envelope.clamp import clamp_drive_impulse
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.loads import FrictionSpec
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

# the engine protocol looks chain runs up on this module (teststand.engines.simulate)
from drive_envelope._src.teststand.engines.chain import simulate_chain as simulate_chain
from drive_envelope._src.teststand.engines.solver_terms import (
    ImplicitDriveDesc,
    compute_drive_impulse,
    compute_friction_impulse,
    implicit_drive_desc,
)

LOADS = ("pendulum", "friction", "armature")
"""The bench loads this engine represents (see :mod:`drive_envelope._src.teststand.engines`)."""

_PROGRESS_EVERY = 4096  # steps between progress reports


class _Overflow(ArithmeticError):
    """A drive quantity overflowed float64 (the message names which)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class JointState:
    """The joint at the end of a step and the step's actuator effort."""

    position: float
    """Joint position [rad or m]."""
    velocity: float
    """Joint velocity [rad/s or m/s]."""
    effort: float
    """Step-average total actuator effort: accumulated drive impulse / dt + applied effort [N*m or N]."""
    friction: float = 0.0
    """Step-average joint friction effort, friction impulse / dt [N*m or N]; not actuator effort."""


@dataclass(frozen=True, kw_only=True, slots=True)
class _Setup:
    """Constants of one run, taken from the scenario once."""

    scenario: Scenario
    response: float
    inertia: float  # PhysX's recipResponse (cfmScale 0)
    envelope: PerformanceEnvelope | None  # None: the envelope branch without limits (maxForce = inf)
    drive_off: bool  # maxEffort = 0: PhysX's legacy branch clamps the drive to +-0
    friction: FrictionSpec | None  # None: PhysX's friction model is off (static = viscous = 0)
    gravity: float  # m*g*d of the pendulum [N*m], 0 without one
    angle_offset: float  # pendulum angle offset [rad]


@dataclass(frozen=True, kw_only=True, slots=True)
class _Command:
    """The drive's targets and power state over one step."""

    target_position: float
    target_velocity: float
    enabled: bool


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


def _solve_friction(
    setup: _Setup, velocity: float, friction_impulse: float, *, timestep: float, per_step: bool
) -> tuple[float, float]:
    """PhysX 5.6's joint friction after the drive; returns the new velocity and accumulated friction."""
    friction = setup.friction
    if friction is None:
        return velocity, friction_impulse
    accumulated = 0.0 if per_step else friction_impulse
    total = compute_friction_impulse(
        accumulated - velocity * setup.inertia,
        friction.static_friction * timestep,
        friction.dynamic_friction * timestep,
        friction.viscous_friction * timestep,
        velocity,
    )
    delta = total - accumulated
    return velocity + delta * setup.response, friction_impulse + delta


def _external(setup: _Setup, position: float) -> float:
    """Efforts from outside the drive over the step: applied, external and gravity [N*m or N]."""
    load = setup.scenario.load
    gravity = -setup.gravity * math.sin(position + setup.angle_offset) if setup.gravity else 0.0
    return load.applied_effort + load.external_effort + gravity


def _desc(
    setup: _Setup, command: _Command, position: float, dt: float, sim_dt: float, is_tgs: bool
) -> ImplicitDriveDesc:
    drive = setup.scenario.drive
    desc = implicit_drive_desc(
        drive_type=drive.type,
        stiffness=drive.stiffness if command.enabled else 0.0,
        damping=drive.damping if command.enabled else 0.0,
        dt=dt,
        sim_dt=sim_dt,
        response=setup.response,
        geom_error=command.target_position - position,
        target_velocity=command.target_velocity,
        is_tgs=is_tgs,
    )
    if not all(math.isfinite(getattr(desc, f.name)) for f in fields(desc)):
        raise _Overflow("the implicit drive law (drive.stiffness, drive.damping and the targets)")
    return desc


def _pgs_step(setup: _Setup, command: _Command, position: float, velocity: float) -> JointState:
    sim, load = setup.scenario.simulation, setup.scenario.load
    dt = sim.dt
    # computeUnconstrainedVelocities: joint force, external load and gravity act once over the step
    velocity += setup.response * _external(setup, position) * dt
    desc = _desc(setup, command, position, dt, dt, is_tgs=False)
    impulse, friction = 0.0, 0.0
    for _ in range(sim.position_iterations):
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=0.0, elapsed=0.0, timestep=dt,
            per_step=False, tgs_velocity_iteration=False,
        )  # fmt: skip
        velocity, friction = _solve_friction(setup, velocity, friction, timestep=dt, per_step=False)
    position_velocity = velocity  # PGS integrates positions with the position-iteration velocity
    # PhysX runs at least one velocity sweep: with 0 velocity iterations configured the reported
    # velocity still comes from one more sweep (real PhysX, viscous friction: 0.00267 rad/s)
    for _ in range(max(1, sim.velocity_iterations)):
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=0.0, elapsed=0.0, timestep=dt,
            per_step=False, tgs_velocity_iteration=False,
        )  # fmt: skip
        velocity, friction = _solve_friction(setup, velocity, friction, timestep=dt, per_step=False)
    return JointState(
        position=position + position_velocity * dt,
        velocity=velocity,
        effort=impulse / dt + load.applied_effort,
        friction=friction / dt,
    )


def _tgs_step(setup: _Setup, command: _Command, position: float, velocity: float) -> JointState:
    sim, load = setup.scenario.simulation, setup.scenario.load
    dt = sim.dt
    step_dt = dt / sim.position_iterations
    desc = _desc(setup, command, position, step_dt, dt, is_tgs=True)
    external = _external(setup, position)  # gravity: the link's force from the start of the step
    impulse, friction, delta_position, elapsed = 0.0, 0.0, 0.0, 0.0
    for _ in range(sim.position_iterations):
        # applyTgsSubstepForces: joint force, external load and gravity act over each substep
        velocity += setup.response * external * step_dt
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=delta_position, elapsed=elapsed,
            timestep=step_dt, per_step=True, tgs_velocity_iteration=False,
        )  # fmt: skip
        velocity, friction = _solve_friction(setup, velocity, friction, timestep=step_dt, per_step=True)
        delta_position += velocity * step_dt  # updateDeltaMotion
        elapsed += step_dt
    for _ in range(sim.velocity_iterations):
        velocity, impulse = _solve_drive(
            setup, velocity, impulse, desc, delta_position=delta_position, elapsed=elapsed,
            timestep=dt, per_step=False, tgs_velocity_iteration=True,
        )  # fmt: skip
        velocity, friction = _solve_friction(setup, velocity, friction, timestep=dt, per_step=False)
    return JointState(
        position=position + delta_position,
        velocity=velocity,
        effort=impulse / dt + load.applied_effort,
        friction=friction / dt,
    )


def _setup(scenario: Scenario) -> _Setup:
    max_effort = scenario.drive.max_effort
    pendulum = scenario.pendulum
    inertia = scenario.effective_inertia
    return _Setup(
        scenario=scenario,
        response=1.0 / inertia,
        inertia=inertia,
        envelope=scenario.effective_envelope(),
        drive_off=max_effort == 0.0,
        friction=scenario.friction if scenario.friction.active else None,
        gravity=(
            pendulum.mass * scenario.simulation.gravity * pendulum.distance if pendulum is not None else 0.0
        ),
        angle_offset=pendulum.angle_offset if pendulum is not None else 0.0,
    )


def _command(scenario: Scenario, schedule: DriveSchedule | None, index: int) -> _Command:
    if schedule is None:
        drive = scenario.drive
        return _Command(
            target_position=drive.target_position, target_velocity=drive.target_velocity, enabled=True
        )
    return _Command(
        target_position=float(schedule.target_position[index]),
        target_velocity=float(schedule.target_velocity[index]),
        enabled=bool(schedule.enabled[index]),
    )


def step(scenario: Scenario, position: float, velocity: float) -> JointState:
    """Advance the scenario's joint by one time step from ``(position, velocity)``.

    Args:
        scenario: The scenario (drive, envelope, loads, friction, solver settings).
        position: Joint position at the start of the step [rad or m].
        velocity: Joint velocity at the start of the step [rad/s or m/s].

    Returns:
        The state at the end of the step and the step's total actuator effort.

    Raises:
        InputError: a drive quantity or the state overflows float64.
    """
    setup = _setup(scenario)
    advance = _tgs_step if scenario.simulation.solver == "tgs" else _pgs_step
    command = _command(scenario, None, 0)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # the state is checked finite
        return _advance(scenario, setup, advance, command, float(position), float(velocity), 0.0)


def _advance(
    scenario: Scenario,
    setup: _Setup,
    advance: Callable[[_Setup, _Command, float, float], JointState],
    command: _Command,
    position: float,
    velocity: float,
    time: float,
) -> JointState:
    """One step, with every overflow turned into one line naming the time [s]."""
    try:
        state = advance(setup, command, position, velocity)
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


def simulate(
    scenario: Scenario,
    *,
    progress: Callable[[int, int], None] | None = None,
    schedule: DriveSchedule | None = None,
) -> Trajectory:
    """Run the whole scenario with the reference model.

    Args:
        scenario: The scenario.
        progress: Called as ``progress(done, total)`` every few thousand steps and at the end.
        schedule: Per-step drive targets and power state replacing the scenario's constant targets
            (one entry per step), or None.

    Returns:
        ``steps + 1`` rows: the initial state (effort 0) and the state after each step.

    Raises:
        InputError: a drive quantity or the state overflows float64, or a schedule whose length is
            not the number of steps.
    """
    setup = _setup(scenario)
    sim = scenario.simulation
    advance = _tgs_step if sim.solver == "tgs" else _pgs_step
    count = sim.steps
    if schedule is not None:
        schedule.check_steps(count, f"scenario {scenario.name!r}")
    time = np.arange(count + 1, dtype=np.float64) * sim.dt
    position = np.empty(count + 1)
    velocity = np.empty(count + 1)
    effort = np.zeros(count + 1)
    position[0], velocity[0] = scenario.joint.initial_position, scenario.joint.initial_velocity
    # every state is checked finite, so NumPy's overflow warnings would only repeat the error
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for i in range(count):
            command = _command(scenario, schedule, i)
            state = _advance(
                scenario, setup, advance, command, float(position[i]), float(velocity[i]), float(time[i])
            )
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

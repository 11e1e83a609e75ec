"""The ``reference`` engine: a float64 NumPy model of the PhysX articulation solver for one DOF.

This is the executable specification of the test stand: a batch of one through
:mod:`drive_envelope._src.teststand.batch`, whose docstring follows PhysX 5.6+ line by line
(``computeImplicitDriveParams``, the per-DOF block of ``solveInternalJointConstraintRecursive``
with ``clampDriveImpulse`` on the total actuator impulse and PhysX 5.6's joint friction, PGS and
TGS). The scenario gives the batch its stand: response ``r = 1/(inertia + armature + pendulum
m*d^2)``, the effective envelope (none: unlimited; ``max_effort = 0``: the drive is off), friction,
the pendulum's gravity torque and angle offset, the applied and external efforts. A
:class:`DriveSchedule` gives per-step targets and power state (an unpowered step has zero drive
gains).

Everything is float64; PhysX computes in float32, so results agree to float32 precision, not bit
for bit. A drive law, drive request or state that overflows float64 (absurd gains, loads or
inertias) stops the run with one :class:`InputError` line naming the time: a clamp fed an infinite
request would otherwise give a finite, wrong effort.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory, stand_run
from drive_envelope._src.teststand.batch import (
    OVERFLOW_LAW,
    OVERFLOW_REQUEST,
    OVERFLOW_STATE,
    BatchSolver,
    BatchStand,
    simulate_batch,
    step_batch,
)

# the engine protocol looks chain runs up on this module (teststand.engines.simulate)
from drive_envelope._src.teststand.engines.chain import overflow_error
from drive_envelope._src.teststand.engines.chain import simulate_chain as simulate_chain

LOADS = ("pendulum", "friction", "armature")
"""The bench loads this engine represents (see :mod:`drive_envelope._src.teststand.engines`)."""

_OVERFLOWS = {
    OVERFLOW_LAW: "the implicit drive law (drive.stiffness, drive.damping and the targets)",
    OVERFLOW_REQUEST: "the drive's impulse request",
    OVERFLOW_STATE: "the joint state (position, velocity, effort)",
}
_CHECK = "joint.inertia, the drive gains, targets and loads"


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


def _batch(scenario: Scenario) -> tuple[BatchSolver, BatchStand]:
    """The scenario as a batch of one stand."""
    sim, drive, load, friction = scenario.simulation, scenario.drive, scenario.load, scenario.friction
    envelope = scenario.effective_envelope()  # None: the envelope branch without limits (inf)
    pendulum = scenario.pendulum
    gravity = 0.0 if pendulum is None else pendulum.mass * sim.gravity * pendulum.distance
    values = {
        "inertia": scenario.effective_inertia,
        "stiffness": drive.stiffness,
        "damping": drive.damping,
        "max_effort": drive.max_effort,  # the envelope's (spec.py holds the two equal)
        "max_actuator_velocity": math.inf if envelope is None else envelope.max_actuator_velocity,
        "velocity_dependent_resistance": 0.0 if envelope is None else envelope.velocity_dependent_resistance,
        "speed_effort_gradient": 0.0 if envelope is None else envelope.speed_effort_gradient,
        "static_friction": friction.static_friction,
        "dynamic_friction": friction.dynamic_friction,
        "viscous_friction": friction.viscous_friction,
        "gravity_torque": gravity,
        "angle_offset": 0.0 if pendulum is None else pendulum.angle_offset,
        "applied_effort": load.applied_effort,
        "external_effort": load.external_effort,
    }
    return batch_solver(scenario), BatchStand(**{name: np.array([value]) for name, value in values.items()})


def batch_solver(scenario: Scenario, dt: float | None = None) -> BatchSolver:
    """The scenario's solver settings for the batch, at its own step or at ``dt`` [s] (a log's)."""
    sim = scenario.simulation
    return BatchSolver(
        dt=sim.dt if dt is None else dt,
        solver=sim.solver,
        position_iterations=sim.position_iterations,
        velocity_iterations=sim.velocity_iterations,
        drive_type=scenario.drive.type,
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
    solver, stand = _batch(scenario)
    drive = scenario.drive
    result = step_batch(
        solver,
        stand,
        float(position),
        float(velocity),
        target_position=drive.target_position,
        target_velocity=drive.target_velocity,
    )
    if result.overflow[0]:
        raise overflow_error(scenario.name, _OVERFLOWS[int(result.overflow[0])], 0.0, _CHECK)
    return JointState(
        position=float(result.position[0]),
        velocity=float(result.velocity[0]),
        effort=float(result.effort[0]),
        friction=float(result.friction[0]),
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
    sim, drive = scenario.simulation, scenario.drive
    count = sim.steps
    if schedule is None:  # constant commands: views, not count-long copies
        constant = (drive.target_position, drive.target_velocity, 1.0)
        commands = [np.broadcast_to(np.float64(value), (count,)) for value in constant]
    else:
        schedule.check_steps(count, f"scenario {scenario.name!r}")
        commands = [schedule.target_position, schedule.target_velocity, schedule.enabled]
    solver, stand = _batch(scenario)
    result = simulate_batch(
        solver,
        stand,
        initial_position=scenario.joint.initial_position,
        initial_velocity=scenario.joint.initial_velocity,
        target_position=commands[0],
        target_velocity=commands[1],
        enabled=commands[2],
        progress=progress,
    )
    if result.diverged[0]:
        what = _OVERFLOWS[int(result.overflow[0])]
        raise overflow_error(scenario.name, what, int(result.diverged_step[0]) * sim.dt, _CHECK)
    columns = (result.position[:, 0], result.velocity[:, 0], result.effort[:, 0])
    return stand_run(scenario, "reference", *columns, precision="float64")

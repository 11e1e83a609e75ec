"""The reference solver: PhysX's per-DOF articulation solver on a batch of one-DOF stands (float64).

:func:`simulate_batch` runs ``B`` one-DOF stands at once, each with its own inertia, drive gains,
envelope, friction, pendulum and loads (arrays of shape ``(B,)``), under one solver setting (PGS or
TGS, ``dt``, iteration counts, drive type), through per-step targets and power states of shape
``(steps, B)`` (or ``(steps, 1)``, shared). The ``reference`` engine
(:mod:`drive_envelope._src.teststand.engines.reference`) is a batch of one; system identification
replays a bench log for a whole population of candidate parameter sets (and several logs) in one
pass. The Python loop runs over time steps only.

It follows PhysX 5.6+ for a single joint on a fixed base (``physx/source/lowleveldynamics``):

* drive parameters: ``computeImplicitDriveParams`` (``shared/DyCpuGpuArticulation.h``; this and
  the other terms are in :mod:`~drive_envelope._src.teststand.solver_terms`), set up once per step
  from the position error at the start of the step; TGS uses the substep ``stepDt`` for the spring
  and ``dt`` for the target-velocity offset;
* each solver iteration runs the per-DOF block of ``solveInternalJointConstraintRecursive``
  (``src/DyFeatherstoneArticulation.cpp``) in its order: the drive (``computeDriveImpulse`` with
  the accumulated impulse, the joint's delta position and the elapsed time, then
  ``clampDriveImpulse`` on the TOTAL actuator impulse, drive + applied joint effort, or the legacy
  ``+-maxForce`` clamp when ``maxEffort = 0``), then joint friction (PhysX 5.6's model,
  ``computeFrictionImpulse``: the impulse that stops the joint, friction accumulated this step
  included, kept whole below ``staticFrictionEffort*dt`` and clipped to ``(dynamicFrictionEffort +
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

Gravity on a pendulum is an external effort evaluated at the start of the step
(``computeLinkStates`` forms the link's gravity force once per step; TGS applies that force every
substep); its centripetal force is radial and adds nothing along a fixed revolute axis. Response
``r = 1/inertia`` (one link on a fixed base; armature adds to the joint-space inertia,
``computeArticulatedSpatialInertiaAndZ``). An unpowered step has zero drive gains. The clamp is the
one NumPy implementation, :func:`~drive_envelope._src.envelope.clamp.clamp_drive_impulse`.

Everything is float64; PhysX computes in float32, so results agree to float32 precision, not bit
for bit. The implicit drive is unconditionally stable: only absurd gains, loads or inertias
overflow float64. An element whose drive law, drive request or state is not finite in a step
(a clamp fed an infinite request would give a finite, wrong effort) is reported in ``diverged``,
with the step and what overflowed, and its rows hold NaN from that step on, rather than stopping
the batch.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.clamp import clamp_drive_impulse
from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.spec import SolverType
from drive_envelope._src.teststand.solver_terms import DriveLaw, drive_law, drive_request, friction_impulse

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
IntArray = npt.NDArray[np.int64]

OVERFLOW_LAW, OVERFLOW_REQUEST, OVERFLOW_STATE = 1, 2, 3
"""What overflowed first in an element's diverging step (``BatchResult.overflow``; 0: nothing):
the step's implicit drive law, a drive impulse request, or the state (position, velocity, effort)."""

PROGRESS_EVERY = 4096
"""Steps between progress reports."""


@dataclass(frozen=True, kw_only=True, slots=True)
class BatchSolver:
    """Solver settings shared by every element of a batch (PhysX's scene and articulation settings)."""

    dt: float
    """Time step [s]."""
    solver: SolverType = "pgs"
    """``"pgs"`` or ``"tgs"``."""
    position_iterations: int = 1
    """Position iterations (TGS: substeps), >= 1."""
    velocity_iterations: int = 0
    """Velocity iterations, >= 0."""
    drive_type: DriveType = "force"
    """``"force"`` or ``"acceleration"`` (gains per unit inertia)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class BatchStand:
    """Per-element stand parameters, each an array of shape ``(B,)`` (SI, joint side)."""

    inertia: FloatArray
    """Joint-space inertia: link + armature + pendulum m*d^2 [kg*m^2 or kg]; ``> 0``."""
    stiffness: FloatArray
    """Drive stiffness [N*m/rad or N/m] (force) or [1/s^2] (acceleration)."""
    damping: FloatArray
    """Drive damping [N*m*s/rad or N*s/m] (force) or [1/s] (acceleration)."""
    max_effort: FloatArray
    """PhysX maxEffort [N*m or N]: ``inf`` no effort limit, 0 turns the drive off."""
    max_actuator_velocity: FloatArray
    """Envelope eq. 2 speed limit [rad/s or m/s]; ``inf`` for none (with ``max_effort`` inf: no clamp)."""
    velocity_dependent_resistance: FloatArray
    """Envelope eq. 1 slope [N*m*s/rad or N*s/m]."""
    speed_effort_gradient: FloatArray
    """Envelope eq. 2 slope [(rad/s)/(N*m) or (m/s)/N]."""
    static_friction: FloatArray
    """PhysX static friction effort [N*m or N]."""
    dynamic_friction: FloatArray
    """PhysX dynamic friction effort [N*m or N]."""
    viscous_friction: FloatArray
    """PhysX viscous friction coefficient [N*m*s/rad or N*s/m]."""
    gravity_torque: FloatArray
    """Pendulum ``mass*gravity*distance`` [N*m]; 0 without a pendulum."""
    angle_offset: FloatArray
    """Pendulum angle offset [rad]."""
    applied_effort: FloatArray
    """Constant joint force counted as actuator effort [N*m or N]."""
    external_effort: FloatArray
    """Constant effort from outside the actuator [N*m or N]."""

    def __post_init__(self) -> None:
        shapes = set()
        for item in fields(self):
            values = np.ascontiguousarray(getattr(self, item.name), dtype=np.float64)
            if values.ndim != 1:
                raise InputError(f"batch stand: {item.name} must be 1-D, got shape {values.shape}")
            shapes.add(values.shape)
            object.__setattr__(self, item.name, values)
        if len(shapes) != 1:
            raise InputError(f"batch stand: every parameter needs one shape (B,), got {sorted(shapes)}")

    @property
    def size(self) -> int:
        """Number of elements ``B``."""
        return int(self.inertia.shape[0])


@dataclass(frozen=True, kw_only=True, slots=True)
class BatchResult:
    """Per-step samples of a batch: arrays of shape ``(steps + 1, B)``, row 0 the initial state."""

    position: FloatArray
    """Joint position [rad or m] (NaN from an element's diverging step on)."""
    velocity: FloatArray
    """Joint velocity [rad/s or m/s]."""
    effort: FloatArray
    """Step-average total actuator effort (drive + applied), ``effort[0] = 0`` [N*m or N]."""
    diverged: BoolArray
    """Shape ``(B,)``: something overflowed float64 in some step of the element."""
    diverged_step: IntArray
    """Shape ``(B,)``: the first such step (``i``: the step from ``time[i]``), -1 where none."""
    overflow: IntArray
    """Shape ``(B,)``: what overflowed first in that step (``OVERFLOW_*``), 0 where nothing did."""


@dataclass(frozen=True, kw_only=True, slots=True)
class BatchStep:
    """One step of every element (arrays ``(B,)``)."""

    position: FloatArray
    """Joint position at the end of the step [rad or m]."""
    velocity: FloatArray
    """Joint velocity at the end of the step [rad/s or m/s]."""
    effort: FloatArray
    """Step-average total actuator effort: drive impulse / dt + applied effort [N*m or N]."""
    friction: FloatArray
    """Step-average joint friction effort, friction impulse / dt [N*m or N]; not actuator effort."""
    overflow: IntArray
    """What overflowed float64 first in the step (``OVERFLOW_*``), 0 where nothing did."""


@dataclass(frozen=True, slots=True)
class _Constants:
    """Per-element constants of the run (shape ``(B,)``) and which branches any element takes."""

    response: FloatArray
    inertia: FloatArray
    unlimited: BoolArray  # maxEffort = maxActuatorVelocity = inf: the clamp would return the request
    drive_off: BoolArray  # maxEffort = 0: no drive
    friction: BoolArray  # PhysX's friction model runs (static or viscous nonzero)
    gravity: bool  # any pendulum
    # a branch no element takes costs nothing (a batch of one takes one of each pair)
    any_unlimited: bool
    all_unlimited: bool
    any_drive_off: bool
    all_drive_off: bool
    any_friction: bool
    all_friction: bool


@dataclass(frozen=True, slots=True)
class _Budget:
    """The clamp's and friction's per-timestep terms (arrays ``(B,)``), formed once per run."""

    timestep: float
    applied: FloatArray  # applied joint impulse
    max_impulse: FloatArray
    gradient: FloatArray
    resistance: FloatArray
    static: FloatArray
    dynamic: FloatArray
    viscous: FloatArray


def _constants(stand: BatchStand) -> _Constants:
    unlimited = np.isinf(stand.max_effort) & np.isinf(stand.max_actuator_velocity)
    drive_off = stand.max_effort == 0.0
    friction = (stand.static_friction != 0.0) | (stand.viscous_friction != 0.0)
    return _Constants(
        response=1.0 / stand.inertia,
        inertia=stand.inertia,
        unlimited=unlimited,
        drive_off=drive_off,
        friction=friction,
        gravity=bool(np.any(stand.gravity_torque != 0.0)),
        any_unlimited=bool(unlimited.any()),
        all_unlimited=bool(unlimited.all()),
        any_drive_off=bool(drive_off.any()),
        all_drive_off=bool(drive_off.all()),
        any_friction=bool(friction.any()),
        all_friction=bool(friction.all()),
    )


def _budget(stand: BatchStand, timestep: float) -> _Budget:
    return _Budget(
        timestep=timestep,
        applied=stand.applied_effort * timestep,
        max_impulse=stand.max_effort * timestep,
        gradient=stand.speed_effort_gradient / timestep,
        resistance=stand.velocity_dependent_resistance * timestep,
        static=stand.static_friction * timestep,
        dynamic=stand.dynamic_friction * timestep,
        viscous=stand.viscous_friction * timestep,
    )


def _drive(
    stand: BatchStand,
    c: _Constants,
    budget: _Budget,
    velocity: FloatArray,
    impulse: FloatArray,
    law: DriveLaw,
    *,
    delta_position: FloatArray | None,
    elapsed: float,
    per_step: bool,
    reclamp: bool,
    requests: list[Any],
) -> tuple[FloatArray, FloatArray]:
    """The drive block of one iteration for every element; returns velocity and drive impulse."""
    applied0 = np.zeros_like(impulse) if per_step else impulse
    if reclamp:
        request = applied0  # TGS velocity iterations only re-clamp what the substeps applied
    else:
        request = drive_request(law, applied0, velocity, delta_position, elapsed)
        requests.append(request)  # checked finite once per step
    clamped = request
    if not c.all_unlimited:
        clamped = (
            clamp_drive_impulse(
                velocity,
                applied0 + budget.applied,
                request + budget.applied,
                c.response,
                stand.max_actuator_velocity,
                budget.max_impulse,
                budget.gradient,
                budget.resistance,
            )
            - budget.applied
        )
        if c.any_unlimited:
            clamped = np.where(c.unlimited, request, clamped)
    delta = clamped - applied0
    if c.any_drive_off:
        delta = np.where(c.drive_off, 0.0, delta)
    return velocity + delta * c.response, impulse + delta


def _friction(
    c: _Constants, budget: _Budget, velocity: FloatArray, friction: FloatArray, *, per_step: bool
) -> tuple[FloatArray, FloatArray]:
    """PhysX 5.6's joint friction after the drive; returns velocity and friction impulse."""
    if not c.any_friction:
        return velocity, friction
    accumulated = np.zeros_like(friction) if per_step else friction
    total = friction_impulse(
        accumulated - velocity * c.inertia, budget.static, budget.dynamic, budget.viscous, velocity
    )
    delta = total - accumulated
    if not c.all_friction:
        delta = np.where(c.friction, delta, 0.0)
    return velocity + delta * c.response, friction + delta


def _step(
    solver: BatchSolver,
    stand: BatchStand,
    c: _Constants,
    budgets: tuple[_Budget, _Budget],
    position: FloatArray,
    velocity: FloatArray,
    command: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, BoolArray, BoolArray]:
    """One time step of every element.

    Returns:
        Position, velocity, effort, friction effort, and per element whether the drive law and
        whether a drive request was not finite.
    """
    target_position, target_velocity, enabled = command
    dt = solver.dt
    is_tgs = solver.solver == "tgs"
    substeps = solver.position_iterations
    step_dt = dt / substeps if is_tgs else dt
    law = drive_law(
        drive_type=solver.drive_type,
        is_tgs=is_tgs,
        stiffness=stand.stiffness * enabled,
        damping=stand.damping * enabled,
        response=c.response,
        inertia=c.inertia,
        geom_error=target_position - position,
        target_velocity=target_velocity,
        dt=step_dt,
        sim_dt=dt,
    )
    bad_law = ~np.isfinite(law.constant) | ~np.isfinite(law.bias) | ~np.isfinite(law.vel)
    if is_tgs:
        bad_law |= ~np.isfinite(law.target_pos_bias)
    requests: list[Any] = []
    external = stand.applied_effort + stand.external_effort
    if c.gravity:
        external = external - stand.gravity_torque * np.sin(position + stand.angle_offset)
    impulse, friction = np.zeros_like(position), np.zeros_like(position)
    whole, part = budgets
    drive = not c.all_drive_off
    if not is_tgs:
        velocity = velocity + c.response * external * dt
        sweeps = (substeps, max(1, solver.velocity_iterations))
        for sweep, count in enumerate(sweeps):
            if sweep:  # PGS integrates positions with the velocity after the position iterations
                new_position = position + velocity * dt
            # PhysX runs at least one velocity sweep: with 0 velocity iterations configured the
            # reported velocity still comes from one more sweep (real PhysX, viscous friction)
            for _ in range(count):
                if drive:
                    velocity, impulse = _drive(
                        stand, c, whole, velocity, impulse, law, delta_position=None, elapsed=0.0,
                        per_step=False, reclamp=False, requests=requests,
                    )  # fmt: skip
                velocity, friction = _friction(c, whole, velocity, friction, per_step=False)
    else:
        moved: FloatArray = np.zeros_like(position)
        elapsed = 0.0
        for _ in range(substeps):
            velocity = velocity + c.response * external * step_dt  # applyTgsSubstepForces
            if drive:
                velocity, impulse = _drive(
                    stand, c, part, velocity, impulse, law, delta_position=moved, elapsed=elapsed,
                    per_step=True, reclamp=False, requests=requests,
                )  # fmt: skip
            velocity, friction = _friction(c, part, velocity, friction, per_step=True)
            moved = moved + velocity * step_dt  # updateDeltaMotion
            elapsed += step_dt
        for _ in range(solver.velocity_iterations):
            if drive:  # re-clamp the whole step's drive impulse at the current velocity
                velocity, impulse = _drive(
                    stand, c, whole, velocity, impulse, law, delta_position=None, elapsed=0.0,
                    per_step=False, reclamp=True, requests=requests,
                )  # fmt: skip
            velocity, friction = _friction(c, whole, velocity, friction, per_step=False)
        new_position = position + moved
    bad_request = np.zeros_like(bad_law)
    for request in requests:
        bad_request |= ~np.isfinite(request)
    if c.any_drive_off:
        bad_request &= ~c.drive_off  # an element without a drive requests nothing
    effort = impulse / dt + stand.applied_effort
    return new_position, velocity, effort, friction / dt, bad_law, bad_request


def _column(values: npt.ArrayLike, steps: int, size: int, name: str) -> FloatArray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 1:
        array = array[:, None]
    if array.ndim != 2 or array.shape[0] != steps or array.shape[1] not in (1, size):
        raise InputError(
            f"simulate_batch: {name} must have shape ({steps}, 1) or ({steps}, {size}), got {array.shape}"
        )
    return array


def _budgets(solver: BatchSolver, stand: BatchStand) -> tuple[_Budget, _Budget]:
    """The budgets over the step and over one position iteration's timestep (TGS: the substep)."""
    whole = _budget(stand, solver.dt)
    if solver.solver != "tgs" or solver.position_iterations == 1:
        return whole, whole
    return whole, _budget(stand, solver.dt / solver.position_iterations)


def _overflow(bad_law: BoolArray, bad_request: BoolArray, bad_state: BoolArray) -> IntArray:
    """``OVERFLOW_*`` of each element in one step, in the order the step meets them; 0 for none."""
    codes = np.select([bad_law, bad_request, bad_state], [OVERFLOW_LAW, OVERFLOW_REQUEST, OVERFLOW_STATE], 0)
    return np.asarray(codes, dtype=np.int64)


def step_batch(
    solver: BatchSolver,
    stand: BatchStand,
    position: npt.ArrayLike,
    velocity: npt.ArrayLike,
    *,
    target_position: npt.ArrayLike,
    target_velocity: npt.ArrayLike,
    enabled: npt.ArrayLike = 1.0,
) -> BatchStep:
    """Advance every element by one time step from ``(position, velocity)`` (shape ``(B,)`` or scalar).

    The targets [rad or m, rad/s or m/s] and the power state (1/True powered) are held over the
    step, each of shape ``(B,)`` or scalar.
    """
    size = stand.size

    def column(values: npt.ArrayLike) -> FloatArray:
        return np.array(np.broadcast_to(np.asarray(values, dtype=np.float64), (size,)))

    q, v = column(position), column(velocity)
    command = (column(target_position), column(target_velocity), column(enabled))
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        q, v, effort, friction, bad_law, bad_request = _step(
            solver, stand, _constants(stand), _budgets(solver, stand), q, v, command
        )
        bad_state = ~(np.isfinite(q) & np.isfinite(v) & np.isfinite(effort))
    code = _overflow(bad_law, bad_request, bad_state)
    return BatchStep(position=q, velocity=v, effort=effort, friction=friction, overflow=code)


def simulate_batch(
    solver: BatchSolver,
    stand: BatchStand,
    *,
    initial_position: npt.ArrayLike,
    initial_velocity: npt.ArrayLike,
    target_position: npt.ArrayLike,
    target_velocity: npt.ArrayLike,
    enabled: npt.ArrayLike,
    progress: Callable[[int, int], None] | None = None,
) -> BatchResult:
    """Run every element of the batch through the per-step commands.

    Args:
        solver: Shared solver settings.
        stand: Per-element parameters, shape ``(B,)``.
        initial_position: Position at t = 0 [rad or m], shape ``(B,)`` or scalar.
        initial_velocity: Velocity at t = 0 [rad/s or m/s], shape ``(B,)`` or scalar.
        target_position: Drive target over each step [rad or m], shape ``(steps, B)`` or ``(steps, 1)``.
        target_velocity: Drive target velocity [rad/s or m/s], same shapes.
        enabled: Drive powered over each step (1/True) or not (0), same shapes.
        progress: Called as ``progress(done, steps)`` every :data:`PROGRESS_EVERY` steps and at the
            end; once every element has diverged, the run stops at the next report instead.

    Returns:
        The samples, ``(steps + 1, B)`` each, and which elements diverged, where and how.

    Raises:
        InputError: arrays of inconsistent shapes.
    """
    size = stand.size
    targets = np.asarray(target_position, dtype=np.float64)
    steps = int(targets.shape[0])
    q_target = _column(targets, steps, size, "target_position")
    v_target = _column(target_velocity, steps, size, "target_velocity")
    powered = _column(np.asarray(enabled, dtype=np.float64), steps, size, "enabled")
    position = np.empty((steps + 1, size))
    velocity = np.empty((steps + 1, size))
    effort = np.zeros((steps + 1, size))
    # per step, whether the drive law / a drive request was not finite (row i: the step from time[i])
    bad_law = np.zeros((steps, size), dtype=np.bool_)
    bad_request = np.zeros((steps, size), dtype=np.bool_)
    position[0] = np.broadcast_to(np.asarray(initial_position, dtype=np.float64), (size,))
    velocity[0] = np.broadcast_to(np.asarray(initial_velocity, dtype=np.float64), (size,))
    done = 0
    dead = np.zeros(size, dtype=np.bool_)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # overflows are reported
        c, budgets = _constants(stand), _budgets(solver, stand)
        while True:  # at least once: a run of 0 steps reports (0, 0)
            chunk = range(done, min(done + PROGRESS_EVERY, steps))
            for i in chunk:
                command = (q_target[i], v_target[i], powered[i])
                row = _step(solver, stand, c, budgets, position[i], velocity[i], command)
                position[i + 1], velocity[i + 1], effort[i + 1], _, bad_law[i], bad_request[i] = row
            dead |= _bad_steps(position, velocity, effort, bad_law, bad_request, chunk).any(axis=0)
            done = chunk.stop
            if dead.all():
                break  # every element has diverged: the rest would be NaN
            if progress is not None:
                progress(done, steps)
            if done == steps:
                break
    bad = _bad_steps(position, velocity, effort, bad_law, bad_request, range(done))
    diverged: BoolArray = np.asarray(bad.any(axis=0), dtype=np.bool_)
    first = np.full(size, -1, dtype=np.int64)
    code = np.zeros(size, dtype=np.int64)
    if diverged.any():
        index = np.flatnonzero(diverged)
        rows = first[index] = np.argmax(bad[:, index], axis=0)
        code[index] = _overflow(
            bad_law[rows, index], bad_request[rows, index], np.ones(index.size, dtype=np.bool_)
        )
        # the rows after an element's diverging step hold NaN (and those a stopped run never reached)
        broken = np.arange(steps + 1)[:, None] > np.where(diverged, first, steps)[None, :]
        for array in (position, velocity, effort):
            array[broken] = np.nan
    return BatchResult(
        position=position,
        velocity=velocity,
        effort=effort,
        diverged=diverged,
        diverged_step=first,
        overflow=code,
    )


def _bad_steps(
    position: FloatArray,
    velocity: FloatArray,
    effort: FloatArray,
    bad_law: BoolArray,
    bad_request: BoolArray,
    steps: range,
) -> BoolArray:
    """Per step in ``steps`` and element (``(len(steps), B)``): whether anything overflowed in it."""
    i, j = steps.start, steps.stop
    rows = slice(i + 1, j + 1)  # the states at the steps' ends
    finite = np.isfinite(position[rows]) & np.isfinite(velocity[rows]) & np.isfinite(effort[rows])
    return np.asarray(~finite | bad_law[i:j] | bad_request[i:j], dtype=np.bool_)

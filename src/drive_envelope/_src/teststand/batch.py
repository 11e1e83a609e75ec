"""The reference engine vectorized over a batch of stands: many parameter sets per NumPy call.

:func:`simulate_batch` runs ``B`` one-DOF stands at once, each with its own inertia, drive gains,
envelope, friction, pendulum and loads (arrays of shape ``(B,)``), under one solver setting (PGS or
TGS, ``dt``, iteration counts, drive type), through per-step targets and power states of shape
``(steps, B)`` (or ``(steps, 1)``, shared). It is the same PhysX solver model as
:mod:`drive_envelope._src.teststand.engines.reference`, step for step and in the same order (drive,
then friction, every iteration), written on arrays: ``tests/test_teststand_batch.py`` holds the two
equal to ~1e-12 on every scenario kind. The clamp is the one NumPy implementation,
:func:`~drive_envelope._src.envelope.clamp.clamp_drive_impulse`.

System identification uses it to replay a bench log for a whole population of candidate
parameter sets (and several logs) in one pass: the Python loop runs over time steps only. An
element whose state overflows is reported in ``diverged`` and its rows hold NaN from then on,
rather than stopping the batch.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.clamp import clamp_drive_impulse
from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.spec import SolverType

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


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
    """PhysX maxEffort [N*m or N]: ``inf`` unlimited (no clamp), 0 turns the drive off."""
    max_actuator_velocity: FloatArray
    """Envelope eq. 2 speed limit [rad/s or m/s]; ``inf`` for none."""
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
    """Joint position [rad or m] (NaN after an element diverged)."""
    velocity: FloatArray
    """Joint velocity [rad/s or m/s]."""
    effort: FloatArray
    """Step-average total actuator effort (drive + applied), ``effort[0] = 0`` [N*m or N]."""
    diverged: BoolArray
    """Shape ``(B,)``: the element's state overflowed float64 at some step."""


@dataclass(frozen=True, slots=True)
class _Constants:
    """Per-element constants of the run (shape ``(B,)``)."""

    response: FloatArray
    inertia: FloatArray
    unlimited: BoolArray  # maxEffort = inf: no clamp
    drive_off: BoolArray  # maxEffort = 0: no drive
    friction: BoolArray  # PhysX's friction model runs (static or viscous nonzero)
    gravity: bool  # any pendulum


def _constants(stand: BatchStand) -> _Constants:
    return _Constants(
        response=1.0 / stand.inertia,
        inertia=stand.inertia,
        unlimited=np.isinf(stand.max_effort),
        drive_off=stand.max_effort == 0.0,
        friction=(stand.static_friction != 0.0) | (stand.viscous_friction != 0.0),
        gravity=bool(np.any(stand.gravity_torque != 0.0)),
    )


@dataclass(slots=True)
class _Desc:
    """``computeImplicitDriveParams`` for every element (arrays ``(B,)``)."""

    constant: FloatArray
    bias: FloatArray
    vel: FloatArray
    impulse: FloatArray | float
    target_pos_bias: FloatArray | float


def _desc(
    solver: BatchSolver,
    c: _Constants,
    stiffness: FloatArray,
    damping: FloatArray,
    geom_error: FloatArray,
    target_velocity: FloatArray,
    dt: float,
) -> _Desc:
    """Port of ``computeImplicitDriveParams`` on arrays (see ``solver_terms.implicit_drive_desc``)."""
    is_tgs = solver.solver == "tgs"
    a = dt * (dt * stiffness + damping)
    b = dt * (damping * target_velocity)
    initial_bias = geom_error - (solver.dt - dt) * target_velocity
    if solver.drive_type == "force":
        x = 1.0 / (1.0 + a * c.response)
        scale: FloatArray | float = 1.0
    else:
        x = 1.0 / (1.0 + a)
        scale = c.inertia
    bias = stiffness * x * scale * dt
    return _Desc(
        constant=x * b * scale + bias * initial_bias,
        bias=bias,
        vel=-x * a * scale,
        impulse=1.0 if is_tgs else 1.0 - x,
        target_pos_bias=bias * target_velocity if is_tgs else 0.0,
    )


def _drive(
    stand: BatchStand,
    c: _Constants,
    velocity: FloatArray,
    impulse: FloatArray,
    desc: _Desc,
    *,
    delta_position: FloatArray | float,
    elapsed: float,
    timestep: float,
    per_step: bool,
    tgs_velocity_iteration: bool,
) -> tuple[FloatArray, FloatArray]:
    """The drive block of one iteration for every element (``reference._solve_drive``)."""
    applied0 = np.zeros_like(impulse) if per_step else impulse
    if tgs_velocity_iteration:
        request = applied0
    else:
        request = (
            applied0 * desc.impulse
            + velocity * desc.vel
            + desc.constant
            - delta_position * desc.bias
            + elapsed * desc.target_pos_bias
        )
    external = stand.applied_effort * timestep
    clamped = (
        clamp_drive_impulse(
            velocity,
            applied0 + external,
            request + external,
            c.response,
            stand.max_actuator_velocity,
            stand.max_effort * timestep,
            stand.speed_effort_gradient / timestep,
            stand.velocity_dependent_resistance * timestep,
        )
        - external
    )
    clamped = np.where(c.unlimited, request, clamped)
    delta = np.where(c.drive_off, 0.0, clamped - applied0)
    return velocity + delta * c.response, impulse + delta


def _friction(
    stand: BatchStand,
    c: _Constants,
    velocity: FloatArray,
    friction: FloatArray,
    *,
    timestep: float,
    per_step: bool,
) -> tuple[FloatArray, FloatArray]:
    """PhysX 5.6's joint friction after the drive (``computeFrictionImpulse`` on arrays)."""
    accumulated = np.zeros_like(friction) if per_step else friction
    stop = accumulated - velocity * c.inertia
    bound = (stand.dynamic_friction + stand.viscous_friction * np.abs(velocity)) * timestep
    slips = np.abs(stop) > stand.static_friction * timestep
    total = np.where(slips, np.clip(stop, -bound, bound), stop)
    delta = np.where(c.friction, total - accumulated, 0.0)
    return velocity + delta * c.response, friction + delta


def _external(stand: BatchStand, c: _Constants, position: FloatArray) -> FloatArray:
    load = stand.applied_effort + stand.external_effort
    if not c.gravity:
        return load
    return load - stand.gravity_torque * np.sin(position + stand.angle_offset)


def _step(
    solver: BatchSolver,
    stand: BatchStand,
    c: _Constants,
    position: FloatArray,
    velocity: FloatArray,
    command: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """One time step of every element; returns (position, velocity, effort)."""
    target_position, target_velocity, enabled = command
    stiffness, damping = stand.stiffness * enabled, stand.damping * enabled
    dt = solver.dt
    external = _external(stand, c, position)
    impulse, friction = np.zeros_like(position), np.zeros_like(position)
    if solver.solver == "pgs":
        velocity = velocity + c.response * external * dt
        desc = _desc(solver, c, stiffness, damping, target_position - position, target_velocity, dt)
        moved = velocity
        # PhysX runs at least one velocity sweep: 0 velocity iterations report one more sweep's velocity
        for i in range(solver.position_iterations + max(1, solver.velocity_iterations)):
            velocity, impulse = _drive(
                stand, c, velocity, impulse, desc, delta_position=0.0, elapsed=0.0, timestep=dt,
                per_step=False, tgs_velocity_iteration=False,
            )  # fmt: skip
            velocity, friction = _friction(stand, c, velocity, friction, timestep=dt, per_step=False)
            if i == solver.position_iterations - 1:
                moved = velocity  # PGS integrates positions with the position-iteration velocity
        new_position = position + moved * dt
    else:
        step_dt = dt / solver.position_iterations
        desc = _desc(solver, c, stiffness, damping, target_position - position, target_velocity, step_dt)
        delta_position: FloatArray = np.zeros_like(position)
        elapsed = 0.0
        for _ in range(solver.position_iterations):
            velocity = velocity + c.response * external * step_dt
            velocity, impulse = _drive(
                stand, c, velocity, impulse, desc, delta_position=delta_position, elapsed=elapsed,
                timestep=step_dt, per_step=True, tgs_velocity_iteration=False,
            )  # fmt: skip
            velocity, friction = _friction(stand, c, velocity, friction, timestep=step_dt, per_step=True)
            delta_position = delta_position + velocity * step_dt
            elapsed += step_dt
        for _ in range(solver.velocity_iterations):
            velocity, impulse = _drive(
                stand, c, velocity, impulse, desc, delta_position=delta_position, elapsed=elapsed,
                timestep=dt, per_step=False, tgs_velocity_iteration=True,
            )  # fmt: skip
            velocity, friction = _friction(stand, c, velocity, friction, timestep=dt, per_step=False)
        new_position = position + delta_position
    return new_position, velocity, impulse / dt + stand.applied_effort


def _column(values: npt.ArrayLike, steps: int, size: int, name: str) -> FloatArray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 1:
        array = array[:, None]
    if array.ndim != 2 or array.shape[0] != steps or array.shape[1] not in (1, size):
        raise InputError(
            f"simulate_batch: {name} must have shape ({steps}, 1) or ({steps}, {size}), got {array.shape}"
        )
    return array


def simulate_batch(
    solver: BatchSolver,
    stand: BatchStand,
    *,
    initial_position: npt.ArrayLike,
    initial_velocity: npt.ArrayLike,
    target_position: npt.ArrayLike,
    target_velocity: npt.ArrayLike,
    enabled: npt.ArrayLike,
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

    Returns:
        The samples, ``(steps + 1, B)`` each, and which elements diverged.

    Raises:
        InputError: arrays of inconsistent shapes.
    """
    size = stand.size
    targets = np.asarray(target_position, dtype=np.float64)
    steps = int(targets.shape[0])
    q_target = _column(targets, steps, size, "target_position")
    v_target = _column(target_velocity, steps, size, "target_velocity")
    powered = _column(np.asarray(enabled, dtype=np.float64), steps, size, "enabled")
    c = _constants(stand)
    position = np.empty((steps + 1, size))
    velocity = np.empty((steps + 1, size))
    effort = np.zeros((steps + 1, size))
    position[0] = np.broadcast_to(np.asarray(initial_position, dtype=np.float64), (size,))
    velocity[0] = np.broadcast_to(np.asarray(initial_velocity, dtype=np.float64), (size,))
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for i in range(steps):
            command = (q_target[i], v_target[i], powered[i])
            position[i + 1], velocity[i + 1], effort[i + 1] = _step(
                solver, stand, c, position[i], velocity[i], command
            )
    finite = np.isfinite(position) & np.isfinite(velocity) & np.isfinite(effort)
    diverged: BoolArray = np.asarray(~finite.all(axis=0), dtype=np.bool_)
    if diverged.any():
        broken = np.logical_not(np.logical_and.accumulate(finite, axis=0))
        for array in (position, velocity, effort):
            array[broken] = np.nan
    return BatchResult(position=position, velocity=velocity, effort=effort, diverged=diverged)

"""The ``reference`` engine for chains: a float64 model of PhysX's articulation solver over many DOFs.

Per step, as PhysX 5.6's Featherstone articulation runs it (``DyFeatherstoneArticulation.cpp``,
``DyFeatherstoneForwardDynamic.cpp``, ``DySolverCore.cpp``, ``DyTGSDynamics.cpp``):

* at the start of the step the joint-space mass matrix ``M(q)`` (armature on its diagonal) and the
  bias efforts ``h(q, v)`` (Coriolis, centrifugal, gravity) are formed
  (:mod:`~drive_envelope._src.teststand.engines.chain_dynamics`); every DOF's unit response is
  ``(M^-1)_ii`` (``getImpulseSelfResponse``: the joint velocity change per unit impulse of the
  articulation, not ``1/M_ii``), and the drive law of each DOF is ``computeImplicitDriveParams``
  with that response;
* the drives are velocity rows solved in one Gauss-Seidel sweep from root to leaf
  (``solveInternalJointConstraintRecursive`` walks the links in order): each DOF's drive impulse
  is requested (``computeDriveImpulse``), clamped on the total actuator impulse
  (``clampDriveImpulse``, the one NumPy clamp), then its friction; each impulse reaches every
  joint through the column ``M^-1[:, i]`` before the next row is solved;
* PGS: applied and external efforts and ``-h`` act once over ``dt``; the position iterations are
  sweeps, positions integrate with the velocity after them (``q1 = q0 + v*dt``), and the velocity
  iterations follow. PhysX runs at least one velocity sweep: with 0 velocity iterations configured
  the reported velocity still comes from one more sweep (measured on real PhysX, one joint and
  chains alike);
* TGS: the velocity-product part of ``-h`` acts once over ``dt``; gravity and the applied and
  external efforts act per substep (``applyTgsSubstepForces``, with the start-of-step inertia);
  each substep is one sweep with per-substep clamps (budget ``maxEffort*stepDt``) and friction,
  after which positions move by ``v*stepDt``; each velocity iteration re-clamps the step's total
  drive impulse at the current velocity (no new request) and solves friction against the whole
  step's friction impulse.

Everything is float64; PhysX computes in float32.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.clamp import clamp_drive_impulse
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain import ChainScenario
from drive_envelope._src.scenario.chain_trajectory import ChainTrajectory, chain_run
from drive_envelope._src.teststand.engines.chain_dynamics import ChainModel
from drive_envelope._src.teststand.solver_terms import DriveLaw, drive_law, drive_request, friction_impulse

FloatArray = npt.NDArray[np.float64]
_PROGRESS_EVERY = 1024
_CHECK = "the masses, inertias, drive gains and loads"


@dataclass(frozen=True, kw_only=True, slots=True)
class _Dof:
    """Constants of one joint's solver rows."""

    envelope: PerformanceEnvelope | None
    drive_off: bool
    applied: float  # applied joint effort [N*m or N], actuator effort
    external: float  # external joint effort [N*m or N]
    static: float
    dynamic: float
    viscous: float
    friction: bool


class _Step:
    """One step's start-of-step quantities and accumulated impulses."""

    def __init__(self, minv: FloatArray, descs: list[DriveLaw]) -> None:
        self.minv = minv
        self.response = np.diag(minv).copy()
        self.descs = descs
        n = minv.shape[0]
        self.impulse = np.zeros(n)
        self.friction = np.zeros(n)


def _dofs(scenario: ChainScenario) -> list[_Dof]:
    result = []
    for joint in scenario.joints:
        friction = joint.friction
        result.append(
            _Dof(
                envelope=joint.effective_envelope(),
                drive_off=joint.drive.max_effort == 0.0,
                applied=joint.load.applied_effort,
                external=joint.load.external_effort,
                static=friction.static_friction,
                dynamic=friction.dynamic_friction,
                viscous=friction.viscous_friction,
                friction=friction.active,
            )
        )
    return result


def _clamp(
    dof: _Dof, velocity: float, applied0: float, request: float, response: float, timestep: float
) -> float:
    """``clampDriveImpulse`` on the total actuator impulse (drive + applied), minus the applied part."""
    env = dof.envelope
    if env is None:
        return request
    external = dof.applied * timestep
    total = clamp_drive_impulse(
        velocity,
        applied0 + external,
        request + external,
        response,
        env.max_actuator_velocity,
        env.max_effort * timestep,
        env.speed_effort_gradient / timestep,
        env.velocity_dependent_resistance * timestep,
    )
    return float(total) - external


def _sweep(
    dofs: list[_Dof],
    state: _Step,
    velocity: FloatArray,
    *,
    timestep: float,
    per_step: bool,
    reclamp: bool,
    delta_position: FloatArray | None = None,
    elapsed: float = 0.0,
) -> None:
    """One Gauss-Seidel pass over the DOFs, root to leaf: drive, then friction, each propagated."""
    minv, response = state.minv, state.response
    for i, dof in enumerate(dofs):
        r = float(response[i])
        if not dof.drive_off:
            applied0 = 0.0 if per_step else float(state.impulse[i])
            if reclamp:
                request = applied0  # TGS velocity iterations re-clamp what the substeps applied
            else:
                shift = None if delta_position is None else float(delta_position[i])
                request = drive_request(state.descs[i], applied0, float(velocity[i]), shift, elapsed)
                if not math.isfinite(request):
                    raise ArithmeticError("the drive's impulse request")
            delta = _clamp(dof, float(velocity[i]), applied0, request, r, timestep) - applied0
            if delta != 0.0:
                velocity += minv[:, i] * delta
                state.impulse[i] += delta
        if dof.friction:
            accumulated = 0.0 if per_step else float(state.friction[i])
            total = float(
                friction_impulse(
                    accumulated - float(velocity[i]) / r,
                    dof.static * timestep,
                    dof.dynamic * timestep,
                    dof.viscous * timestep,
                    float(velocity[i]),
                )
            )
            delta = total - accumulated
            if delta != 0.0:
                velocity += minv[:, i] * delta
                state.friction[i] += delta


def _descs(
    scenario: ChainScenario, response: FloatArray, position: FloatArray, dt: float, is_tgs: bool
) -> list[DriveLaw]:
    sim_dt = scenario.simulation.dt
    result = []
    for i, joint in enumerate(scenario.joints):
        drive = joint.drive
        r = float(response[i])
        result.append(
            drive_law(
                drive_type=drive.type,
                is_tgs=is_tgs,
                stiffness=drive.stiffness,
                damping=drive.damping,
                response=r,
                inertia=1.0 / r,  # PhysX's recipResponse
                geom_error=drive.target_position - float(position[i]),
                target_velocity=drive.target_velocity,
                dt=dt,
                sim_dt=sim_dt,
            )
        )
    return result


def step_chain(
    scenario: ChainScenario,
    model: ChainModel,
    position: FloatArray,
    velocity: FloatArray,
    dofs: list[_Dof] | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Advance the chain by one step; returns the new positions, velocities and step efforts.

    The effort of each DOF is its step-average total actuator effort: drive impulse / dt + applied.
    """
    dofs = dofs if dofs is not None else _dofs(scenario)
    sim = scenario.simulation
    dt = sim.dt
    kin = model.kinematics(position)
    minv: FloatArray = np.asarray(np.linalg.inv(model.mass_matrix(kin)), dtype=np.float64)
    loads = np.array([dof.applied + dof.external for dof in dofs])
    velocity = velocity.astype(np.float64, copy=True)
    if sim.solver == "pgs":
        bias = model.bias(kin, velocity)
        velocity += minv @ (loads - bias) * dt
        state = _Step(minv, _descs(scenario, np.diag(minv), position, dt, is_tgs=False))
        for _ in range(sim.position_iterations):
            _sweep(dofs, state, velocity, timestep=dt, per_step=False, reclamp=False)
        new_position = position + velocity * dt
        for _ in range(max(1, sim.velocity_iterations)):
            _sweep(dofs, state, velocity, timestep=dt, per_step=False, reclamp=False)
    else:
        step_dt = dt / sim.position_iterations
        gravity = model.bias(kin, np.zeros_like(velocity))
        velocity += minv @ (gravity - model.bias(kin, velocity)) * dt  # velocity products, once
        substep_force = minv @ (loads - gravity) * step_dt
        state = _Step(minv, _descs(scenario, np.diag(minv), position, step_dt, is_tgs=True))
        moved = np.zeros_like(position)
        elapsed = 0.0
        for _ in range(sim.position_iterations):
            velocity += substep_force
            _sweep(dofs, state, velocity, timestep=step_dt, per_step=True, reclamp=False,
                   delta_position=moved, elapsed=elapsed)  # fmt: skip
            moved += velocity * step_dt
            elapsed += step_dt
        for _ in range(sim.velocity_iterations):
            _sweep(dofs, state, velocity, timestep=dt, per_step=False, reclamp=True)
        new_position = position + moved
    effort = state.impulse / dt + np.array([dof.applied for dof in dofs])
    return new_position, velocity, effort


def simulate_chain(
    scenario: ChainScenario, *, progress: Callable[[int, int], None] | None = None
) -> ChainTrajectory:
    """Run a chain scenario with the reference model.

    Returns:
        ``steps + 1`` rows per joint: the initial state (effort 0) and the state after each step.

    Raises:
        InputError: a drive quantity or the state overflows float64.
    """
    sim = scenario.simulation
    model = ChainModel(scenario)
    dofs = _dofs(scenario)
    count = sim.steps
    n = scenario.dofs
    position = np.zeros((count + 1, n))
    velocity = np.zeros((count + 1, n))
    effort = np.zeros((count + 1, n))
    position[0] = [joint.initial_position for joint in scenario.joints]
    velocity[0] = [joint.initial_velocity for joint in scenario.joints]
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for i in range(count):
            try:
                q, v, e = step_chain(scenario, model, position[i], velocity[i], dofs)
            except (ArithmeticError, np.linalg.LinAlgError) as exc:
                raise overflow_error(
                    scenario.name, str(exc) or "a drive quantity", i * sim.dt, _CHECK
                ) from None
            if not (np.isfinite(q).all() and np.isfinite(v).all() and np.isfinite(e).all()):
                what = "the joint state (position, velocity, effort)"
                raise overflow_error(scenario.name, what, i * sim.dt, _CHECK)
            position[i + 1], velocity[i + 1], effort[i + 1] = q, v, e
            if progress is not None and (i + 1) % _PROGRESS_EVERY == 0:
                progress(i + 1, count)
    if progress is not None:
        progress(count, count)
    return chain_run(
        scenario,
        "reference",
        position,
        velocity,
        effort,
        precision="float64",
        effort_source="drive impulse / dt + applied effort (total actuator effort)",
    )


def overflow_error(name: str | None, what: str, time: float, check: str) -> InputError:
    """The one line of a reference run (a joint's or a chain's) that overflowed float64 at ``time`` [s]."""
    return InputError(
        f"scenario {name or ''!r}: {what} overflowed float64 in the step from t = {time:g} s; "
        f"expected values whose products stay finite (check {check})"
    )

"""PhysX's per-DOF solver terms for an articulation joint, ported from PhysX 5.6 (float64).

From ``physx/source/lowleveldynamics/shared/DyCpuGpuArticulation.h``:

* :func:`drive_law`: ``computeImplicitDriveParams``, the implicit drive's linear law for one step
  (force and acceleration drives);
* :func:`drive_request`: ``computeDriveImpulse``, the unclamped drive impulse of one solver
  iteration;
* :func:`friction_impulse`: ``computeFrictionImpulse``, the joint friction of PhysX 5.6's friction
  model (``PxJointFrictionParams``: static, dynamic and viscous friction).

Each takes Python floats or NumPy arrays alike: the one-DOF stands run them on arrays of stands
(:mod:`drive_envelope._src.teststand.batch`), the chain engine on floats, one DOF at a time in its
Gauss-Seidel sweep (:mod:`drive_envelope._src.teststand.engines.chain`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from drive_envelope._src.envelope.drive import DriveType


@dataclass(frozen=True, kw_only=True, slots=True)
class DriveLaw:
    """PhysX ``ArticulationImplicitDriveDesc``: the implicit drive's linear law for one step.

    The unclamped drive impulse is ``accumulated*impulse + v*vel + constant - delta_position*bias +
    elapsed*target_pos_bias`` [N*m*s or N*s] (:func:`drive_request`); floats or arrays alike.
    """

    constant: Any
    """Damping toward the target velocity plus the initial spring error [N*m*s or N*s]."""
    bias: Any
    """Impulse per unit joint displacement within the step [N*m*s/rad or N*s/m]."""
    vel: Any
    """Impulse per unit joint velocity (negative) [N*m*s/(rad/s) or N*s/(m/s)]."""
    impulse: Any
    """Weight of the impulse accumulated so far: ``1 - x`` for PGS, 1 for TGS [-]."""
    target_pos_bias: Any
    """Impulse per second of elapsed time (TGS: the target moves with the target velocity) [N*m or N]."""


def drive_law(
    *,
    drive_type: DriveType,
    is_tgs: bool,
    stiffness: Any,
    damping: Any,
    response: Any,
    inertia: Any,
    geom_error: Any,
    target_velocity: Any,
    dt: float,
    sim_dt: float,
) -> DriveLaw:
    """Port of PhysX ``computeImplicitDriveParams`` (force and acceleration drives), floats or arrays.

    Args:
        drive_type: ``"force"`` or ``"acceleration"``.
        is_tgs: Whether the TGS solver runs the drive.
        stiffness: Drive stiffness [N*m/rad or N/m] (force) or [1/s^2] (acceleration).
        damping: Drive damping [N*m*s/rad or N*s/m] (force) or [1/s] (acceleration).
        response: Joint velocity change per unit impulse [rad/s/(N*m*s) or m/s/(N*s)].
        inertia: PhysX's recipResponse, ``1/response`` [kg*m^2 or kg] (the acceleration drive's scale).
        geom_error: ``target_position - position`` at the start of the step [rad or m].
        target_velocity: Drive target velocity [rad/s or m/s].
        dt: Step over which the spring is integrated: the substep for TGS, the step for PGS [s].
        sim_dt: The simulation step [s].
    """
    a = dt * (dt * stiffness + damping)
    b = dt * (damping * target_velocity)
    initial_bias = geom_error - (sim_dt - dt) * target_velocity  # equals geom_error for PGS
    if drive_type == "force":
        x = 1.0 / (1.0 + a * response)
        scale = 1.0
    else:
        x = 1.0 / (1.0 + a)
        scale = inertia  # the gains act per unit inertia
    bias = stiffness * x * scale * dt
    return DriveLaw(
        constant=x * b * scale + bias * initial_bias,
        bias=bias,
        vel=-x * a * scale,
        impulse=1.0 if is_tgs else 1.0 - x,
        target_pos_bias=bias * target_velocity if is_tgs else 0.0,
    )


def drive_request(
    law: DriveLaw, accumulated: Any, velocity: Any, delta_position: Any = None, elapsed: float = 0.0
) -> Any:
    """Port of PhysX ``computeDriveImpulse``: the unclamped drive impulse [N*m*s or N*s].

    ``delta_position`` (the joint's displacement since the start of the step [rad or m]) and
    ``elapsed`` (the time elapsed in it [s]) are TGS's; PGS passes None (PhysX's zeros, whose
    terms add exactly nothing to a finite request).
    """
    request = accumulated * law.impulse + velocity * law.vel + law.constant
    if delta_position is not None:
        request = request - delta_position * law.bias + elapsed * law.target_pos_bias
    return request


def friction_impulse(stop: Any, static: Any, dynamic: Any, viscous: Any, velocity: Any) -> Any:
    """Port of PhysX ``computeFrictionImpulse``: the total friction impulse of one iteration [N*m*s or N*s].

    ``stop`` is the impulse that would stop the joint, friction accumulated this step included
    (``accumulated - v*recipResponse``): below the static threshold the joint sticks (the whole
    stopping impulse); above it the impulse is clipped (``PxClamp``) to the dynamic + viscous
    budget. The thresholds are impulses over the iteration's timestep, ``velocity`` the joint's
    after the drive.
    """
    bound = dynamic + viscous * abs(velocity)
    return np.where(abs(stop) > static, np.minimum(np.maximum(stop, -bound), bound), stop)

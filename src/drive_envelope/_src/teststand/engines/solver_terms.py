"""PhysX's per-DOF solver terms for one articulation joint, ported from PhysX 5.6 (float64).

From ``physx/source/lowleveldynamics/shared/DyCpuGpuArticulation.h``:

* :func:`implicit_drive_desc`: ``computeImplicitDriveParams``, the implicit drive's linear law for one
  step (force and acceleration drives);
* :func:`compute_drive_impulse`: ``computeDriveImpulse``, the unclamped drive impulse of one solver
  iteration;
* :func:`compute_friction_impulse`: ``computeFrictionImpulse``, the joint friction of PhysX 5.6's
  friction model (``PxJointFrictionParams``: static, dynamic and viscous friction).

The functions take Python floats (the reference engine's scalar loop);
:mod:`drive_envelope._src.teststand.batch` follows the same formulas on arrays, and the tests hold
the two equal.
"""

from __future__ import annotations

from dataclasses import dataclass

from drive_envelope._src.envelope.drive import DriveType


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


def compute_friction_impulse(
    friction_impulse: float,
    static_impulse: float,
    dynamic_impulse: float,
    viscous_coefficient: float,
    joint_velocity: float,
) -> float:
    """Port of PhysX ``computeFrictionImpulse``: the total friction impulse of one iteration [N*m*s or N*s].

    PhysX calls it after the drive with ``friction_impulse = accumulated - v*recipResponse`` (the
    impulse that stops the joint, plus the friction already applied this step): below the static
    threshold the joint sticks (the whole stopping impulse); above it the impulse is clipped to the
    dynamic + viscous budget.

    Args:
        friction_impulse: The impulse that would stop the joint, accumulated friction included [N*m*s or N*s].
        static_impulse: ``staticFrictionEffort * dt`` [N*m*s or N*s].
        dynamic_impulse: ``dynamicFrictionEffort * dt`` [N*m*s or N*s].
        viscous_coefficient: ``viscousFrictionCoefficient * dt`` [N*m*s/(rad/s) or N*s/(m/s)].
        joint_velocity: Joint velocity after the drive in this iteration [rad/s or m/s].
    """
    if abs(friction_impulse) > static_impulse:
        bound = dynamic_impulse + viscous_coefficient * abs(joint_velocity)
        friction_impulse = min(max(friction_impulse, -bound), bound)  # PxClamp
    return friction_impulse

"""PhysX's implicit PD drive for one DOF (``computeImplicitDriveParams`` semantics).

PhysX solves the drive's spring-damper law at the END of the step. For a force drive the total
impulse ``J = effort*dt`` satisfies::

    J = dt*stiffness*(position_error - dt*v1) + dt*damping*(target_velocity - v1),   v1 = v + response*J

so, with ``a = dt*(dt*stiffness + damping)`` and ``x = 1/(1 + a*response)``::

    J = x * (dt*stiffness*position_error + dt*damping*target_velocity - a*v)

An acceleration drive uses the same law with a unit response (``x = 1/(1 + a)``) and divides the
impulse by ``response`` (it scales by the DOF's inertia). ``position_error`` is
``target_position - position``; ``v`` is the joint velocity before the drive acts (it contains
the other forces of the step).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.clamp import check_time_step
from drive_envelope._src.errors import InputError
from drive_envelope._src.validation import broadcast_shape

DriveType = Literal["force", "acceleration"]


def implicit_drive_effort(
    *,
    stiffness: npt.ArrayLike,
    damping: npt.ArrayLike,
    position_error: npt.ArrayLike,
    velocity: npt.ArrayLike,
    target_velocity: npt.ArrayLike,
    response: npt.ArrayLike,
    dt: float,
    drive_type: DriveType = "force",
) -> npt.NDArray[Any]:
    """Unclamped total drive effort of one step of PhysX's implicit PD drive.

    Args:
        stiffness: Drive stiffness [N*m/rad or N/m] (force drive) or [1/s^2] (acceleration drive).
        damping: Drive damping [N*m*s/rad or N*s/m] (force drive) or [1/s] (acceleration drive).
        position_error: ``target_position - position`` at the start of the step [rad or m].
        velocity: Joint velocity before the drive acts [rad/s or m/s].
        target_velocity: Drive target velocity [rad/s or m/s].
        response: Joint velocity change per unit joint impulse, ``1/inertia`` for one DOF
            [rad/s/(N*m*s) or m/s/(N*s)], ``>= 0``.
        dt: Time step [s], a number ``> 0`` and finite (an array is refused).
        drive_type: ``"force"`` or ``"acceleration"``.

    Returns:
        The effort ``J/dt`` [N*m or N], before any clamp; broadcast shape, float64. A force drive
        on a DOF with zero response gives 0 (PhysX's guard), an acceleration drive gives inf there.

    Raises:
        InputError: ``dt`` not finite and > 0, an unknown ``drive_type``, a value that is not a
            number, shapes that do not broadcast, or a negative (or NaN) gain or negative response.
    """
    dt = check_time_step(dt)  # the one time-step rule (docs/architecture.md)
    if drive_type not in ("force", "acceleration"):
        raise InputError(f"drive_type must be 'force' or 'acceleration', got {drive_type!r}")
    names = ("stiffness", "damping", "position_error", "velocity", "target_velocity", "response")
    arrays = []
    values = (stiffness, damping, position_error, velocity, target_velocity, response)
    for name, value in zip(names, values, strict=True):
        try:
            arrays.append(np.asarray(value, dtype=np.float64))
        except (TypeError, ValueError):  # a string with units, None in a list: float()'s error
            raise InputError(f"implicit_drive_effort: {name}: expected SI numbers, got {value!r}") from None
    broadcast_shape("implicit_drive_effort", names, [a.shape for a in arrays])
    k, c, err, v, v_target, r = arrays
    gains = ("1/s^2", "1/s") if drive_type == "acceleration" else ("N*m/rad or N/m", "N*m*s/rad or N*s/m")
    # a negative gain is an anti-spring (it pushes away from the target) and a NaN one a NaN effort;
    # a negative response is refused as clamp_effort_implicit refuses it (a NaN one lets go there)
    for name, array, unit, nan in (
        ("stiffness", k, gains[0], True),
        ("damping", c, gains[1], True),
        ("response", r, "rad/s/(N*m*s) or m/s/(N*s)", False),
    ):
        bad = (array < 0.0) | (np.isnan(array) & nan)
        if np.any(bad):
            raise InputError(
                f"implicit_drive_effort: {name}: expected >= 0 [{unit}], got {float(array[bad].flat[0])!r}"
            )
    a = dt * (dt * k + c)
    rhs = dt * k * err + dt * c * v_target - a * v
    if drive_type == "force":
        x = np.where(r > 0.0, 1.0 / (1.0 + a * np.maximum(r, 0.0)), 0.0)
        impulse = x * rhs
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            impulse = rhs / ((1.0 + a) * r)
    return impulse / dt

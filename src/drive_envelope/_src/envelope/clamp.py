"""Clamping a drive's effort to the envelope: explicit, and implicit with PhysX's exact semantics.

:func:`clamp_drive_impulse` is a vectorized port of PhysX 5.6+ ``Dy::clampDriveImpulse``
(``physx/source/lowleveldynamics/shared/DyCpuGpuArticulation.h``): same argument order, same
branches, same absolute epsilon ``2^-23`` (``PX_EPS_F32``), same ``FLT_MAX`` sentinels, same
float ``PxMax``/``PxMin`` select semantics (``a > b ? a : b`` and ``a < b ? a : b``, PhysX's
``intrinsics::selectMax``/``selectMin`` on Linux, which decide what a NaN turns into). It computes in
float64 by default; ``dtype=numpy.float32`` reproduces PhysX bit for bit (checked against vectors
from PhysX itself in ``tests/test_envelope_physx_vectors.py``).

The implicit clamp finds the largest total impulse ``x`` (same sign as the request, not above it)
such that ``x`` and the joint velocity after applying it, ``v(x) = v0 + r*(x - x0)``, satisfy::

    |v(x)| <= max_joint_vel - speed_impulse_gradient * |x|
    |x|    <= max_impulse - velocity_dependent_resistance * |v(x)|   (|x| <= max_impulse if R = 0)

and returns 0 when no such ``x`` exists (the drive lets go).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.fast_clamp import clamp_drive_impulse_symmetric
from drive_envelope._src.envelope.model import PerformanceEnvelope

__all__ = [
    "CLAMP_DRIVE_IMPULSE_ARGS",
    "PX_EPS_F32",
    "PX_MAX_F32",
    "clamp_drive_impulse",
    "clamp_effort",
    "clamp_effort_implicit",
]

PX_EPS_F32 = float(np.finfo(np.float32).eps)
"""PhysX's absolute epsilon for near-zero denominators, ``FLT_EPSILON = 2^-23``."""
PX_MAX_F32 = float(np.finfo(np.float32).max)
"""PhysX's sentinel for an absent bound, ``FLT_MAX``."""
CLAMP_DRIVE_IMPULSE_ARGS = (
    "joint_vel0",
    "drive_impulse0",
    "drive_impulse",
    "response",
    "max_joint_vel",
    "max_impulse",
    "speed_impulse_gradient",
    "velocity_dependent_resistance",
)
"""Argument names of :func:`clamp_drive_impulse`, in PhysX's order (every backend uses them)."""

Array = npt.NDArray[Any]


def clamp_effort(envelope: PerformanceEnvelope, effort: npt.ArrayLike, velocity: npt.ArrayLike) -> Array:
    """Limit ``effort`` to the envelope at the given (current) velocity: the explicit clamp.

    This is what a plain actuator model does each control step: the effort keeps its sign and its
    magnitude is capped at :meth:`PerformanceEnvelope.effort_limit` of ``velocity``.

    Args:
        envelope: The envelope (joint side, SI).
        effort: Requested effort [N*m or N]; broadcast with ``velocity``.
        velocity: Current joint velocity [rad/s or m/s].

    Returns:
        Clamped effort [N*m or N], float64, broadcast shape.
    """
    limit = envelope.effort_limit(velocity)
    effort = np.asarray(effort, dtype=np.float64)
    clamped = np.minimum(effort, limit, out=np.empty(np.broadcast_shapes(effort.shape, limit.shape)))
    return np.maximum(clamped, np.negative(limit, out=limit), out=clamped)


def clamp_effort_implicit(
    envelope: PerformanceEnvelope,
    requested_effort: npt.ArrayLike,
    velocity: npt.ArrayLike,
    response: npt.ArrayLike,
    dt: float,
    applied_effort: npt.ArrayLike = 0.0,
) -> Array:
    """Clamp a requested total effort with PhysX's implicit semantics (at the end-of-step velocity).

    The result ``e`` is the clamped TOTAL actuator effort such that ``e`` and the post-step velocity
    ``velocity + response*dt*(e - applied_effort)`` satisfy both envelope curves; it keeps the sign
    of the request, never exceeds it in magnitude, and is 0 when even zero effort is infeasible.

    Args:
        envelope: The envelope (joint side, SI).
        requested_effort: Requested total actuator effort for the step [N*m or N].
        velocity: Joint velocity that already contains ``applied_effort`` [rad/s or m/s].
        response: Joint velocity change per unit joint impulse, ``1/inertia`` for one DOF
            [rad/s/(N*m*s) or m/s/(N*s)].
        dt: Time step [s], ``> 0``.
        applied_effort: Total actuator effort already applied this step [N*m or N].

    Returns:
        Clamped total effort [N*m or N], float64, broadcast shape.
    """
    if not dt > 0.0:
        raise ValueError(f"dt must be > 0, got {dt!r}")
    requested = np.asarray(requested_effort, dtype=np.float64)
    impulse = clamp_drive_impulse(
        velocity,
        np.asarray(applied_effort, dtype=np.float64) * dt,
        requested * dt,
        response,
        envelope.max_actuator_velocity,
        envelope.max_effort * dt,
        envelope.speed_effort_gradient / dt,
        envelope.velocity_dependent_resistance * dt,
    )
    # (x*dt)/dt can round one ulp above x: the clamp never grows a request, so neither may we
    return np.copysign(np.minimum(np.abs(impulse / dt), np.abs(requested)), impulse)


def _pmax(a: Array, b: Array) -> Array:
    """``PxMax(float)``: ``a > b ? a : b`` (a NaN in ``b`` survives, a NaN in ``a`` does not).

    PhysX specializes ``PxMax`` for float to ``intrinsics::selectMax``, which differs from the generic
    template ``a < b ? b : a`` exactly when a NaN is involved: the generic form would keep a NaN
    bound (e.g. ``(dev - inf) / inf``) and turn it into a NaN impulse where PhysX returns a number.
    """
    return np.where(a > b, a, b)


def _pmin(a: Array, b: Array) -> Array:
    """``PxMin(float)``: ``a < b ? a : b`` (a NaN in ``b`` survives, a NaN in ``a`` does not)."""
    return np.where(a < b, a, b)


def _bounds_positive(
    dev: Array, max_v: Array, denom1: Array, denom2: Array, impulse: Array, eps: Any, big: Any
) -> tuple[Array, Array]:
    """``computeBoundsForPositiveImpulse``: feasible [lower, upper] for a positive request."""
    bound1 = (dev - max_v) / denom1
    bound2 = (dev + max_v) / denom2
    zero = np.zeros_like(dev)
    # denom1 ~ 0: the lower curve is a yes/no test on (dev - max_v)
    flat_lower = np.where(np.abs(dev - max_v) < eps, -big, np.where((dev - max_v) > 0.0, big, -big))
    regular_lo = np.where(denom1 >= 0.0, _pmax(zero, bound1), zero)
    regular_hi = np.where(denom1 >= 0.0, _pmin(bound2, impulse), _pmin(_pmin(bound1, bound2), impulse))
    lower = np.where(np.abs(denom1) < eps, _pmax(zero, flat_lower), regular_lo)
    upper = np.where(np.abs(denom1) < eps, bound2, regular_hi)
    invalid = np.abs(denom2) < eps  # the curve is ignored
    return np.where(invalid, -big, lower), np.where(invalid, big, upper)


def _bounds_negative(
    dev: Array, max_v: Array, denom1: Array, denom2: Array, impulse: Array, eps: Any, big: Any
) -> tuple[Array, Array]:
    """``computeBoundsForNegativeImpulse``: feasible [lower, upper] for a negative (or zero) request."""
    bound1 = (dev - max_v) / denom1
    bound2 = (dev + max_v) / denom2
    zero = np.zeros_like(dev)
    flat_upper = np.where(np.abs(dev + max_v) < eps, big, np.where((dev + max_v) > 0.0, big, -big))
    regular_lo = np.where(denom2 >= 0.0, _pmax(bound1, impulse), _pmax(_pmax(bound1, bound2), impulse))
    regular_hi = np.where(denom2 >= 0.0, _pmin(zero, bound2), zero)
    lower = np.where(np.abs(denom2) < eps, bound1, regular_lo)
    upper = np.where(np.abs(denom2) < eps, _pmin(zero, flat_upper), regular_hi)
    invalid = np.abs(denom1) < eps
    return np.where(invalid, -big, lower), np.where(invalid, big, upper)


def clamp_drive_impulse(
    joint_vel0: npt.ArrayLike,
    drive_impulse0: npt.ArrayLike,
    drive_impulse: npt.ArrayLike,
    response: npt.ArrayLike,
    max_joint_vel: npt.ArrayLike,
    max_impulse: npt.ArrayLike,
    speed_impulse_gradient: npt.ArrayLike,
    velocity_dependent_resistance: npt.ArrayLike,
    *,
    dtype: npt.DTypeLike = np.float64,
) -> Array:
    """PhysX ``clampDriveImpulse``, vectorized: clamp a total drive impulse to the envelope.

    Arguments follow PhysX's order and meaning; all broadcast together.

    Args:
        joint_vel0: Joint velocity before the new impulse, containing ``drive_impulse0``
            [rad/s or m/s].
        drive_impulse0: Total drive impulse applied so far this step [N*m*s or N*s].
        drive_impulse: Requested total drive impulse [N*m*s or N*s].
        response: Joint velocity change per unit impulse [rad/s/(N*m*s) or m/s/(N*s)].
        max_joint_vel: ``maxActuatorVelocity`` [rad/s or m/s] (``inf`` allowed).
        max_impulse: ``maxEffort * dt`` [N*m*s or N*s].
        speed_impulse_gradient: ``speedEffortGradient / dt`` [(rad/s)/(N*m*s) or (m/s)/(N*s)].
        velocity_dependent_resistance: ``velocityDependentResistance * dt`` [N*m*s/rad or N*s/m]
            (times seconds: impulse per unit speed); exactly 0 selects the plain ``|x| <= max_impulse``.
        dtype: ``numpy.float64`` (default) or ``numpy.float32`` to reproduce PhysX's float arithmetic.

    Returns:
        The clamped total drive impulse [N*m*s or N*s], of ``dtype``, broadcast shape.
    """
    dt: np.dtype[Any] = np.dtype(dtype)
    v0, x0, x, r, max_v, max_x, grad, resist = (
        np.asarray(a, dtype=dt)
        for a in (
            joint_vel0,
            drive_impulse0,
            drive_impulse,
            response,
            max_joint_vel,
            max_impulse,
            speed_impulse_gradient,
            velocity_dependent_resistance,
        )
    )
    inputs = (v0, x0, x, r, max_v, max_x, grad, resist)
    shape = np.broadcast_shapes(*(a.shape for a in inputs))
    if dt == np.float64:
        # same numbers as the literal port below, a few times faster (see fast_clamp.py)
        fast = clamp_drive_impulse_symmetric(
            v0, x0, np.broadcast_to(x, shape), r, max_v, max_x, grad, resist, PX_EPS_F32, PX_MAX_F32
        )
        if fast is not None:
            return fast
    v0, x0, x, r, max_v, max_x, grad, resist = np.broadcast_arrays(*inputs)
    eps, big, one = dt.type(PX_EPS_F32), dt.type(PX_MAX_F32), dt.type(1.0)
    # IEEE overflow, inf - inf and x/0 happen inside PhysX too and are part of what we reproduce
    with np.errstate(divide="ignore", over="ignore", invalid="ignore", under="ignore"):
        dev = x0 * r - v0
        positive = x > 0.0
        # eq. 2 (speed-effort line) bounds, per sign of the request
        pos_lo, pos_hi = _bounds_positive(dev, max_v, r - grad, r + grad, x, eps, big)
        neg_lo, neg_hi = _bounds_negative(dev, max_v, r + grad, r - grad, x, eps, big)
        lo1, hi1 = np.where(positive, pos_lo, neg_lo), np.where(positive, pos_hi, neg_hi)
        # eq. 1 (effort-speed line) written as |v| <= max_x/R - (1/R)|x|
        has_resistance = resist != 0.0
        safe_resist = np.where(has_resistance, resist, one)
        inv_r = one / safe_resist
        max_v_r = max_x / safe_resist
        pos_lo2, pos_hi2 = _bounds_positive(dev, max_v_r, r - inv_r, r + inv_r, x, eps, big)
        neg_lo2, neg_hi2 = _bounds_negative(dev, max_v_r, r + inv_r, r - inv_r, x, eps, big)
        lo2 = np.where(has_resistance, np.where(positive, pos_lo2, neg_lo2), -max_x)
        hi2 = np.where(has_resistance, np.where(positive, pos_hi2, neg_hi2), max_x)
        lower = _pmax(lo1, lo2)
        upper = _pmin(hi1, hi2)
        clamped = _pmin(upper, _pmax(lower, x))  # PxClamp(x, lower, upper)
        result = np.where(lower > upper, dt.type(0.0), clamped)
        return result.astype(dt, copy=False)

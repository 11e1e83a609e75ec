"""Fast float64 evaluation of PhysX ``clampDriveImpulse`` through its sign symmetry.

PhysX's negative-request branch (``computeBoundsForNegativeImpulse``) is the mirror image of the
positive one: with ``s = +1`` for a positive request and ``-1`` otherwise,
``bounds_neg(dev, m, r+g, r-g, x) == -reversed(bounds_pos(s*dev, m, r-g, r+g, s*x))``. Negation is
exact in IEEE arithmetic, so evaluating only the positive branch on sign-normalized inputs gives the
literal port's numbers (a zero may come out as ``-0.0``) as long as no intermediate is NaN: PhysX's
``PxMax``/``PxMin`` select a NaN by argument order, which mirroring changes. The fast path therefore
declines (returns None) whenever a NaN could arise: non-finite states, responses, gradients or
resistances, a NaN cap, a subnormal resistance (1/R overflows), an overflowing ``x0*r``, or a NaN
result. The rare near-zero denominator cases (``|d| < 2^-23``) are patched only where they occur,
so the common case costs a few dozen array operations in total.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["clamp_drive_impulse_symmetric"]

Array = npt.NDArray[np.float64]


def _positive_bounds(
    dev: Array, max_v: Any, denom1: Any, denom2: Any, impulse: Array, eps: float, big: float
) -> tuple[Array, Array]:
    """``computeBoundsForPositiveImpulse`` on arrays, common branches first, guards patched after."""
    bound1 = dev - max_v
    bound1 /= denom1
    bound2 = dev + max_v
    bound2 /= denom2
    rising = np.greater_equal(denom1, 0.0)
    lower = np.where(rising, np.maximum(bound1, 0.0), 0.0)  # 0 where the lower curve falls
    upper = np.where(rising, bound2, np.minimum(bound1, bound2))
    np.minimum(upper, impulse, out=upper)
    flat = np.abs(denom1) < eps
    if np.any(flat):  # the lower curve is a yes/no test on (dev - max_v)
        gap = dev - max_v
        flat_lower = np.where((np.abs(gap) >= eps) & (gap > 0.0), big, 0.0)
        lower = np.where(flat, flat_lower, lower)
        upper = np.where(flat, bound2, upper)
    ignored = np.abs(denom2) < eps
    if np.any(ignored):
        lower = np.where(ignored, -big, lower)
        upper = np.where(ignored, big, upper)
    return np.broadcast_to(lower, dev.shape), np.broadcast_to(upper, dev.shape)


def clamp_drive_impulse_symmetric(
    v0: Array,
    x0: Array,
    x: Array,
    r: Array,
    max_v: Array,
    max_x: Array,
    grad: Array,
    resist: Array,
    eps: float,
    big: float,
) -> Array | None:
    """PhysX ``clampDriveImpulse`` in float64 (arguments as in ``clamp_drive_impulse``).

    Returns:
        The clamped impulses, or None when an intermediate NaN is possible (use the literal port).
    """
    if not (all(_finite(a) for a in (v0, x0, x, r, grad, resist)) and _not_nan(max_v) and _not_nan(max_x)):
        return None
    if np.min(np.abs(resist), where=resist != 0.0, initial=np.inf) < _SMALLEST_RESISTANCE:
        return None
    with np.errstate(all="ignore"):
        result = _clamp(v0, x0, x, r, max_v, max_x, grad, resist, eps, big)
    return None if result is None or np.isnan(np.min(result, initial=0.0)) else result


_SMALLEST_RESISTANCE = 1e-250
"""Below this 1/R and the R-curve's denominators could overflow to inf (then inf/inf = NaN)."""


def _finite(a: Array) -> bool:
    return a.size == 0 or bool(np.isfinite(np.min(a)) and np.isfinite(np.max(a)))


def _not_nan(a: Array) -> bool:
    return a.size == 0 or not np.isnan(np.min(a))


def _clamp(
    v0: Array,
    x0: Array,
    x: Array,
    r: Array,
    max_v: Array,
    max_x: Array,
    grad: Array,
    resist: Array,
    eps: float,
    big: float,
) -> Array | None:
    sign = np.where(x > 0.0, 1.0, -1.0)
    dev = np.multiply(x0, r, out=np.empty(x.shape))
    dev -= v0
    dev *= sign
    if not _finite(dev):  # x0*r overflowed
        return None
    request = x * sign
    lower, upper = _positive_bounds(dev, max_v, r - grad, r + grad, request, eps, big)
    if np.any(resist != 0.0):
        inv = 1.0 / resist
        max_v2 = max_x / resist
        lo2, hi2 = _positive_bounds(dev, max_v2, r - inv, r + inv, request, eps, big)
        plain = np.broadcast_to(resist == 0.0, dev.shape)
        if np.any(plain):
            lo2 = np.where(plain, -max_x, lo2)
            hi2 = np.where(plain, max_x, hi2)
        lower = np.maximum(lower, lo2)
        upper = np.minimum(upper, hi2)
    else:
        lower = np.maximum(lower, -max_x)
        upper = np.minimum(upper, max_x)
    empty = lower > upper
    result = np.maximum(request, lower, out=np.empty(x.shape))
    np.minimum(result, upper, out=result)
    result[empty] = 0.0
    result *= sign
    return result

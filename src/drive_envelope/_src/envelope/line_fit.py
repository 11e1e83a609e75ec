"""One line of a fit: the tightest bound ``w <= intercept - slope*u`` of a set of samples.

For eq. 1 ``u = |v|`` and ``w = |tau|``; for eq. 2 ``u = |tau|`` and ``w = |v|``. "Tightest" is the
smallest mean gap between the samples and the line with at most a fraction ``q`` of them above it:
a pinball loss, convex in the slope, minimized by golden-section search; the intercept is then the
``1 - q`` quantile of ``w + slope*u``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

_GOLDEN_STEPS = 48  # golden-section iterations: the bracket shrinks by 0.618**48 ~ 1e-10


def _top_index(size: int, q: float) -> int:
    """Index, in sorted order, of the smallest bound with at most a fraction ``q`` of values above."""
    return min(max(math.ceil((1.0 - q) * size) - 1, 0), size - 1)


def top(values: FloatArray, q: float) -> float:
    """Smallest bound with at most a fraction ``q`` of ``values`` above it."""
    if q == 0.0:
        return float(values.max())
    k = _top_index(values.size, q)
    return float(np.partition(values, k)[k])


def line_cost(a: FloatArray, q: float) -> float:
    """Cost of the tightest bound of ``a = w + s*u`` (convex in the slope).

    The mean gap below the bound plus ``(1-q)/q`` times the mean excess above it: a pinball loss,
    minimized over the bound by the ``1 - q`` quantile; for q = 0 just the mean gap.
    """
    mean = float(a.sum()) / a.size
    if q == 0.0:
        return float(a.max()) - mean
    k = _top_index(a.size, q)
    ordered = np.partition(a, k)
    bound = float(ordered[k])
    excess = float(ordered[k + 1 :].sum()) - bound * (a.size - k - 1)
    # mean(gap) + mean(excess) * (1 + (1-q)/q) with gap = bound - a and excess = max(a - bound, 0)
    return bound - mean + excess / (q * a.size)


def _golden(cost: Callable[[float], float], low: float, high: float) -> float:
    """Minimizer of a unimodal ``cost`` on ``[low, high]`` by golden-section search."""
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = low, high
    c, d = b - ratio * (b - a), a + ratio * (b - a)
    fc, fd = cost(c), cost(d)
    for _ in range(_GOLDEN_STEPS):
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - ratio * (b - a)
            fc = cost(c)
        else:
            a, c, fc = c, d, fd
            d = a + ratio * (b - a)
            fd = cost(d)
    best = min((cost(low), low), (fc, c), (fd, d), (cost(high), high))
    return best[1]


def fit_line(
    u: FloatArray, w: FloatArray, q: float, slope: float | None, intercept: float | None
) -> tuple[float, float, bool]:
    """Tightest line ``w <= intercept - slope*u`` (slope >= 0) with at most a fraction ``q`` above it.

    Args:
        u: Abscissae of the samples the line bounds [SI].
        w: Ordinates of the same samples [SI].
        q: Fraction of the samples allowed above the line, in ``[0, 0.5]``.
        slope: Fixed slope, or None to fit it.
        intercept: Fixed intercept, or None to fit it.

    Returns:
        ``(slope, intercept, slope_identified)``; fixed values are kept as given. The slope is not
        identified (and reported as 0) when the samples span no range of ``u``.
    """
    if slope is not None and intercept is not None:
        return slope, intercept, True
    if u.size == 0:  # no sample on this line: nothing to fit (callers keep both sides populated)
        return slope or 0.0, 0.0 if intercept is None else intercept, False
    if slope is not None:
        return slope, top(w + slope * u, q), True
    scale = max(float(np.abs(u).max()), 1e-300)
    if intercept is not None:
        moving = u > 1e-12 * scale
        if not moving.any():
            return 0.0, intercept, False
        # the largest slope keeping all but a fraction q below the line through (0, intercept)
        ratios = (intercept - w[moving]) / u[moving]
        bound = float(ratios.min()) if q == 0.0 else float(np.quantile(ratios, q, method="lower"))
        return max(bound, 0.0), intercept, True
    if float(np.ptp(u)) <= 1e-9 * scale:
        return 0.0, top(w, q), False

    def cost(s: float) -> float:
        return line_cost(w + s * u, q)

    high = max(float(np.ptp(w)), 1e-300) / float(np.ptp(u))
    for _ in range(60):  # widen the bracket until the cost rises: the minimum then lies below `2*high`
        if cost(2.0 * high) >= cost(high):
            break
        high *= 2.0
    best = _golden(cost, 0.0, 2.0 * high)
    return best, top(w + best * u, q), True

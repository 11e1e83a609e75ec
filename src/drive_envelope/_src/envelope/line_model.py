"""A fit's structures and their fits: eq. 1 only, both lines split at a speed, or eq. 2 only.

The samples here are a fit's frontier samples, folded into the first quadrant (``x = |v|``,
``y = |tau|``)::

    y <= max_effort - R*x            (eq. 1)          x <= max_actuator_velocity - G*y   (eq. 2)

* **eq. 1 only**: ``max_actuator_velocity = inf``.
* **both lines**: the samples are split at a speed ``x_c`` (eq. 1 below, eq. 2 above) and ``x_c`` is
  scanned; samples bounded by the wrong line near the corner lie inside it and do not move it.
* **eq. 2 only**: the speed-torque line through every sample, with eq. 1 flat at its stall effort
  (or at the largest effort seen, when the samples stay far from standstill).

Which structure the data support is :mod:`.fit_choice`'s decision.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.line_fit import fit_line, top

FloatArray = npt.NDArray[np.float64]
Structure = Literal["effort", "both", "speed"]

_SPLIT_CANDIDATES = 25  # split speeds tried per scan pass (two passes: coarse, then around the best)
_SPEED_CAP_SHARE = 0.05  # with an allowance, eq. 2 only: max_effort leaves out the top 5 % at most
STANDSTILL = 0.05
"""Samples below this fraction of the top speed are near standstill: a line seen there is
extrapolated to zero speed (max_effort), a line seen only above it is not."""


@dataclass(frozen=True, slots=True)
class Model:
    """Parameters of one fit, its structure and which slopes the data identified."""

    lines: Structure
    effort: float  # max_effort [N*m or N]
    resistance: float  # velocity_dependent_resistance [N*m*s/rad or N*s/m]
    velocity: float  # max_actuator_velocity [rad/s or m/s]; inf for eq. 1 only
    gradient: float  # speed_effort_gradient [(rad/s)/(N*m) or (m/s)/N]
    split: float  # eq. 1 fits samples with x <= split: inf for eq. 1 only, -inf for eq. 2 only
    resistance_identified: bool
    gradient_identified: bool

    def gauge(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """Each sample's radius as a multiple of the boundary's along its ray (> 1 outside)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            eq1 = (
                (y + self.resistance * x) / self.effort if self.effort > 0.0 else np.where(y > 0, np.inf, 0.0)
            )
            eq2 = (
                (x + self.gradient * y) / self.velocity if math.isfinite(self.velocity) else np.zeros(x.size)
            )
        return np.maximum(eq1, eq2)

    def on_eq1(self, x: FloatArray, y: FloatArray) -> npt.NDArray[np.bool_]:
        """True where eq. 1 bounds the sample (its ray from the origin meets eq. 1 first)."""
        if not math.isfinite(self.velocity):
            return np.ones(x.size, dtype=bool)
        if self.effort <= 0.0:
            return np.zeros(x.size, dtype=bool)
        return (y + self.resistance * x) / self.effort >= (x + self.gradient * y) / self.velocity


def fit_structure(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], lines: Structure, split: float
) -> Model:
    """Fit the given structure; ``split`` is the speed separating eq. 1 from eq. 2 samples (both)."""
    if lines == "speed":
        return _fit_speed_line(x, y, q, fixed)
    below = x <= split if lines == "both" else np.ones(x.size, dtype=bool)
    slope, cap, r_ok = fit_line(
        x[below], y[below], q, fixed.get("velocity_dependent_resistance"), fixed.get("max_effort")
    )
    if lines == "effort":
        gradient = fixed.get("speed_effort_gradient", 0.0)
        limit = fixed.get("max_actuator_velocity", math.inf)
        return Model("effort", cap, slope, limit, gradient, math.inf, r_ok, False)
    above = ~below
    gradient, limit, g_ok = fit_line(
        y[above], x[above], q, fixed.get("speed_effort_gradient"), fixed.get("max_actuator_velocity")
    )
    if q == 0.0:  # a sample outside either half-plane is outside the envelope: each must hold all
        if "max_effort" not in fixed:
            cap = max(cap, float((y + slope * x).max()))
        elif "velocity_dependent_resistance" not in fixed:
            slope = min(slope, _containing_slope(x, y, cap))
        if "max_actuator_velocity" not in fixed:
            limit = max(limit, float((x + gradient * y).max()))
        elif "speed_effort_gradient" not in fixed:
            # a held intercept cannot move out to the samples on the other side of the split: the
            # slope comes down instead (a fixed speed above every point left the stall point out)
            gradient = min(gradient, _containing_slope(y, x, limit))
    return Model("both", cap, slope, limit, gradient, split, r_ok, g_ok)


def _containing_slope(u: FloatArray, w: FloatArray, intercept: float) -> float:
    """Largest slope of ``w <= intercept - slope*u`` holding every sample a slope >= 0 can hold.

    Samples at or beyond the intercept are outside for every slope (cut off by the held value) and
    do not bound it; inf when no sample does.
    """
    bounding = (u > 0.0) & (w < intercept)
    if not bounding.any():
        return math.inf
    return float(((intercept - w[bounding]) / u[bounding]).min())


def _fit_speed_line(x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float]) -> Model:
    """Eq. 2 through every sample; eq. 1 flat (R = 0) at the line's stall effort or the top effort.

    When the samples come near standstill (within :data:`STANDSTILL` of the top speed) max_effort
    is the line's effort at zero speed, its stall effort, as eq. 1's intercept is extrapolated to
    zero speed. Otherwise eq. 1 was never reached and max_effort is the largest effort seen (with
    an allowance, the top of all but a ``min(q, 5 %)`` share, so that a spike does not set it):
    extrapolating further would claim an effort no sample shows.
    """
    gradient, limit, g_ok = fit_line(
        y, x, q, fixed.get("speed_effort_gradient"), fixed.get("max_actuator_velocity")
    )
    resistance = fixed.get("velocity_dependent_resistance", 0.0)
    seen = top(y + resistance * x, min(q, _SPEED_CAP_SHARE))
    if "max_effort" in fixed:
        cap = fixed["max_effort"]
    elif gradient > 0.0 and float(x.min()) <= STANDSTILL * float(x.max()):
        cap = max(limit / gradient, seen) if q == 0.0 else limit / gradient
    else:
        cap = seen
    return Model("speed", cap, resistance, limit, gradient, -math.inf, True, g_ok)


def _gaps(model: Model, x: FloatArray, y: FloatArray, x_scale: float, y_scale: float) -> FloatArray:
    """Gap of each sample to the line fitting it, as a fraction of the data range (>= 0 inside)."""
    gap = (model.effort - model.resistance * x - y) / y_scale
    above = x > model.split
    gap[above] = (model.velocity - model.gradient * y[above] - x[above]) / x_scale
    return gap


def line_residuals(model: Model, x: FloatArray, y: FloatArray) -> FloatArray:
    """Each sample's excess over the line fitting it, as a fraction of the data range (> 0 outside)."""
    return -_gaps(model, x, y, max(float(x.max()), 1e-300), max(float(y.max()), 1e-300))


def model_cost(model: Model, x: FloatArray, y: FloatArray) -> float:
    """Mean gap of the samples inside their lines, as a fraction of the data range.

    Samples outside (the outlier allowance) are left out, so gross outliers, however far, do not
    decide the split or the choice between one and two lines.
    """
    gap = _gaps(model, x, y, max(float(x.max()), 1e-300), max(float(y.max()), 1e-300))
    inside = gap[gap >= 0.0]
    return float(inside.mean()) if inside.size else 0.0


def scan_split(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], least: int
) -> Model | None:
    """Best two-line fit over split speeds leaving ``least`` samples on each side; None if too few."""
    order = np.sort(x)
    n = order.size
    if n < 2 * least:
        return None

    def score(split: float) -> tuple[float, Model]:
        model = fit_structure(x, y, q, fixed, "both", split)
        return model_cost(model, x, y), model

    def candidates(first: int, last: int) -> FloatArray:
        # split speeds leaving `least` samples on each side; ties (a vertical eq. 2) stay together
        values = np.unique(order[np.linspace(first, last, _SPLIT_CANDIDATES).astype(int)])
        below = np.searchsorted(order, values, side="right")
        return values[(below >= least) & (n - below >= least)]

    low, high = least - 1, n - least - 1
    coarse = candidates(low, high)
    if coarse.size == 0:
        return None
    best = min(coarse.tolist(), key=lambda value: score(value)[0])
    k = int(np.searchsorted(order, best, side="right")) - 1
    step = max((high - low) // (_SPLIT_CANDIDATES - 1), 1)
    fine = np.union1d(candidates(max(low, k - step), min(high, k + step)), [best])
    return min((score(value) for value in fine.tolist()), key=lambda item: item[0])[1]


def losses(model: Model, x: FloatArray, y: FloatArray, q: float) -> FloatArray:
    """Each sample's share of the fit's cost: its gap inside, ``(1-q)/q`` times its excess outside."""
    gap = _gaps(model, x, y, max(float(x.max()), 1e-300), max(float(y.max()), 1e-300))
    if q == 0.0:
        return np.maximum(gap, 0.0)
    return np.where(gap >= 0.0, gap, -gap * (1.0 - q) / q)

"""Fitting an envelope to measured samples of saturated operation (e.g. a torque-speed sweep).

The samples are folded into the first quadrant (``x = |v|``, ``y = |tau|``; the envelope is symmetric)
and the fit looks for the tightest region of the spec's form that contains them::

    y <= max_effort - R*x            (eq. 1)          x <= max_actuator_velocity - G*y   (eq. 2)

"Tightest" is the smallest mean gap between each sample and the line that bounds it (the area
between the data and the boundary), subject to at most a fraction ``outlier_quantile`` of the
samples lying outside (0: all inside). For one line this is a convex problem in its slope, solved by
golden-section search; the intercept is then the ``1 - q`` quantile of ``y + R*x`` (or ``x + G*y``).
With two lines the samples are split at a speed ``x_c`` (eq. 1 below, eq. 2 above) and ``x_c`` is
scanned. Samples bounded by the wrong line near the corner lie inside it and do not move it.

Identifiability: eq. 2 is fitted only when the data show it, i.e. when two lines at least halve the
mean gap of the best single line (noise alone gives a ratio near 1). Otherwise
``max_actuator_velocity`` is reported as ``inf`` (not identified: the data
never reach the speed limit) rather than the largest speed seen. A slope whose samples span no range
(e.g. all at one speed) is reported as 0, not identified.

Uncertainty: the standard deviation and 95 % interval over bootstrap resamples of the samples, with
the model structure (which lines, split speed) of the main fit. For a frontier (q = 0 is a maximum)
the bootstrap spread is a rough scale, not an exact confidence interval.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.fit_input import MAX_BOOTSTRAP, check_count, fit_samples_input
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.params.table import si_unit

__all__ = ["FitOptions", "FitResult", "ParameterEstimate", "ParameterStatus", "fit_samples"]

FloatArray = npt.NDArray[np.float64]
ParameterStatus = Literal["fitted", "fixed", "unidentified"]

_GOLDEN_STEPS = 48  # golden-section iterations: the bracket shrinks by 0.618**48 ~ 1e-10
_SPLIT_CANDIDATES = 25  # split speeds tried per scan pass (two passes: coarse, then around the best)
_EQ2_COST_RATIO = 0.5  # two lines must at least halve the one-line cost to count as identified


@dataclass(frozen=True, kw_only=True, slots=True)
class FitOptions:
    """How to fit an envelope to samples."""

    joint: JointType = "revolute"
    """Joint type of the samples (fixes the units): ``"revolute"`` or ``"prismatic"``."""
    outlier_quantile: float = 0.0
    """Fraction of samples allowed outside the fitted envelope, in ``[0, 0.5]``. 0 gives the tightest
    envelope containing every sample; 0.5 the central line through noisy saturated samples."""
    fixed: Mapping[str, float] = field(default_factory=dict)
    """Parameters held at given values [SI], by field name (``max_actuator_velocity`` may be inf)."""
    bootstrap: int = 200
    """Bootstrap resamples for the uncertainties, 0 .. :data:`MAX_BOOTSTRAP`; 0 skips them."""
    seed: int = 0
    """Seed of the bootstrap's random generator, an integer >= 0 (results are reproducible)."""
    min_segment_samples: int | None = None
    """Fewest samples that identify a line; None: ``max(5, 2 %)`` of the samples."""
    name: str = ""
    """Name written into the fitted envelope."""

    def __post_init__(self) -> None:
        if self.joint not in ("revolute", "prismatic"):
            raise InputError(f"joint: expected 'revolute' or 'prismatic', got {self.joint!r}")
        quantile = self.outlier_quantile
        if isinstance(quantile, bool) or not isinstance(quantile, (int, float)) or not 0.0 <= quantile <= 0.5:
            raise InputError(f"outlier-quantile: expected a number in [0, 0.5], got {quantile!r}")
        check_count("bootstrap", self.bootstrap, MAX_BOOTSTRAP)
        check_count("seed", self.seed, None)
        least = self.min_segment_samples
        if least is not None and (isinstance(least, bool) or not isinstance(least, int) or least < 2):
            raise InputError(f"min_segment_samples: expected an integer >= 2 or None, got {least!r}")
        for key, value in self.fixed.items():
            if key not in ENVELOPE_FIELDS:
                raise InputError(
                    f"fix: unknown parameter {key!r}; expected one of {', '.join(ENVELOPE_FIELDS)}"
                )
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(f"fix: {key} must be a number, got {value!r}")
            if not value >= 0.0 or (math.isinf(value) and key != "max_actuator_velocity"):
                raise InputError(
                    f"fix: {key} must be >= 0 and finite (only max_actuator_velocity may be inf), "
                    f"got {value!r}"
                )


@dataclass(frozen=True, kw_only=True, slots=True)
class ParameterEstimate:
    """One fitted parameter with its uncertainty."""

    name: str
    """Field name (``max_effort``, ...)."""
    value: float
    """Estimate [SI unit of the field]; ``inf`` for an unidentified ``max_actuator_velocity``."""
    unit: str
    """SI unit (``N*m``, ``rad/s``, ...)."""
    status: ParameterStatus
    """``"fitted"``, ``"fixed"`` (held by the user) or ``"unidentified"`` (the data cannot tell)."""
    std: float | None
    """Bootstrap standard deviation [unit]; None when not fitted or not bootstrapped."""
    interval: tuple[float, float] | None
    """Bootstrap 2.5 % and 97.5 % percentiles [unit]; None when ``std`` is None."""
    note: str = ""
    """Why a parameter is unidentified, or how it was obtained."""


@dataclass(frozen=True, kw_only=True, slots=True)
class FitResult:
    """A fitted envelope, its parameters with uncertainties, and the residuals."""

    envelope: PerformanceEnvelope
    """The fitted envelope (joint side, SI)."""
    parameters: tuple[ParameterEstimate, ...]
    """The four parameters in :data:`ENVELOPE_FIELDS` order."""
    samples: int
    """Number of samples fitted."""
    samples_outside: int
    """Samples outside the fitted envelope (at most about ``outlier_quantile`` of them)."""
    effort_residuals: FloatArray
    """``|tau| - (max_effort - R|v|)`` of the samples bounded by eq. 1, positive outside [N*m or N]."""
    velocity_residuals: FloatArray
    """``|v| - (max_actuator_velocity - G|tau|)`` of the samples bounded by eq. 2, positive outside
    [rad/s or m/s]; empty when eq. 2 is not identified."""
    notes: tuple[str, ...] = ()
    """Remarks on identifiability and method."""

    def estimate(self, name: str) -> ParameterEstimate:
        """The estimate of parameter ``name``."""
        for parameter in self.parameters:
            if parameter.name == name:
                return parameter
        raise KeyError(name)

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible dict: the four parameters (SI) at the top level, then their uncertainties."""
        data: dict[str, Any] = {"name": self.envelope.name, "joint": self.envelope.joint}
        data.update({p.name: _json_float(p.value) for p in self.parameters})
        data["uncertainty"] = {p.name: p.std for p in self.parameters}
        data["interval95"] = {
            p.name: None if p.interval is None else list(p.interval) for p in self.parameters
        }
        data["status"] = {p.name: p.status for p in self.parameters}
        data["units"] = {p.name: p.unit for p in self.parameters}
        data["samples"] = self.samples
        data["samples_outside"] = self.samples_outside
        data["residuals"] = {
            "effort": _residual_summary(self.effort_residuals),
            "velocity": _residual_summary(self.velocity_residuals),
        }
        data["notes"] = list(self.notes)
        return data


def _json_float(value: float) -> float | str:
    return value if math.isfinite(value) else ("inf" if value > 0 else "-inf")


def _residual_summary(residuals: FloatArray) -> dict[str, Any]:
    if residuals.size == 0:
        return {"count": 0, "rms": None, "max": None, "median": None}
    return {
        "count": int(residuals.size),
        "rms": float(np.sqrt(np.mean(residuals**2))),
        "max": float(residuals.max()),
        "median": float(np.median(residuals)),
    }


# -- one line -------------------------------------------------------------------------------------


def _top_index(size: int, q: float) -> int:
    """Index, in sorted order, of the smallest bound with at most a fraction ``q`` of values above."""
    return min(max(math.ceil((1.0 - q) * size) - 1, 0), size - 1)


def _top(values: FloatArray, q: float) -> float:
    """Smallest bound with at most a fraction ``q`` of ``values`` above it."""
    if q == 0.0:
        return float(values.max())
    k = _top_index(values.size, q)
    return float(np.partition(values, k)[k])


def _line_cost(a: FloatArray, q: float) -> float:
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


def _frontier(
    u: FloatArray, w: FloatArray, q: float, slope: float | None, intercept: float | None
) -> tuple[float, float, bool]:
    """Tightest line ``w <= intercept - slope*u`` (slope >= 0) with at most a fraction ``q`` above it.

    Returns ``(slope, intercept, slope_identified)``; fixed values are kept as given.
    """
    if slope is not None and intercept is not None:
        return slope, intercept, True
    if u.size == 0:  # no sample on this line: nothing to fit (callers keep both sides populated)
        return slope or 0.0, 0.0 if intercept is None else intercept, False
    if slope is not None:
        return slope, _top(w + slope * u, q), True
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
        return 0.0, _top(w, q), False

    def cost(s: float) -> float:
        return _line_cost(w + s * u, q)

    high = max(float(np.ptp(w)), 1e-300) / float(np.ptp(u))
    for _ in range(60):  # widen the bracket until the cost rises: the minimum then lies below `2*high`
        if cost(2.0 * high) >= cost(high):
            break
        high *= 2.0
    best = _golden(cost, 0.0, 2.0 * high)
    return best, _top(w + best * u, q), True


# -- two lines ------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Model:
    """Parameters of one fit and which slopes the data identified."""

    effort: float
    resistance: float
    velocity: float
    gradient: float
    split: float  # speed separating eq. 1 samples (x <= split) from eq. 2 samples; inf: eq. 1 only
    resistance_identified: bool
    gradient_identified: bool


def _fit_structure(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], split: float
) -> _Model:
    """Fit with a given structure: eq. 1 only (``split = inf``) or both lines split at ``split``."""
    below = x <= split
    slope, top, r_ok = _frontier(
        x[below], y[below], q, fixed.get("velocity_dependent_resistance"), fixed.get("max_effort")
    )
    if math.isinf(split):
        return _Model(top, slope, math.inf, fixed.get("speed_effort_gradient", 0.0), split, r_ok, False)
    above = ~below
    gradient, limit, g_ok = _frontier(
        y[above], x[above], q, fixed.get("speed_effort_gradient"), fixed.get("max_actuator_velocity")
    )
    if q == 0.0:  # a sample outside either half-plane is outside the envelope: each must hold all
        if "max_effort" not in fixed:
            top = max(top, float((y + slope * x).max()))
        if "max_actuator_velocity" not in fixed:
            limit = max(limit, float((x + gradient * y).max()))
    return _Model(top, slope, limit, gradient, split, r_ok, g_ok)


def _gaps(model: _Model, x: FloatArray, y: FloatArray, x_scale: float, y_scale: float) -> FloatArray:
    """Gap of each sample to the line bounding it, as a fraction of the data range (>= 0 inside)."""
    gap = (model.effort - model.resistance * x - y) / y_scale
    if math.isfinite(model.split):
        above = x > model.split
        gap[above] = (model.velocity - model.gradient * y[above] - x[above]) / x_scale
    return gap


def _model_cost(model: _Model, x: FloatArray, y: FloatArray, q: float) -> float:
    """Mean gap of the samples inside their lines, as a fraction of the data range.

    Samples outside (the outlier allowance) are left out, so gross outliers, however far, do not
    decide the split or the choice between one and two lines.
    """
    gap = _gaps(model, x, y, max(float(x.max()), 1e-300), max(float(y.max()), 1e-300))
    inside = gap[gap >= 0.0]
    return float(inside.mean()) if inside.size else 0.0


def _scan_split(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], least: int
) -> _Model | None:
    """Best two-line fit over split speeds leaving ``least`` samples on each side; None if too few."""
    order = np.sort(x)
    n = order.size
    if n < 2 * least:
        return None

    def score(split: float) -> tuple[float, _Model]:
        model = _fit_structure(x, y, q, fixed, split)
        return _model_cost(model, x, y, q), model

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


def _choose_model(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], least: int
) -> tuple[_Model, str]:
    """The eq. 1-only or the two-line model, whichever the data support; and a note on the choice."""
    speed_fixed = fixed.get("max_actuator_velocity")
    one = _fit_structure(x, y, q, fixed, math.inf)
    if speed_fixed is not None and math.isinf(speed_fixed):
        return one, "max_actuator_velocity fixed at inf: eq. 2 not fitted"
    two = _scan_split(x, y, q, fixed, least)
    if two is None:
        if speed_fixed is not None:
            raise InputError(
                f"fix: max_actuator_velocity needs at least {2 * least} samples to place eq. 2, got {x.size}"
            )
        return one, f"eq. 2 not identified: {x.size} samples, fewer than {2 * least} needed for two lines"
    if speed_fixed is not None:
        return two, ""
    # two lines only when they fit clearly better than one (noise alone gives a ratio near 1)
    if _model_cost(two, x, y, q) < _EQ2_COST_RATIO * _model_cost(one, x, y, q):
        return two, ""
    return one, (
        f"max_actuator_velocity not identified: no samples show the speed limit (eq. 2); the highest "
        f"|velocity| seen is {float(x.max()):.6g}, so the limit is at least that; reported as inf"
    )


# -- public ---------------------------------------------------------------------------------------


def fit_samples(
    velocity: npt.ArrayLike, effort: npt.ArrayLike, options: FitOptions | None = None
) -> FitResult:
    """Fit the tightest envelope of the spec's form to samples of saturated operation.

    Args:
        velocity: Joint velocity samples [rad/s or m/s]; only ``|velocity|`` matters.
        effort: Effort samples at the same instants [N*m or N]; only ``|effort|`` matters.
        options: Joint type, outlier quantile, fixed parameters, bootstrap size.

    Returns:
        A :class:`FitResult` with the envelope, each parameter's estimate and bootstrap uncertainty,
        and the residuals.

    Raises:
        InputError: arrays of different shapes, fewer than 3 samples, NaN or infinite values,
            magnitudes above :data:`MAX_SAMPLE`.
    """
    options = options or FitOptions()
    x, y = fit_samples_input(velocity, effort)
    q, fixed = options.outlier_quantile, dict(options.fixed)
    least = options.min_segment_samples or max(5, math.ceil(0.02 * x.size))
    model, note = _choose_model(x, y, q, fixed, least)
    notes = [note] if note else []
    spreads = _bootstrap(x, y, q, fixed, model, options)
    parameters = _estimates(model, fixed, options, spreads, notes, x)
    values = {p.name: p.value for p in parameters}
    envelope = PerformanceEnvelope(joint=options.joint, name=options.name, **values)
    below = x <= model.split
    effort_residuals = y[below] - (model.effort - model.resistance * x[below])
    velocity_residuals = x[~below] - (model.velocity - model.gradient * y[~below])
    effort_margin, velocity_margin = envelope.margins(x, y)
    slack = 1e-9
    outside = (effort_margin < -slack * max(envelope.max_effort, 1.0)) | (
        velocity_margin
        < -slack * (envelope.max_actuator_velocity if math.isfinite(envelope.max_actuator_velocity) else 1.0)
    )
    if options.bootstrap:
        notes.append(
            f"uncertainties: {options.bootstrap} bootstrap resamples (a rough scale for a frontier fit)"
        )
    return FitResult(
        envelope=envelope,
        parameters=parameters,
        samples=int(x.size),
        samples_outside=int(np.count_nonzero(outside)),
        effort_residuals=effort_residuals,
        velocity_residuals=velocity_residuals,
        notes=tuple(notes),
    )


def _bootstrap(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], model: _Model, options: FitOptions
) -> dict[str, FloatArray]:
    """Parameter values over bootstrap resamples, refitted with the main fit's structure."""
    if not options.bootstrap:
        return {}
    rng = np.random.default_rng(options.seed)
    rows = []
    for _ in range(options.bootstrap):
        pick = rng.integers(0, x.size, x.size)
        xs, ys = x[pick], y[pick]
        split = model.split
        if math.isfinite(split) and not (np.any(xs <= split) and np.any(xs > split)):
            continue  # a resample that lost one side entirely cannot place that line
        refit = _fit_structure(xs, ys, q, fixed, split)
        rows.append((refit.effort, refit.velocity, refit.resistance, refit.gradient))
    if len(rows) < 2:
        return {}
    table = np.array(rows)
    return dict(zip(ENVELOPE_FIELDS, table.T, strict=True))


_UNIDENTIFIED = {
    "max_actuator_velocity": "the data never reach the speed limit: reported as inf",
    "velocity_dependent_resistance": "the samples on eq. 1 span no speed range: 0 assumed",
    "speed_effort_gradient": "the samples on eq. 2 span no effort range: 0 assumed (a vertical speed limit)",
}


def _estimates(
    model: _Model,
    fixed: Mapping[str, float],
    options: FitOptions,
    spreads: dict[str, FloatArray],
    notes: list[str],
    x: FloatArray,
) -> tuple[ParameterEstimate, ...]:
    """One :class:`ParameterEstimate` per field; appends identifiability remarks to ``notes``."""
    two_lines = math.isfinite(model.split)
    values = {
        "max_effort": max(model.effort, 0.0),
        "max_actuator_velocity": model.velocity
        if two_lines
        else fixed.get("max_actuator_velocity", math.inf),
        "velocity_dependent_resistance": model.resistance,
        "speed_effort_gradient": model.gradient if two_lines else fixed.get("speed_effort_gradient", 0.0),
    }
    identified = {
        "max_effort": True,
        "max_actuator_velocity": two_lines,
        "velocity_dependent_resistance": model.resistance_identified,
        "speed_effort_gradient": two_lines and model.gradient_identified,
    }
    estimates = []
    for name in ENVELOPE_FIELDS:
        spread = None
        status: ParameterStatus
        if name in fixed:
            status, note = "fixed", "fixed by the user"
        elif not identified[name]:
            status, note = (
                "unidentified",
                _UNIDENTIFIED[name] if two_lines or name != "speed_effort_gradient" else "",
            )
            if name != "max_actuator_velocity" and note:  # the speed limit has its own note already
                notes.append(f"{name} not identified: {note}")
        else:
            status, note, spread = "fitted", "", spreads.get(name)
            if name == "max_effort":
                note = _extrapolation_note(x[x <= model.split], float(x.max()), options.joint)
                notes.extend([f"max_effort {note}"] if note else [])
        estimates.append(
            ParameterEstimate(
                name=name,
                value=fixed.get(name, values[name]),
                unit=si_unit(name, options.joint),
                status=status,
                std=None if spread is None else float(np.std(spread, ddof=1)),
                interval=None
                if spread is None
                else (float(np.percentile(spread, 2.5)), float(np.percentile(spread, 97.5))),
                note=note,
            )
        )
    return tuple(estimates)


def _extrapolation_note(speeds: FloatArray, top_speed: float, joint: JointType) -> str:
    """A note when max_effort is extrapolated: no eq. 1 sample within 5 % of the top speed of zero."""
    low = float(speeds.min()) if speeds.size else 0.0
    if low <= 0.05 * top_speed:
        return ""
    return (
        f"extrapolated to zero speed from |velocity| >= {low:.6g} {si_unit('max_actuator_velocity', joint)}"
    )

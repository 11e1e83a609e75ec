"""Which lines the frontier shows: eq. 1 only, both lines, or eq. 2 only (the speed-torque line).

* Two lines are fitted only when the data show a speed limit: they must fit clearly better than
  one (:func:`_clearly_better`), have a real knee (eq. 1 flatter than eq. 2), bound the frontier
  (no saturated samples far beyond eq. 2), and the samples beyond the split must lie along the
  eq. 2 line (on it within the noise, covering a good part of the effort range). Samples that bend
  down at the top speed (a drive leaving saturation) are a curve, not a line, so they do not
  invent a speed limit; such a limit is reported as ``inf`` (not identified).
* One line that reaches zero effort at a finite speed within the data (at most 5 % beyond the
  fastest sample) is the speed-torque line of eq. 2 (the back-EMF line of a motor at a fixed
  voltage), not a loss line: max_actuator_velocity and speed_effort_gradient come from it,
  velocity_dependent_resistance is 0 and max_effort is the largest effort seen (the stall effort
  when the line reaches standstill). This is the rule the datasheet derivation applies to a stored
  curve (``datasheet/losses.py``: a curve falling to zero effort within 1.05 times its fastest
  point is the speed-torque line).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.line_model import Model, fit_structure, losses, model_cost, scan_split
from drive_envelope._src.errors import InputError

FloatArray = npt.NDArray[np.float64]

ON_LINE = 0.01
"""A sample within this fraction of a line's cap is on the line (``check``'s default limit band)."""
REACH = 1.05
"""A line reaching zero effort within this factor of the fastest sample is the speed-torque line
(the factor the datasheet derivation uses for a stored curve)."""
_ROUNDING = 1e-4  # gains and "on a line" below this fraction of the range are rounding in logs
_EQ2_COST_RATIO = 0.5  # two lines that halve the one-line cost are clearly better ...
_T_STAT = 5.0  # ... as are two lines whose per-sample gain exceeds this many standard errors
_PARALLEL = 0.8  # two lines with R * G above this are one line (both bind only if R * G < 1)
_BEYOND = 0.02  # two lines with more than this share of the frontier far outside are no speed limit
_EQ2_COVER = 0.5  # eq. 2's on-line samples must cover at least half the effort range it bounds ...
_EQ2_REACH = 0.4  # ... and half of this share of the largest effort (20 %)


def _clearly_better(two: Model, one: Model, x: FloatArray, y: FloatArray, q: float) -> bool:
    """Whether two lines fit clearly better than one.

    Either they at least halve the mean gap (a clean or small set: a digitized curve), or their
    per-sample losses are lower by more than :data:`_T_STAT` standard errors (a large noisy set
    fitted with an outlier allowance, where the noise keeps both mean gaps high). A single line
    split in two gains about one standard error of noise at most. A containing fit rests on a few
    extreme samples, so it has the first test only.
    """
    # a gain below rounding is no gain, however large a share (a noise-free line split in two)
    cost_one, cost_two = model_cost(one, x, y), model_cost(two, x, y)
    if cost_one - cost_two > _ROUNDING and cost_two < _EQ2_COST_RATIO * cost_one:
        return True
    if q == 0.0:  # a containing fit rests on a few extreme samples: no standard error to speak of
        return False
    gain = losses(one, x, y, q) - losses(two, x, y, q)
    mean = float(gain.mean())
    spread = float(np.std(gain, ddof=1)) if gain.size > 1 else 0.0
    return mean > _ROUNDING and mean > _T_STAT * spread / math.sqrt(gain.size)


def _line_band(model: Model, x: FloatArray, y: FloatArray) -> float:
    """How close to a line a sample must be to count as on it, as a fraction of the line's cap.

    Four times the scatter of eq. 1's samples about their line (1.4826 median absolute deviations:
    the same sensors measured both lines), at least :data:`_ROUNDING` and at most :data:`ON_LINE`.
    Noise-free samples thus need to be collinear to rounding, which a curve never is over a range.
    """
    below = x <= model.split
    if not below.any() or model.effort <= 0.0:
        return ON_LINE
    residual = (model.effort - model.resistance * x[below] - y[below]) / model.effort
    scatter = 1.4826 * float(np.median(np.abs(residual - np.median(residual))))
    return min(ON_LINE, max(_ROUNDING, 4.0 * scatter))


def _speed_line_support(model: Model, x: FloatArray, y: FloatArray, band: float) -> tuple[int, float]:
    """Samples beyond the split on eq. 2 (within ``band`` of max_actuator_velocity) and their cover.

    The cover is the share of the effort range that the on-line samples span: of the range of the
    samples beyond the split (those not outside the line), and of the largest effort seen,
    whichever is smaller. A line through a curve's samples touches it at one place and covers
    little of it; a sweep's last few noisy samples span little of the effort range; a real speed
    limit's samples lie along the whole line, a good way down toward zero effort.
    """
    above = x > model.split
    margin = (model.velocity - model.gradient * y[above] - x[above]) / model.velocity
    on = np.abs(margin) <= band
    if not on.any():
        return 0, 0.0
    inside = margin >= -band  # outliers beyond the line (the allowance) do not stretch the range
    span = float(np.ptp(y[above][on]))
    own = float(np.ptp(y[above][inside]))
    top = float(y.max())
    covered = min(span / own if own > 0.0 else 1.0, span / (_EQ2_REACH * top) if top > 0.0 else 0.0)
    return int(np.count_nonzero(on)), covered


def choose_model(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], least: int, band: float
) -> tuple[Model, str, Model | None]:
    """The structure the frontier samples support, fitted.

    Args:
        x: ``|velocity|`` of the frontier samples [rad/s or m/s].
        y: ``|effort|`` of the frontier samples [N*m or N].
        q: Outlier allowance per line.
        fixed: Parameters held by the user [SI].
        least: Fewest samples that identify a line.
        band: The frontier band: a sample more than that outside a model is beyond the noise.

    Returns:
        The model, a note on the choice ("" if none) and the best two-line fit, chosen or not
        (None when there are too few samples for it).

    Raises:
        InputError: ``max_actuator_velocity`` is fixed (finite) but there are too few samples to
            place eq. 2.
    """
    speed_fixed = fixed.get("max_actuator_velocity")
    one = fit_structure(x, y, q, fixed, "effort", math.inf)
    if speed_fixed is not None and math.isinf(speed_fixed):
        return one, "max_actuator_velocity fixed at inf: eq. 2 not fitted", None
    two = scan_split(x, y, q, fixed, least)
    if two is None:
        if speed_fixed is not None:
            raise InputError(
                f"fix: max_actuator_velocity needs at least {2 * least} samples to place eq. 2, got {x.size}"
            )
        if x.size < 2 * least:
            why = f"{x.size} samples, fewer than {2 * least} needed for two lines"
        else:
            why = f"the samples lie at too few distinct speeds to split between two lines ({least} each)"
        return _one_line(one, two, x, y, q, fixed, why)
    if speed_fixed is not None:
        return two, "", two
    why = _why_no_speed_limit(two, one, x, y, q, least, band)
    return _one_line(one, two, x, y, q, fixed, why) if why else (two, "", two)


def _why_no_speed_limit(
    two: Model, one: Model, x: FloatArray, y: FloatArray, q: float, least: int, band: float
) -> str:
    """Why the best two lines show no speed limit, or "" when they do."""
    # a knee has eq. 1 flatter than eq. 2 (both lines bind only if R * G < 1); two lines with
    # nearly the same slope are one line, bent by noise
    if two.resistance * two.gradient >= _PARALLEL:
        return f"the best two lines have nearly the same slope (R * G = {two.resistance * two.gradient:.3g})"
    # a speed limit bounds the frontier: saturated samples beyond it (a sweep going on past a
    # wall of interior samples) say it is not one; noise leaves few samples that far out
    beyond = int(np.count_nonzero(two.gauge(x, y) - 1.0 > band))
    if beyond > _BEYOND * x.size + 2:
        return f"{beyond} frontier samples lie beyond the best speed line, more than noise explains"
    if not _clearly_better(two, one, x, y, q):
        return "no samples show the speed limit (eq. 2)"
    # the samples beyond the split must lie along one line, not on a curve bending down
    on_band = _line_band(two, x, y)
    on_line, covered = _speed_line_support(two, x, y, on_band)
    if on_line < least or covered < _EQ2_COVER:
        return (
            f"the samples above |velocity| {two.split:.6g} bend down but do not lie along one line "
            f"({on_line} within {on_band:.2g} of the best line, covering {covered:.0%} of the effort "
            f"range; {least} and {_EQ2_COVER:.0%} needed), so they show no speed limit"
        )
    return ""


def _one_line(
    one: Model,
    two: Model | None,
    x: FloatArray,
    y: FloatArray,
    q: float,
    fixed: Mapping[str, float],
    why: str,
) -> tuple[Model, str, Model | None]:
    """Eq. 1 only, or eq. 2 only when the line reaches zero effort within the data.

    ``why`` says why eq. 2 was not identified (for the note); ``two`` is passed through.
    """
    free = not ({"velocity_dependent_resistance", "max_actuator_velocity"} & set(fixed))
    if free and one.resistance > 0.0 and one.effort / one.resistance <= REACH * float(x.max()):
        speed = fit_structure(x, y, q, fixed, "speed", -math.inf)
        note = (
            f"the samples fall to zero effort at |velocity| {speed.velocity:.6g}: one line that reaches "
            "zero effort is the speed-torque line (eq. 2), so velocity_dependent_resistance = 0 "
            "(as derive reads a stored curve that falls to zero effort)"
        )
        return speed, note, two
    note = (
        f"max_actuator_velocity not identified: {why}; the highest |velocity| seen is "
        f"{float(x.max()):.6g}, so the limit is at least that; reported as inf"
    )
    return one, note, two

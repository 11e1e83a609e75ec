"""A fit's parameter estimates: values, status (fitted, fixed, unidentified), bootstrap spread, notes."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.line_model import STANDSTILL, Model, fit_structure
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, JointType
from drive_envelope._src.params.table import si_unit

FloatArray = npt.NDArray[np.float64]
ParameterStatus = Literal["fitted", "fixed", "unidentified"]


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


def bootstrap(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], model: Model, count: int, seed: int
) -> dict[str, FloatArray]:
    """Parameter values over ``count`` bootstrap resamples, refitted with the main fit's structure."""
    if not count:
        return {}
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(count):
        pick = rng.integers(0, x.size, x.size)
        xs, ys = x[pick], y[pick]
        split = model.split
        if model.lines == "both" and not (np.any(xs <= split) and np.any(xs > split)):
            continue  # a resample that lost one side entirely cannot place that line
        refit = fit_structure(xs, ys, q, fixed, model.lines, split)
        rows.append((refit.effort, refit.velocity, refit.resistance, refit.gradient))
    if len(rows) < 2:
        return {}
    table = np.array(rows)
    return dict(zip(ENVELOPE_FIELDS, table.T, strict=True))


_UNIDENTIFIED = {
    "max_actuator_velocity": "the data never reach the speed limit: reported as inf",
    "velocity_dependent_resistance": "the frontier samples on eq. 1 span no speed range: 0 assumed",
    "speed_effort_gradient": (
        "the frontier samples on eq. 2 span no effort range: 0 assumed (a vertical speed limit)"
    ),
}
_SPEED_LINE_RESISTANCE = (
    "0: the samples' one line reaches zero effort, so it is eq. 2 (the speed-torque line)"
)


def estimates(
    model: Model,
    fixed: Mapping[str, float],
    joint: JointType,
    spreads: dict[str, FloatArray],
    notes: list[str],
    x: FloatArray,
) -> tuple[ParameterEstimate, ...]:
    """One :class:`ParameterEstimate` per field; appends identifiability remarks to ``notes``."""
    speed_line = model.lines != "effort"
    values = {
        "max_effort": max(model.effort, 0.0),
        "max_actuator_velocity": model.velocity
        if speed_line
        else fixed.get("max_actuator_velocity", math.inf),
        "velocity_dependent_resistance": model.resistance,
        "speed_effort_gradient": model.gradient if speed_line else fixed.get("speed_effort_gradient", 0.0),
    }
    identified = {
        "max_effort": True,
        "max_actuator_velocity": speed_line,
        "velocity_dependent_resistance": model.resistance_identified,
        "speed_effort_gradient": speed_line and model.gradient_identified,
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
                _UNIDENTIFIED[name] if speed_line or name != "speed_effort_gradient" else "",
            )
            if name != "max_actuator_velocity" and note:  # the speed limit has its own note already
                notes.append(f"{name} not identified: {note}")
        else:
            status, note, spread = "fitted", "", spreads.get(name)
            if name == "velocity_dependent_resistance" and model.lines == "speed":
                note = _SPEED_LINE_RESISTANCE
            if name == "max_effort":
                note = _max_effort_note(model, x, joint)
                notes.extend([f"max_effort {note}"] if note else [])
        estimates.append(
            ParameterEstimate(
                name=name,
                value=fixed.get(name, values[name]),
                unit=si_unit(name, joint),
                status=status,
                std=None if spread is None else float(np.std(spread, ddof=1)),
                interval=None
                if spread is None
                else (float(np.percentile(spread, 2.5)), float(np.percentile(spread, 97.5))),
                note=note,
            )
        )
    return tuple(estimates)


def _max_effort_note(model: Model, x: FloatArray, joint: JointType) -> str:
    """How max_effort was read when no frontier sample is near standstill (below 5 % of the top speed).

    ``x`` holds the frontier samples' ``|velocity|``. Eq. 1's intercept is extrapolated to zero
    speed; with eq. 2 only, eq. 1 was never reached and max_effort is the largest frontier effort.
    """
    speeds = x if model.lines == "speed" else x[x <= model.split]
    low = float(speeds.min()) if speeds.size else 0.0
    if low <= STANDSTILL * float(x.max()):
        return ""
    unit = si_unit("max_actuator_velocity", joint)
    if model.lines == "speed":
        return (
            "is the largest |effort| seen: eq. 1 is not reached (no frontier sample below "
            f"|velocity| {low:.6g} {unit}; samples inside the hull do not count)"
        )
    return f"extrapolated to zero speed from frontier samples at |velocity| >= {low:.6g} {unit}"

"""Which samples decided each line of a fit: the evidence a report shows beside the numbers."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.line_choice import ON_LINE
from drive_envelope._src.envelope.line_model import Model
from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.params.table import si_unit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

MAX_JSON_RANGES = 1000
"""Most runs of sample numbers a line lists in JSON (a long noisy log has many short runs)."""
SPIKE_RATIO = 2.0
"""A line's one deciding sample stands this many times above every other sample (in the line's
quantity): the warning on it says so, it is most likely a spike."""
WARNING = "warning: "
"""Prefix of a note that warns: the fit's numbers may rest on a fluke (text reports print it as a
warning line)."""


def sample_ranges(indices: IntArray) -> list[tuple[int, int]]:
    """Runs of consecutive sample numbers, 1-based and inclusive: ``[0, 1, 2, 7]`` -> ``[(1, 3), (8, 8)]``."""
    if indices.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(indices) != 1)
    starts = np.concatenate(([indices[0]], indices[breaks + 1]))
    ends = np.concatenate((indices[breaks], [indices[-1]]))
    return [(int(a) + 1, int(b) + 1) for a, b in zip(starts.tolist(), ends.tolist(), strict=True)]


@dataclass(frozen=True, kw_only=True, slots=True)
class LineEvidence:
    """The samples that decided one line of a fit."""

    curve: Literal["effort", "velocity"]
    """``"effort"`` (eq. 1) or ``"velocity"`` (eq. 2), as ``check`` names the curves."""
    identified: bool
    """Whether the fit has this line; eq. 2 is absent when max_actuator_velocity is inf."""
    bounded: int
    """Frontier samples this line bounds (their ray from the origin meets it first)."""
    on_line: IntArray
    """Indices (0-based, in the order given) of the bounded samples within 1 % of the line's cap
    (``check``'s "on limit"): the samples that decided the line."""
    driving: int
    """Of the on-line samples, those with the effort along the velocity (quadrants I and III)."""
    braking: int
    """Of the on-line samples, those with the effort against the velocity (quadrants II and IV)."""
    velocity_range: tuple[float, float] | None
    """Smallest and largest ``|velocity|`` of the on-line samples [rad/s or m/s]; None if none."""
    effort_range: tuple[float, float] | None
    """Smallest and largest ``|effort|`` of the on-line samples [N*m or N]; None if none."""

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible dict; ``samples`` lists runs of 1-based sample numbers ``[first, last]``."""
        runs = sample_ranges(self.on_line)
        return {
            "identified": self.identified,
            "bounded": self.bounded,
            "on_line": int(self.on_line.size),
            "driving": self.driving,
            "braking": self.braking,
            "velocity_range": None if self.velocity_range is None else list(self.velocity_range),
            "effort_range": None if self.effort_range is None else list(self.effort_range),
            "samples": [list(run) for run in runs[:MAX_JSON_RANGES]],
            "samples_truncated": len(runs) > MAX_JSON_RANGES,
        }


def line_evidence(
    model: Model, x: FloatArray, y: FloatArray, pair: npt.NDArray[np.int8], frontier: npt.NDArray[np.bool_]
) -> tuple[LineEvidence, LineEvidence]:
    """The evidence for eq. 1 and eq. 2 of ``model`` among the ``frontier`` samples.

    Args:
        model: The fitted model.
        x: ``|velocity|`` of every sample [rad/s or m/s].
        y: ``|effort|`` of every sample [N*m or N].
        pair: Quadrant pair of every sample: 1 driving, -1 braking, 0 at rest or zero effort.
        frontier: True for the frontier samples.
    """
    eq1 = model.on_eq1(x, y) & frontier
    speed_line = math.isfinite(model.velocity)
    eq2 = frontier & ~eq1 if speed_line else np.zeros(x.size, dtype=bool)
    effort_margin = model.effort - model.resistance * x - y
    near1 = eq1 & (np.abs(effort_margin) <= ON_LINE * max(model.effort, 1e-300))
    lines = [_line("effort", True, eq1, near1, x, y, pair)]
    if speed_line:
        velocity_margin = model.velocity - model.gradient * y - x
        near2 = eq2 & (np.abs(velocity_margin) <= ON_LINE * model.velocity)
    else:
        near2 = eq2
    lines.append(_line("velocity", speed_line, eq2, near2, x, y, pair))
    return lines[0], lines[1]


def _line(
    curve: Literal["effort", "velocity"],
    identified: bool,
    bounded: npt.NDArray[np.bool_],
    near: npt.NDArray[np.bool_],
    x: FloatArray,
    y: FloatArray,
    pair: npt.NDArray[np.int8],
) -> LineEvidence:
    index = np.flatnonzero(near)
    spans = index.size > 0
    return LineEvidence(
        curve=curve,
        identified=identified,
        bounded=int(np.count_nonzero(bounded)),
        on_line=index,
        driving=int(np.count_nonzero(pair[index] > 0)),
        braking=int(np.count_nonzero(pair[index] < 0)),
        velocity_range=(float(x[index].min()), float(x[index].max())) if spans else None,
        effort_range=(float(y[index].min()), float(y[index].max())) if spans else None,
    )


def support_warnings(
    lines: tuple[LineEvidence, LineEvidence], x: FloatArray, y: FloatArray, joint: JointType, held: set[str]
) -> list[str]:
    """Warnings (notes starting with :data:`WARNING`) for each fitted line that rests on a fluke.

    A line decided by a single frontier sample follows that sample wherever it lies, and so does a
    line through a sample that stands more than :data:`SPIKE_RATIO` times above every other sample
    (in the line's quantity: |effort| for eq. 1, |velocity| for eq. 2): one spike in a log of
    saturated operation moves the cap by the spike's height. The warning names the sample (its
    number, 1-based in the order given: the data row of a one-joint log) and its values, says how
    far it stands above every other sample when that is more than :data:`SPIKE_RATIO` times, and
    suggests ``--outlier-quantile``.

    Args:
        lines: The evidence of eq. 1 and eq. 2 (:func:`line_evidence`).
        x: ``|velocity|`` of every sample [rad/s or m/s].
        y: ``|effort|`` of every sample [N*m or N].
        joint: Joint type (units of the message).
        held: Parameters fixed by the user: a line whose cap is held is not decided by its samples.
    """
    speed_unit, effort_unit = si_unit("max_actuator_velocity", joint), si_unit("max_effort", joint)
    caps = {"effort": "max_effort", "velocity": "max_actuator_velocity"}
    warnings = []
    for line in lines:
        on = line.on_line
        if not line.identified or on.size == 0 or caps[line.curve] in held:
            continue
        values, unit, what = (
            (y, effort_unit, "|effort|") if line.curve == "effort" else (x, speed_unit, "|velocity|")
        )
        index = int(on[int(np.argmax(values[on]))])
        rest = max(float(values[:index].max(initial=0.0)), float(values[index + 1 :].max(initial=0.0)))
        value = float(values[index])
        stands = value > SPIKE_RATIO * rest
        if on.size > 1 and not stands:
            continue
        title = "eq. 1 (max_effort)" if line.curve == "effort" else "eq. 2 (max_actuator_velocity)"
        support = "one sample, sample" if on.size == 1 else f"{on.size} samples, among them sample"
        sample = (
            f"{index + 1} (|velocity| {float(x[index]):.6g} {speed_unit}, |effort| {float(y[index]):.6g} "
            f"{effort_unit})"
        )
        height = (
            f"; its {what} is {value / rest:.3g} times the largest of all other samples ({rest:.6g} {unit})"
            if stands
            else ""
        )
        warnings.append(
            f"{WARNING}{title} rests on {support} {sample}{height}: if it is a spike, refit with "
            "--outlier-quantile (e.g. 0.01) or remove it"
        )
    return warnings

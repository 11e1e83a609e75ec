"""What a check reports: its options, per-joint margins, violations, released samples, and JSON.

A sample is *outside* when a margin is below ``-slack * cap``. A sample outside the envelope with
zero effort (``|effort| <= slack * max_effort``) is *released* instead: no effort at all is feasible
at its speed, which happens when something else drives the joint past the no-load speed
(``max_actuator_velocity``, or ``max_effort / velocity_dependent_resistance``) and PhysX's drive
lets go. That is PhysX's behaviour, not the drive violating its envelope, so released samples are
counted on their own and never as outside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.mapping import UnusedKey
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.envelope_file import envelope_data

CurveName = Literal["effort", "velocity"]
FloatArray = npt.NDArray[np.float64]
MARGIN_QUANTILES = (0.001, 0.01, 0.05, 0.25, 0.5)
"""Probabilities of the reported margin quantiles (lower tail: how close the data runs)."""
DEFAULT_MAX_JOINTS = 1000
"""Most distinct joints one check accepts by default: each costs about 32 KiB of statistics, so a
log with a new name on every row cannot exhaust memory."""


@dataclass(frozen=True, kw_only=True, slots=True)
class CheckOptions:
    """Thresholds of a check; all relative to the cap of each curve."""

    tolerance: float = 0.0
    """Largest fraction of a joint's samples allowed outside the envelope; above it the check fails."""
    slack: float = 1e-6
    """A margin below ``-slack * cap`` counts as outside; absorbs rounding of logged numbers. An
    effort within ``slack * max_effort`` of zero counts as zero (for released samples)."""
    limit_band: float = 0.01
    """A margin within ``+-limit_band * cap`` counts as "on the limit"."""
    keep_points: int = 0
    """Samples per joint kept for a plot (a thinned subset plus up to as many violations); 0: none.
    Above 16 joints each joint keeps fewer (at least 500), so the total stays bounded."""
    max_joints: int = DEFAULT_MAX_JOINTS
    """Most distinct joint names in a log; more is an error (memory stays bounded)."""

    def __post_init__(self) -> None:
        for name in ("tolerance", "slack", "limit_band"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
                raise InputError(f"{name}: expected a fraction in [0, 1], got {value!r}")
        for name, low in (("keep_points", 0), ("max_joints", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, int) and value >= low):
                raise InputError(f"{name}: expected an integer >= {low}, got {value!r}")


@dataclass(frozen=True, kw_only=True, slots=True)
class Violation:
    """The worst sample outside one curve."""

    curve: CurveName
    """``"effort"`` (eq. 1, torque-speed line) or ``"velocity"`` (eq. 2, speed-torque line)."""
    excess: float
    """How far outside: minus the margin [N*m or N for effort, rad/s or m/s for velocity]."""
    relative: float
    """``excess`` as a fraction of the curve's cap."""
    row: int
    """Row of the sample in the log (1 = first data row)."""
    time: float | None
    """Time of the sample [s], None when the log has no time column."""
    velocity: float
    """Joint velocity of the sample [rad/s or m/s]."""
    effort: float
    """Effort of the sample [N*m or N]."""
    source: str | None = None
    """The log of a fleet the sample is in (row and time are that log's), None for one log."""


@dataclass(frozen=True, kw_only=True, slots=True)
class MarginSummary:
    """How close one joint's data runs to one curve of its envelope."""

    curve: CurveName
    """``"effort"`` (eq. 1) or ``"velocity"`` (eq. 2)."""
    unit: str
    """SI unit of the margins (``N*m``, ``N``, ``rad/s`` or ``m/s``)."""
    cap: float
    """The curve's cap, the scale of relative numbers: ``max_effort`` or ``max_actuator_velocity``."""
    minimum: float
    """Smallest margin over all samples, released ones included (exact; negative: outside) [unit]."""
    quantiles: tuple[tuple[float, float], ...]
    """``(probability, margin [unit])`` for :data:`MARGIN_QUANTILES`, accurate to 0.1 % of the cap."""
    samples_outside: int
    """Samples with margin below ``-slack * cap``, released samples not counted."""
    samples_on_limit: int
    """Samples with ``|margin| <= limit_band * cap``."""
    time_on_limit: float | None
    """Time spent on the limit [s]; None without a time column."""
    worst: Violation | None
    """The sample furthest outside (released samples not considered), None when none is outside."""
    histogram: npt.NDArray[np.int64] | None = field(default=None, compare=False, repr=False)
    """Sample counts of the margin histogram (0.1 % of the cap per bin, under- and overflow at the
    ends): what reports of a fleet's parts add up to merge their quantiles exactly."""


@dataclass(frozen=True, kw_only=True, slots=True)
class KeptPoints:
    """A bounded, time-ordered subset of a joint's samples for plotting (every k-th plus violations)."""

    velocity: FloatArray
    """Joint velocity [rad/s or m/s]."""
    effort: FloatArray
    """Effort [N*m or N]."""
    time: FloatArray
    """Time [s], or the row number when the log has no time column."""
    outside: npt.NDArray[np.bool_]
    """True for samples outside the envelope (released samples are not)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class JointCheck:
    """The check of one joint's samples against its envelope."""

    joint: str
    """Joint name (from the log's joint column, else the envelope name or ``"joint"``)."""
    envelope: PerformanceEnvelope
    """The envelope checked against."""
    samples: int
    """Number of samples."""
    samples_outside: int
    """Samples outside the envelope (either curve), released samples not counted."""
    duration: float | None
    """Time covered by the samples [s]; None without a time column."""
    time_outside: float | None
    """Time spent outside the envelope [s]; None without a time column."""
    effort: MarginSummary
    """Margins to eq. 1 (torque-speed line)."""
    velocity: MarginSummary | None
    """Margins to eq. 2 (speed-torque line); None when ``max_actuator_velocity`` is infinite."""
    points: KeptPoints | None = None
    """Samples kept for a plot, or None (see :attr:`CheckOptions.keep_points`)."""
    samples_released: int = 0
    """Samples beyond the no-load speed with zero effort: the drive let go, as PhysX's does."""
    time_released: float | None = None
    """Time spent released [s]; None without a time column."""
    time_resets: int = 0
    """Samples whose time is below the one before: the log holds ``time_resets + 1`` episodes (each
    jump back counts 0 s in :attr:`duration`)."""
    first_time_reset: int | None = None
    """Row of the first such sample (the data row of a one-joint log), or None."""

    @property
    def fraction_outside(self) -> float:
        """Fraction of samples outside the envelope."""
        return self.samples_outside / self.samples if self.samples else 0.0

    @property
    def worst(self) -> Violation | None:
        """The worst violation over both curves, compared relative to their caps."""
        found = [m.worst for m in (self.effort, self.velocity) if m is not None and m.worst is not None]
        return max(found, key=lambda v: v.relative) if found else None


@dataclass(frozen=True, kw_only=True, slots=True)
class CheckReport:
    """The check of a whole log: one :class:`JointCheck` per joint, in order of appearance."""

    source: str
    """The log checked (path or ``<table>``)."""
    joints: tuple[JointCheck, ...]
    """Per-joint results."""
    options: CheckOptions
    """The thresholds used."""
    unused_keys: tuple[UnusedKey, ...] = ()
    """Keys of a joint mapping that gave no joint of the log its envelope (a warning each)."""
    parts: int = 1
    """Logs (fleet parts) merged into this report."""

    @property
    def passed(self) -> bool:
        """Whether every joint's fraction outside is within ``options.tolerance``."""
        return all(j.fraction_outside <= self.options.tolerance for j in self.joints)

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible dict (SI numbers; an infinite number is the string ``"inf"`` or ``"-inf"``)."""
        data: dict[str, Any] = {
            "source": self.source,
            "passed": self.passed,
            "tolerance": self.options.tolerance,
            "slack": self.options.slack,
            "limit_band": self.options.limit_band,
            "joints": [_joint_dict(j, self.options.tolerance) for j in self.joints],
            "unused_keys": [{"key": unused.key, "reason": unused.reason} for unused in self.unused_keys],
        }
        if self.parts > 1:
            data["parts"] = self.parts
        return data


def json_float(value: float | None) -> float | str | None:
    """``value``, or ``"inf"``/``"-inf"``/``"nan"`` where strict JSON has no number for it."""
    if value is None or math.isfinite(value):
        return value
    if math.isnan(value):
        return "nan"
    return "inf" if value > 0 else "-inf"


def _joint_dict(check: JointCheck, tolerance: float) -> dict[str, Any]:
    return {
        "joint": check.joint,
        "passed": check.fraction_outside <= tolerance,
        "envelope": envelope_data(check.envelope),
        "samples": check.samples,
        "samples_outside": check.samples_outside,
        "samples_released": check.samples_released,
        "fraction_outside": check.fraction_outside,
        "duration": json_float(check.duration),
        "time_outside": json_float(check.time_outside),
        "time_released": json_float(check.time_released),
        "time_resets": check.time_resets,
        "first_time_reset": check.first_time_reset,
        "effort": _margin_dict(check.effort),
        "velocity": None if check.velocity is None else _margin_dict(check.velocity),
    }


def _margin_dict(summary: MarginSummary) -> dict[str, Any]:
    worst = summary.worst
    return {
        "unit": summary.unit,
        "cap": json_float(summary.cap),
        "minimum": json_float(summary.minimum),
        "quantiles": {f"{p:g}": json_float(value) for p, value in summary.quantiles},
        "samples_outside": summary.samples_outside,
        "samples_on_limit": summary.samples_on_limit,
        "time_on_limit": json_float(summary.time_on_limit),
        "worst": None
        if worst is None
        else {
            "excess": json_float(worst.excess),
            "relative": json_float(worst.relative),
            "row": worst.row,
            "time": json_float(worst.time),
            "velocity": worst.velocity,
            "effort": worst.effort,
            **({} if worst.source is None else {"source": worst.source}),
        },
    }

"""Checking logged (velocity, effort) samples against envelopes, streaming, in bounded memory.

For every sample the two margins of the envelope are computed (positive inside)::

    effort margin   = max_effort - R*|v| - |tau|                [N*m or N]      (eq. 1)
    velocity margin = max_actuator_velocity - G*|tau| - |v|     [rad/s or m/s]  (eq. 2)

A sample is outside when a margin is below ``-slack * cap`` (cap = ``max_effort`` for eq. 1,
``max_actuator_velocity`` for eq. 2). It is "on the limit" when ``|margin| <= limit_band * cap``.
Margins are histogrammed as a fraction of the cap (bins of 0.1 % of the cap between -100 % and
+100 %), so the reported quantiles are accurate to 0.1 % of the cap while memory stays constant;
the minimum is exact. Time on a limit sums the time step that ends at each sample on it (the first
sample of a joint counts 0; a backwards jump in time, e.g. a new episode, counts 0).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.logs import LogChunk
from drive_envelope._src.analysis.mapping import JointMapping
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.params.table import si_unit

__all__ = [
    "MARGIN_QUANTILES",
    "CheckOptions",
    "CheckReport",
    "CurveName",
    "JointCheck",
    "KeptPoints",
    "MarginSummary",
    "Violation",
    "check_chunks",
]

CurveName = Literal["effort", "velocity"]
FloatArray = npt.NDArray[np.float64]
MARGIN_QUANTILES = (0.001, 0.01, 0.05, 0.25, 0.5)
"""Probabilities of the reported margin quantiles (lower tail: how close the data runs)."""

_BINS = 2000  # margin histogram: [-1, 1] of the cap in 0.1 % bins, plus under- and overflow
_LOW, _HIGH = -1.0, 1.0
_WIDTH = (_HIGH - _LOW) / _BINS
_BLOCK = 1 << 16  # samples processed at a time: 512 KiB per temporary, cache-sized


@dataclass(frozen=True, kw_only=True, slots=True)
class CheckOptions:
    """Thresholds of a check; all relative to the cap of each curve."""

    tolerance: float = 0.0
    """Largest fraction of a joint's samples allowed outside the envelope; above it the check fails."""
    slack: float = 1e-6
    """A margin below ``-slack * cap`` counts as outside; absorbs rounding of logged numbers."""
    limit_band: float = 0.01
    """A margin within ``+-limit_band * cap`` counts as "on the limit"."""
    keep_points: int = 0
    """Samples per joint kept for a plot (a thinned subset plus up to as many violations); 0: none."""

    def __post_init__(self) -> None:
        for name in ("tolerance", "slack", "limit_band"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
                raise InputError(f"{name.replace('_', '-')} must be a fraction in [0, 1], got {value!r}")
        if not (isinstance(self.keep_points, int) and self.keep_points >= 0):
            raise InputError(f"keep_points must be an integer >= 0, got {self.keep_points!r}")


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
    """Smallest margin over all samples (exact; negative: outside) [unit]."""
    quantiles: tuple[tuple[float, float], ...]
    """``(probability, margin [unit])`` for :data:`MARGIN_QUANTILES`, accurate to 0.1 % of the cap."""
    samples_outside: int
    """Samples with margin below ``-slack * cap``."""
    samples_on_limit: int
    """Samples with ``|margin| <= limit_band * cap``."""
    time_on_limit: float | None
    """Time spent on the limit [s]; None without a time column."""
    worst: Violation | None
    """The sample furthest outside, None when no sample is outside."""


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
    """True for samples outside the envelope."""


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
    """Samples outside the envelope (either curve)."""
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

    @property
    def passed(self) -> bool:
        """Whether every joint's fraction outside is within ``options.tolerance``."""
        return all(j.fraction_outside <= self.options.tolerance for j in self.joints)

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible dict (SI numbers; an infinite cap is the string ``"inf"``)."""
        return {
            "source": self.source,
            "passed": self.passed,
            "tolerance": self.options.tolerance,
            "slack": self.options.slack,
            "limit_band": self.options.limit_band,
            "joints": [_joint_dict(j, self.options.tolerance) for j in self.joints],
        }


def _json_float(value: float | None) -> float | str | None:
    if value is None or math.isfinite(value):
        return value
    return "inf" if value > 0 else "-inf"


def _joint_dict(check: JointCheck, tolerance: float) -> dict[str, Any]:
    env = check.envelope.to_dict()
    return {
        "joint": check.joint,
        "passed": check.fraction_outside <= tolerance,
        "envelope": {
            key: _json_float(value) if isinstance(value, float) else value for key, value in env.items()
        },
        "samples": check.samples,
        "samples_outside": check.samples_outside,
        "fraction_outside": check.fraction_outside,
        "duration": check.duration,
        "time_outside": check.time_outside,
        "effort": _margin_dict(check.effort),
        "velocity": None if check.velocity is None else _margin_dict(check.velocity),
    }


def _margin_dict(summary: MarginSummary) -> dict[str, Any]:
    worst = summary.worst
    return {
        "unit": summary.unit,
        "cap": _json_float(summary.cap),
        "minimum": summary.minimum,
        "quantiles": {f"{p:g}": value for p, value in summary.quantiles},
        "samples_outside": summary.samples_outside,
        "samples_on_limit": summary.samples_on_limit,
        "time_on_limit": summary.time_on_limit,
        "worst": None
        if worst is None
        else {
            "excess": worst.excess,
            "relative": worst.relative,
            "row": worst.row,
            "time": worst.time,
            "velocity": worst.velocity,
            "effort": worst.effort,
        },
    }


# -- accumulation ---------------------------------------------------------------------------------


class _Curve:
    """Running statistics of one margin of one joint."""

    def __init__(self, name: CurveName, cap: float, unit: str) -> None:
        self.name, self.cap, self.unit = name, cap, unit
        # relative numbers need a positive finite scale; a zero cap falls back to absolute units
        self.scale = cap if 0.0 < cap < math.inf else 1.0
        self.histogram = np.zeros(_BINS + 2, dtype=np.int64)
        self.minimum = math.inf
        self.outside = 0
        self.on_limit = 0
        self.time_on_limit = 0.0
        self.worst: Violation | None = None

    def add(self, margin: FloatArray, options: CheckOptions, ctx: _Context) -> npt.NDArray[np.bool_]:
        """Accumulate ``margin`` [unit]; return the mask of samples outside."""
        # histogram bin: 0 underflow (below -100 % of the cap), 1.._BINS, _BINS + 1 at the cap; a
        # margin never exceeds its cap, so only the lower end needs clipping
        position = margin * (1.0 / (self.scale * _WIDTH))
        position += 1.0 - _LOW / _WIDTH
        np.maximum(position, 0.0, out=position)
        counts = np.bincount(position.astype(np.intp), minlength=_BINS + 2)
        if counts.size > _BINS + 2:  # rounding at exactly the cap
            counts[_BINS + 1] += counts[_BINS + 2 :].sum()
        self.histogram += counts[: _BINS + 2]
        outside = margin < -options.slack * self.scale
        on_limit = np.abs(margin) <= options.limit_band * self.scale
        self.outside += int(np.count_nonzero(outside))
        self.on_limit += int(np.count_nonzero(on_limit))
        if ctx.dt is not None:
            self.time_on_limit += float(np.sum(ctx.dt, where=on_limit))
        lowest = int(np.argmin(margin))
        if margin[lowest] < self.minimum:
            self.minimum = float(margin[lowest])
            if outside[lowest]:
                self.worst = ctx.violation(self.name, lowest, -float(margin[lowest]), self.scale)
        return outside

    def summary(self, samples: int, has_time: bool) -> MarginSummary:
        return MarginSummary(
            curve=self.name,
            unit=self.unit,
            cap=self.cap,
            minimum=self.minimum,
            quantiles=tuple((p, self._quantile(p, samples)) for p in MARGIN_QUANTILES),
            samples_outside=self.outside,
            samples_on_limit=self.on_limit,
            time_on_limit=self.time_on_limit if has_time else None,
            worst=self.worst,
        )

    def _quantile(self, probability: float, samples: int) -> float:
        """Lower-tail quantile from the histogram: the centre of the bin holding it [unit]."""
        rank = max(1, math.ceil(probability * samples))
        k = int(np.searchsorted(np.cumsum(self.histogram), rank))
        if k == 0:  # below -100 % of the cap: the exact minimum is the best bound we kept
            return self.minimum
        if k == _BINS + 1:
            return self.scale * _HIGH
        return self.scale * max(_LOW + (k - 0.5) * _WIDTH, self.minimum / self.scale)


class _Context:
    """One joint's slice of a chunk: what a violation record needs to locate its sample."""

    def __init__(
        self,
        velocity: FloatArray,
        effort: FloatArray,
        time: FloatArray | None,
        rows: Any,
        dt: FloatArray | None,
    ) -> None:
        self.velocity, self.effort, self.time, self.rows, self.dt = velocity, effort, time, rows, dt

    def violation(self, curve: CurveName, index: int, excess: float, scale: float) -> Violation:
        return Violation(
            curve=curve,
            excess=excess,
            relative=excess / scale,
            row=int(self.rows[index]),
            time=None if self.time is None else float(self.time[index]),
            velocity=float(self.velocity[index]),
            effort=float(self.effort[index]),
        )


class _Joint:
    """Running statistics of one joint."""

    def __init__(self, name: str, envelope: PerformanceEnvelope, options: CheckOptions) -> None:
        self.name, self.envelope, self.options = name, envelope, options
        joint = envelope.joint
        self.effort = _Curve("effort", envelope.max_effort, si_unit("max_effort", joint))
        self.velocity = (
            _Curve("velocity", envelope.max_actuator_velocity, si_unit("max_actuator_velocity", joint))
            if math.isfinite(envelope.max_actuator_velocity)
            else None
        )
        self.samples = 0
        self.outside = 0
        self.duration = 0.0
        self.time_outside = 0.0
        self.last_time: float | None = None
        self.has_time = False
        self.kept = _Keeper(options.keep_points) if options.keep_points else None

    def add(self, velocity: FloatArray, effort: FloatArray, time: FloatArray | None, rows: Any) -> None:
        """Accumulate one joint's samples in blocks small enough for the temporaries to stay in cache."""
        for start in range(0, velocity.shape[0], _BLOCK):
            block = slice(start, start + _BLOCK)
            self._add_block(
                velocity[block], effort[block], None if time is None else time[block], rows[block]
            )

    def _add_block(
        self, velocity: FloatArray, effort: FloatArray, time: FloatArray | None, rows: Any
    ) -> None:
        env = self.envelope
        speed, magnitude = np.abs(velocity), np.abs(effort)
        dt = None
        if time is not None:
            self.has_time = True
            previous = time[0] if self.last_time is None else self.last_time
            dt = np.diff(time, prepend=previous)
            np.maximum(dt, 0.0, out=dt)  # a jump back in time (a new episode) counts 0
            self.last_time = float(time[-1])
            self.duration += float(dt.sum())
        ctx = _Context(velocity, effort, time, rows, dt)
        margin = env.velocity_dependent_resistance * speed
        np.subtract(env.max_effort, margin, out=margin)
        margin -= magnitude
        outside = self.effort.add(margin, self.options, ctx)
        if self.velocity is not None:
            margin = np.multiply(env.speed_effort_gradient, magnitude, out=margin)
            np.subtract(env.max_actuator_velocity, margin, out=margin)
            margin -= speed
            outside |= self.velocity.add(margin, self.options, ctx)
        self.samples += int(speed.shape[0])
        self.outside += int(np.count_nonzero(outside))
        if dt is not None:
            self.time_outside += float(np.sum(dt, where=outside))
        if self.kept is not None:
            stamps = time if time is not None else np.fromiter(rows, dtype=np.float64, count=len(rows))
            self.kept.add(np.stack([velocity, effort, stamps], axis=1), outside)

    def result(self) -> JointCheck:
        return JointCheck(
            joint=self.name,
            envelope=self.envelope,
            samples=self.samples,
            samples_outside=self.outside,
            duration=self.duration if self.has_time else None,
            time_outside=self.time_outside if self.has_time else None,
            effort=self.effort.summary(self.samples, self.has_time),
            velocity=None if self.velocity is None else self.velocity.summary(self.samples, self.has_time),
            points=None if self.kept is None else self.kept.points(),
        )


class _Keeper:
    """A bounded subset of samples for a plot: every k-th sample (k doubles when full) and violations.

    Each kept sample is ``(velocity, effort, time)``; without a time column "time" is the row number.
    """

    def __init__(self, capacity: int) -> None:
        self.capacity, self.stride, self.seen = capacity, 1, 0
        self.regular: list[FloatArray] = []
        self.violations: list[FloatArray] = []
        self.regular_count = self.violation_count = 0

    def add(self, samples: FloatArray, outside: npt.NDArray[np.bool_]) -> None:
        """Offer ``samples`` (shape ``(n, 3)``) with their outside mask."""
        start = (-self.seen) % self.stride  # keep the global stride across chunks
        self.seen += samples.shape[0]
        block = samples[start :: self.stride]
        self.regular.append(block)
        self.regular_count += block.shape[0]
        if self.regular_count > self.capacity:
            merged = np.concatenate(self.regular)
            while merged.shape[0] > self.capacity:
                merged, self.stride = merged[::2], self.stride * 2
            self.regular, self.regular_count = [merged], merged.shape[0]
        if self.violation_count < self.capacity and outside.any():
            bad = samples[outside][: self.capacity - self.violation_count]
            self.violations.append(bad)
            self.violation_count += bad.shape[0]

    def points(self) -> KeptPoints:
        regular = np.concatenate(self.regular) if self.regular else np.zeros((0, 3))
        bad = np.concatenate(self.violations) if self.violations else np.zeros((0, 3))
        points = np.concatenate([regular, bad])
        order = np.argsort(points[:, 2], kind="stable")  # back in time order, violations in place
        mask = np.concatenate([np.zeros(regular.shape[0], dtype=bool), np.ones(bad.shape[0], dtype=bool)])
        return KeptPoints(
            velocity=points[order, 0], effort=points[order, 1], time=points[order, 2], outside=mask[order]
        )


def _groups(chunk: LogChunk) -> Iterator[tuple[int, npt.NDArray[np.intp] | None]]:
    """``(joint code, row indices)`` per joint in the chunk; indices None for a single-joint log."""
    if chunk.joint is None:
        yield -1, None
        return
    codes = chunk.joint
    if codes.size and codes.min() == codes.max():
        yield int(codes[0]), None
        return
    order = np.argsort(codes, kind="stable")  # stable: each joint's samples stay in time order
    counts = np.bincount(codes)
    bounds = np.concatenate([[0], np.cumsum(counts)])
    for code in np.flatnonzero(counts):
        yield int(code), order[bounds[code] : bounds[code + 1]]


def check_chunks(
    chunks: Iterator[LogChunk],
    envelopes: PerformanceEnvelope | JointMapping,
    *,
    options: CheckOptions,
    source: str,
) -> CheckReport:
    """Check a stream of log chunks; joints are reported in order of first appearance.

    Args:
        chunks: The log, from :func:`~drive_envelope._src.analysis.logs.iter_log`.
        envelopes: One envelope for every joint, or a mapping joint name -> envelope.
        options: Thresholds.
        source: Name of the log for the report.

    Raises:
        InputError: a joint the mapping has no envelope for; a mapping with a log without joint column.
    """
    joints: dict[int, _Joint] = {}
    for chunk in chunks:
        for code, index in _groups(chunk):
            if code not in joints:
                joints[code] = _new_joint(code, chunk, envelopes, options, source)
            if index is None:
                rows = range(chunk.first_row, chunk.first_row + len(chunk))  # indexable, no allocation
                joints[code].add(chunk.velocity, chunk.effort, chunk.time, rows)
            else:
                time = None if chunk.time is None else chunk.time[index]
                joints[code].add(chunk.velocity[index], chunk.effort[index], time, index + chunk.first_row)
    return CheckReport(source=source, joints=tuple(j.result() for j in joints.values()), options=options)


def _new_joint(
    code: int,
    chunk: LogChunk,
    envelopes: PerformanceEnvelope | JointMapping,
    options: CheckOptions,
    source: str,
) -> _Joint:
    if code < 0:
        if isinstance(envelopes, JointMapping):
            raise InputError(
                f"{source}: a joint mapping ({envelopes.source}) needs a joint column in the log; "
                "name it with --joint-column"
            )
        return _Joint(envelopes.name or "joint", envelopes, options)
    name = chunk.names[code]
    envelope = envelopes.envelope_for(name) if isinstance(envelopes, JointMapping) else envelopes
    return _Joint(name, envelope, options)

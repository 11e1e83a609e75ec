"""Checking logged (velocity, effort) samples against envelopes, streaming, in bounded memory.

For every sample the two margins of the envelope are computed (positive inside)::

    effort margin   = max_effort - R*|v| - |tau|                [N*m or N]      (eq. 1)
    velocity margin = max_actuator_velocity - G*|tau| - |v|     [rad/s or m/s]  (eq. 2)

A sample is outside when a margin is below ``-slack * cap`` (cap = ``max_effort`` for eq. 1,
``max_actuator_velocity`` for eq. 2), unless its effort is zero: then no effort was feasible at its
speed and the drive let go, as PhysX's does; such samples are counted as *released* (see
:mod:`~drive_envelope._src.analysis.report`). A sample is "on the limit" when
``|margin| <= limit_band * cap``. Margins are histogrammed as a fraction of the cap (bins of 0.1 %
of the cap between -100 % and +100 %), so the reported quantiles are accurate to 0.1 % of the cap
while memory stays constant; the minimum is exact. Time on a limit sums the time step that ends at
each sample on it (the first sample of a joint counts 0; a jump back in time, a new episode,
counts 0, and the report counts those jumps and names the row of the first).

Memory is one chunk of the log plus about 32 KiB per joint; :attr:`CheckOptions.max_joints` bounds
the number of joints.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.log_model import LogChunk
from drive_envelope._src.analysis.mapping import JointMapping
from drive_envelope._src.analysis.report import (
    MARGIN_QUANTILES,
    CheckOptions,
    CheckReport,
    CurveName,
    JointCheck,
    KeptPoints,
    MarginSummary,
    Violation,
)
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.params.table import si_unit

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

_BINS = 2000  # margin histogram: [-1, 1] of the cap in 0.1 % bins, plus under- and overflow
_LOW, _HIGH = -1.0, 1.0
_WIDTH = (_HIGH - _LOW) / _BINS
_BLOCK = 1 << 16  # samples processed at a time: 512 KiB per temporary, cache-sized
_FULL_PLOTS = 16  # joints that keep all keep_points samples; beyond, the budget is shared
_LEAST_KEPT = 500  # samples kept per joint however many joints share the budget


# -- accumulation ---------------------------------------------------------------------------------


class _Curve:
    """Running statistics of one margin of one joint."""

    def __init__(self, name: CurveName, cap: float, unit: str) -> None:
        self.name, self.cap, self.unit = name, cap, unit
        # relative numbers need a positive finite scale; a zero cap falls back to absolute units
        self.scale = margin_scale(cap)
        bin_width = self.scale * _WIDTH
        self.inverse_bin = 1.0 / bin_width if bin_width > 1e-300 else None  # else: divide, see add()
        self.histogram = np.zeros(_BINS + 2, dtype=np.int64)
        self.minimum = math.inf
        self.outside = 0
        self.on_limit = 0
        self.time_on_limit = 0.0
        self.worst: Violation | None = None

    def add(self, margin: FloatArray, options: CheckOptions, ctx: _Context) -> BoolArray:
        """Accumulate ``margin`` [unit] (histogram, minimum, on-limit); return the mask below -slack.

        The mask may hold released samples: :meth:`count_outside` then records the rest as outside.
        """
        # histogram bin: 0 underflow (below -100 % of the cap), 1.._BINS, _BINS + 1 at the cap
        if self.inverse_bin is not None:
            position = margin * self.inverse_bin
            position += 1.0 - _LOW / _WIDTH
            # a finite cap bounds its margin; an infinite one (max_effort = inf) gives inf margins
            np.clip(position, 0.0, _BINS + 1.0, out=position)
        else:  # a subnormal cap times the bin width is 0: divide by the cap first, clip both ends
            position = margin / self.scale
            position *= 1.0 / _WIDTH
            position += 1.0 - _LOW / _WIDTH
            np.clip(position, 0.0, _BINS + 1.0, out=position)
        counts = np.bincount(position.astype(np.intp), minlength=_BINS + 2)
        if counts.size > _BINS + 2:  # rounding at exactly the cap
            counts[_BINS + 1] += counts[_BINS + 2 :].sum()
        self.histogram += counts[: _BINS + 2]
        self.minimum = min(self.minimum, float(margin.min()))
        on_limit = np.abs(margin) <= options.limit_band * self.scale
        self.on_limit += int(np.count_nonzero(on_limit))
        if ctx.dt is not None:
            self.time_on_limit += float(np.sum(ctx.dt, where=on_limit))
        return margin < -options.slack * self.scale

    def count_outside(self, margin: FloatArray, outside: BoolArray, ctx: _Context) -> None:
        """Count the samples of ``outside`` (released ones removed) and keep the worst of them."""
        self.outside += int(np.count_nonzero(outside))
        lowest = int(np.argmin(np.where(outside, margin, np.inf)))
        excess = -float(margin[lowest])
        if self.worst is None or excess > self.worst.excess:
            self.worst = ctx.violation(self.name, lowest, excess, self.scale)

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
            histogram=self.histogram.copy(),
        )

    def _quantile(self, probability: float, samples: int) -> float:
        return histogram_quantile(self.histogram, self.minimum, self.scale, probability, samples)


def margin_scale(cap: float) -> float:
    """The scale of a curve's relative numbers: its cap, or 1 for a zero or infinite cap [unit]."""
    return cap if 0.0 < cap < math.inf else 1.0


def histogram_quantile(
    histogram: npt.NDArray[np.int64], minimum: float, scale: float, probability: float, samples: int
) -> float:
    """Lower-tail quantile from a margin histogram: the centre of the bin holding it [unit]."""
    rank = max(1, math.ceil(probability * samples))
    k = int(np.searchsorted(np.cumsum(histogram), rank))
    if k == 0:  # below -100 % of the cap: the exact minimum is the best bound we kept
        return minimum
    if k == _BINS + 1:  # at the cap; beyond it only for an infinite cap, where the minimum may be inf
        return max(scale * _HIGH, minimum)
    return scale * max(_LOW + (k - 0.5) * _WIDTH, minimum / scale)


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
        self.no_load = envelope.no_load_velocity()
        self.samples = 0
        self.outside = 0
        self.released = 0
        self.duration = 0.0
        self.time_outside = 0.0
        self.time_released = 0.0
        self.last_time: float | None = None
        self.time_resets = 0
        self.first_time_reset: int | None = None
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
            with np.errstate(over="ignore"):  # steps beyond float range: an infinite duration
                dt = np.diff(time, prepend=previous)
                self._count_time_resets(dt, rows)
                np.maximum(dt, 0.0, out=dt)  # a jump back in time (a new episode) counts 0
                self.duration += float(dt.sum())
            self.last_time = float(time[-1])
        ctx = _Context(velocity, effort, time, rows, dt)
        with np.errstate(over="ignore"):  # R*|v| beyond float range: a margin of -inf, far outside
            effort_margin = env.velocity_dependent_resistance * speed
            np.subtract(env.max_effort, effort_margin, out=effort_margin)
            effort_margin -= magnitude
            below = {
                "effort": (self.effort, effort_margin, self.effort.add(effort_margin, self.options, ctx))
            }
            if self.velocity is not None:
                velocity_margin = np.multiply(env.speed_effort_gradient, magnitude)
                np.subtract(env.max_actuator_velocity, velocity_margin, out=velocity_margin)
                velocity_margin -= speed
                mask = self.velocity.add(velocity_margin, self.options, ctx)
                below["velocity"] = (self.velocity, velocity_margin, mask)
        self.samples += int(speed.shape[0])
        outside = below["effort"][2] | below["velocity"][2] if "velocity" in below else below["effort"][2]
        if not outside.any():  # the usual block: nothing outside, nothing released
            self._keep(velocity, effort, time, rows, outside)
            return
        released = outside & (magnitude <= self.options.slack * self.effort.scale)
        released &= speed > self.no_load * (1.0 + self.options.slack)
        outside &= ~released
        for curve, margin, mask in below.values():
            mask &= ~released
            if mask.any():
                curve.count_outside(margin, mask, ctx)
        self.outside += int(np.count_nonzero(outside))
        self.released += int(np.count_nonzero(released))
        if dt is not None:
            self.time_outside += float(np.sum(dt, where=outside))
            self.time_released += float(np.sum(dt, where=released))
        self._keep(velocity, effort, time, rows, outside)

    def _count_time_resets(self, dt: FloatArray, rows: Any) -> None:
        """Count the samples whose time is below the one before (episodes), and the first one's row."""
        back = np.flatnonzero(dt < 0.0)
        if back.size:
            self.time_resets += int(back.size)
            if self.first_time_reset is None:
                self.first_time_reset = int(rows[int(back[0])])

    def _keep(
        self, velocity: FloatArray, effort: FloatArray, time: FloatArray | None, rows: Any, outside: BoolArray
    ) -> None:
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
            samples_released=self.released,
            time_released=self.time_released if self.has_time else None,
            time_resets=self.time_resets,
            first_time_reset=self.first_time_reset,
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

    def limit(self, capacity: int) -> None:
        """Lower the capacity (many joints share the budget): thin what was kept to fit."""
        if capacity >= self.capacity:
            return
        self.capacity = capacity
        if self.regular_count > capacity:
            merged = np.concatenate(self.regular)
            while merged.shape[0] > capacity:
                merged, self.stride = merged[::2], self.stride * 2
            self.regular, self.regular_count = [merged], merged.shape[0]
        if self.violation_count > capacity:
            self.violations = [np.concatenate(self.violations)[:capacity]]
            self.violation_count = capacity

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

    Returns:
        The report; with a mapping, its ``unused_keys`` name the keys no joint of the log took.

    Raises:
        InputError: a joint the mapping has no envelope for; a mapping with a log without joint column;
            more than ``options.max_joints`` joints.
    """
    joints: dict[int, _Joint] = {}
    for chunk in chunks:
        for code, index in _groups(chunk):
            if code not in joints:
                if len(joints) >= options.max_joints:
                    row = chunk.first_row + (0 if index is None else int(index[0]))
                    raise InputError(
                        f"{source}: row {row}: joint {chunk.names[code]!r} is joint number "
                        f"{len(joints) + 1}; expected at most {options.max_joints} distinct joint names "
                        "(raise the limit with --max-joints)"
                    )
                joints[code] = _new_joint(code, chunk, envelopes, options, source)
                _share_kept_points(joints, options)
            if index is None:
                rows = range(chunk.first_row, chunk.first_row + len(chunk))  # indexable, no allocation
                joints[code].add(chunk.velocity, chunk.effort, chunk.time, rows)
            else:
                time = None if chunk.time is None else chunk.time[index]
                joints[code].add(chunk.velocity[index], chunk.effort[index], time, index + chunk.first_row)
    results = tuple(j.result() for j in joints.values())
    unused = envelopes.unused_keys([j.joint for j in results]) if isinstance(envelopes, JointMapping) else ()
    return CheckReport(source=source, joints=results, options=options, unused_keys=unused)


def _share_kept_points(joints: dict[int, _Joint], options: CheckOptions) -> None:
    """Above :data:`_FULL_PLOTS` joints, split their kept-point budget so the total stays bounded."""
    if not options.keep_points or len(joints) <= _FULL_PLOTS:
        return
    share = max(_LEAST_KEPT, options.keep_points * _FULL_PLOTS // len(joints))
    for joint in joints.values():
        if joint.kept is not None:
            joint.kept.limit(share)


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
        if chunk.joint_type is not None and chunk.joint_type != envelopes.joint:
            raise InputError(
                f"{source}: the units in the log's column headers are those of a {chunk.joint_type} "
                f"joint, but the envelope is {envelopes.joint}; expected one joint type"
            )
        return _Joint(envelopes.name or "joint", envelopes, options)
    name = chunk.names[code]
    envelope = envelopes.envelope_for(name) if isinstance(envelopes, JointMapping) else envelopes
    if chunk.joint_type is not None and chunk.joint_type != envelope.joint:
        raise InputError(
            f"{source}: the units in the log's column headers are those of a {chunk.joint_type} joint, "
            f"but joint {name!r} has a {envelope.joint} envelope; expected one joint type"
        )
    return _Joint(name, envelope, options)

"""Fitting an envelope to measured samples of saturated operation (a torque-speed sweep, a log).

The samples are folded into the first quadrant (``x = |v|``, ``y = |tau|``; the envelope is symmetric)
and the fit looks for the tightest region of the spec's form around them::

    y <= max_effort - R*x            (eq. 1)          x <= max_actuator_velocity - G*y   (eq. 2)

in three steps:

1. **Frontier** (:mod:`.fit_frontier`): only the samples on or near the upper hull of ``|effort|``
   over ``|velocity|`` (driving and braking quadrants together) are fitted. Interior samples, taken
   while the drive was not saturated, say nothing about the lines and would swamp the few
   saturated ones. With an outlier allowance, spikes standing clear above the hull are set aside
   first, and the band widens round by round to the noise the fit sees (:mod:`.fit_rounds`).
2. **Structure** (:mod:`.fit_choice`): eq. 1 only, both lines split at a speed, or eq. 2 only (one
   line that reaches zero effort is the speed-torque line), as the frontier shows them; a speed
   limit the samples do not lie along is not invented.
3. **Lines** (:mod:`.fit_line`): each line is the tightest bound of its samples (smallest mean gap)
   with at most a fraction ``outlier_quantile`` of them outside (0: all inside).

The result says which samples decided each line (:class:`LineEvidence`): those within 1 % of it, by
sample number and quadrant pair.

Identifiability: a sweep that never reaches the speed limit cannot determine
``max_actuator_velocity``; it is reported as ``inf`` (not identified) rather than the largest speed
seen. A slope whose samples span no range (e.g. all at one speed) is reported as 0, not identified.

Uncertainty: the standard deviation and 95 % interval over bootstrap resamples of the frontier
samples, with the model structure (which lines, split speed) of the main fit. For a frontier (q = 0
is a maximum) the bootstrap spread is a rough scale, not an exact confidence interval.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.fit_estimates import (
    ParameterEstimate,
    bootstrap,
    estimates,
)
from drive_envelope._src.analysis.fit_evidence import LineEvidence, line_evidence, support_warnings
from drive_envelope._src.analysis.fit_frontier import Frontier
from drive_envelope._src.analysis.fit_input import MAX_BOOTSTRAP, check_count, fit_samples_input
from drive_envelope._src.analysis.fit_rounds import frontier_fit
from drive_envelope._src.analysis.report import json_float
from drive_envelope._src.envelope.line_model import Model
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, kw_only=True, slots=True)
class FitOptions:
    """How to fit an envelope to samples."""

    joint: JointType = "revolute"
    """Joint type of the samples (fixes the units): ``"revolute"`` or ``"prismatic"``."""
    outlier_quantile: float = 0.0
    """Fraction of each line's samples allowed outside the fitted envelope, in ``[0, 0.5]``. 0 gives
    the tightest envelope containing every sample; 0.5 the central line through noisy saturated
    samples."""
    fixed: Mapping[str, float] = field(default_factory=dict)
    """Parameters held at given values [SI], by field name (``max_actuator_velocity`` may be inf)."""
    bootstrap: int = 200
    """Bootstrap resamples for the uncertainties, 0 .. :data:`MAX_BOOTSTRAP`; 0 skips them."""
    seed: int = 0
    """Seed of the bootstrap's random generator, an integer >= 0 (results are reproducible)."""
    min_segment_samples: int | None = None
    """Fewest samples that identify a line; None: ``max(5, 2 %)`` of the frontier samples."""
    frontier_band: float | None = None
    """Samples within this fraction of the upper hull's radius (along their ray from the origin) are
    frontier samples, the ones fitted, in ``(0, 1]``; 1 fits every sample. None (automatic): the
    samples on the hull (within :data:`ON_HULL`, rounding in logs) for a containing fit of clean
    samples, :data:`DEFAULT_BAND` for noisy ones, and with an outlier allowance :data:`DEFAULT_BAND`
    widened to six times the noise the fit sees."""
    name: str = ""
    """Name written into the fitted envelope."""

    def __post_init__(self) -> None:
        if self.joint not in ("revolute", "prismatic"):
            raise InputError(f"joint: expected 'revolute' or 'prismatic', got {self.joint!r}")
        quantile = self.outlier_quantile
        if isinstance(quantile, bool) or not isinstance(quantile, (int, float)) or not 0.0 <= quantile <= 0.5:
            raise InputError(f"outlier-quantile: expected a number in [0, 0.5], got {quantile!r}")
        band = self.frontier_band
        if band is not None and (
            isinstance(band, bool) or not isinstance(band, (int, float)) or not 0.0 < band <= 1.0
        ):
            raise InputError(f"frontier-band: expected a fraction in (0, 1], got {band!r}")
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
class FitResult:
    """A fitted envelope, its parameters with uncertainties, the samples that decided it, residuals."""

    envelope: PerformanceEnvelope
    """The fitted envelope (joint side, SI)."""
    parameters: tuple[ParameterEstimate, ...]
    """The four parameters in :data:`ENVELOPE_FIELDS` order."""
    samples: int
    """Number of samples given."""
    samples_outside: int
    """Samples outside the fitted envelope (at most about ``outlier_quantile`` of the frontier)."""
    frontier_samples: int
    """Samples on the frontier (near the upper hull), the ones the lines were fitted to."""
    frontier_band: float
    """Largest gap of a frontier sample to the hull, as a fraction of the hull's radius."""
    set_aside: int
    """Samples far outside the fit left out of the hull (with an outlier allowance; kept in the fit)."""
    lines: tuple[LineEvidence, LineEvidence]
    """The samples that decided eq. 1 and eq. 2 (in that order)."""
    effort_residuals: FloatArray
    """``|tau| - (max_effort - R|v|)`` of the frontier samples eq. 1 bounds, positive outside [N*m or N]."""
    velocity_residuals: FloatArray
    """``|v| - (max_actuator_velocity - G|tau|)`` of the frontier samples eq. 2 bounds, positive
    outside [rad/s or m/s]; empty when eq. 2 is not identified."""
    notes: tuple[str, ...] = ()
    """Remarks on identifiability and method; those starting with ``"warning: "`` warn that a number
    may rest on a fluke (a line decided by one sample)."""

    def estimate(self, name: str) -> ParameterEstimate:
        """The estimate of parameter ``name``."""
        for parameter in self.parameters:
            if parameter.name == name:
                return parameter
        raise KeyError(name)

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible dict: the four parameters (SI) at the top level, then their uncertainties."""
        data: dict[str, Any] = {"name": self.envelope.name, "joint": self.envelope.joint}
        data.update({p.name: json_float(p.value) for p in self.parameters})
        data["uncertainty"] = {p.name: p.std for p in self.parameters}
        data["interval95"] = {
            p.name: None if p.interval is None else list(p.interval) for p in self.parameters
        }
        data["status"] = {p.name: p.status for p in self.parameters}
        data["units"] = {p.name: p.unit for p in self.parameters}
        data["samples"] = self.samples
        data["samples_outside"] = self.samples_outside
        data["frontier"] = {
            "samples": self.frontier_samples,
            "band": self.frontier_band,
            "set_aside": self.set_aside,
        }
        data["lines"] = {line.curve: line.to_dict() for line in self.lines}
        data["residuals"] = {
            "effort": _residual_summary(self.effort_residuals),
            "velocity": _residual_summary(self.velocity_residuals),
        }
        data["notes"] = list(self.notes)
        return data


def _residual_summary(residuals: FloatArray) -> dict[str, Any]:
    if residuals.size == 0:
        return {"count": 0, "rms": None, "max": None, "median": None}
    return {
        "count": int(residuals.size),
        "rms": float(np.sqrt(np.mean(residuals**2))),
        "max": float(residuals.max()),
        "median": float(np.median(residuals)),
    }


# -- public ---------------------------------------------------------------------------------------


def fit_samples(
    velocity: npt.ArrayLike, effort: npt.ArrayLike, options: FitOptions | None = None
) -> FitResult:
    """Fit the tightest envelope of the spec's form to samples of saturated operation.

    Args:
        velocity: Joint velocity samples [rad/s or m/s].
        effort: Effort samples at the same instants [N*m or N]; the sign relative to the velocity
            only tells driving from braking samples in the report.
        options: Joint type, outlier quantile, fixed parameters, bootstrap size, frontier band.

    Returns:
        A :class:`FitResult` with the envelope, each parameter's estimate and bootstrap uncertainty,
        the samples that decided each line, and the residuals.

    Raises:
        InputError: arrays of different shapes, fewer than 3 samples, NaN or infinite values,
            magnitudes above :data:`MAX_SAMPLE`, or ``options`` that are not a :class:`FitOptions`.
    """
    if options is not None and not isinstance(options, FitOptions):
        # a dict of options failed at its first attribute (or, empty, silently meant the defaults)
        raise InputError(
            f"fit_samples: argument 'options': expected a FitOptions (FitOptions(outlier_quantile=0.5)), "
            f"got {type(options).__name__} {options!r}"
        )
    options = options or FitOptions()
    x, y, pair = fit_samples_input(velocity, effort)
    q, fixed = options.outlier_quantile, dict(options.fixed)
    frontier, model, note = frontier_fit(x, y, q, fixed, options.min_segment_samples, options.frontier_band)
    xf, yf = x[frontier.mask], y[frontier.mask]
    notes = [note] if note else []
    spreads = bootstrap(xf, yf, q, fixed, model, options.bootstrap, options.seed)
    parameters = estimates(model, fixed, options.joint, spreads, notes, xf)
    values = {p.name: p.value for p in parameters}
    envelope = PerformanceEnvelope(joint=options.joint, name=options.name, **values)
    notes.extend(_frontier_notes(frontier, pair, x.size))
    if options.bootstrap:
        notes.append(
            f"uncertainties: {options.bootstrap} bootstrap resamples of the frontier samples "
            "(a rough scale for a frontier fit)"
        )
    result = _result(envelope, parameters, model, frontier, x, y, pair, tuple(notes))
    warnings = support_warnings(result.lines, x, y, options.joint, set(fixed))
    return dataclasses.replace(result, notes=(*result.notes, *warnings)) if warnings else result


def _result(
    envelope: PerformanceEnvelope,
    parameters: tuple[ParameterEstimate, ...],
    model: Model,
    frontier: Frontier,
    x: FloatArray,
    y: FloatArray,
    pair: npt.NDArray[np.int8],
    notes: tuple[str, ...],
) -> FitResult:
    """The result of a fit: the evidence and residuals of the envelope's own lines (fixed values in)."""
    final = dataclasses.replace(
        model,
        effort=envelope.max_effort,
        resistance=envelope.velocity_dependent_resistance,
        velocity=envelope.max_actuator_velocity,
        gradient=envelope.speed_effort_gradient,
    )
    xf, yf = x[frontier.mask], y[frontier.mask]
    eq1 = final.on_eq1(xf, yf)
    return FitResult(
        envelope=envelope,
        parameters=parameters,
        samples=int(x.size),
        samples_outside=_count_outside(envelope, x, y),
        frontier_samples=int(xf.size),
        frontier_band=frontier.band,
        set_aside=frontier.set_aside,
        lines=line_evidence(final, x, y, pair, frontier.mask),
        effort_residuals=yf[eq1] - (final.effort - final.resistance * xf[eq1]),
        velocity_residuals=xf[~eq1] - (final.velocity - final.gradient * yf[~eq1]),
        notes=notes,
    )


def _count_outside(envelope: PerformanceEnvelope, x: FloatArray, y: FloatArray) -> int:
    """Samples outside the envelope by more than 1e-9 of its caps (rounding is not outside)."""
    effort_margin, velocity_margin = envelope.margins(x, y)
    speed = envelope.max_actuator_velocity
    slack = 1e-9
    outside = (effort_margin < -slack * max(envelope.max_effort, 1.0)) | (
        velocity_margin < -slack * (speed if math.isfinite(speed) else 1.0)
    )
    return int(np.count_nonzero(outside))


def _frontier_notes(frontier: Frontier, pair: npt.NDArray[np.int8], total: int) -> list[str]:
    """What the frontier left out, and spikes set aside."""
    notes = []
    kept = int(np.count_nonzero(frontier.mask))
    if kept < total:
        driving = int(np.count_nonzero(pair[frontier.mask] > 0))
        braking = int(np.count_nonzero(pair[frontier.mask] < 0))
        inside = total - kept
        rest = "the other sample lies" if inside == 1 else f"the other {inside} lie"
        notes.append(
            f"frontier: {kept} of {total} samples lie within {frontier.band:.3g} of the upper hull "
            f"({driving} driving, {braking} braking) and were fitted; {rest} inside, where the drive "
            "was not saturated"
        )
    if frontier.set_aside:
        notes.append(
            f"{frontier.set_aside} samples standing clear above the others were left out of the hull "
            "(spikes); the outlier allowance covers them"
        )
    return notes

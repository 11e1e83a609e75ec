"""The result of a derivation: every candidate limit, the binding ones, the method and the notes."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Literal

from drive_envelope._src.datasheet.spec import Datasheet, ParamSource
from drive_envelope._src.envelope.model import PerformanceEnvelope

Duty = Literal["peak", "continuous"]
"""Motor torque rating used for maxEffort: ``max_torque`` (peak) or ``continuous_torque``."""


@dataclass(frozen=True, kw_only=True, slots=True)
class Candidate:
    """One candidate limit of maxEffort or maxActuatorVelocity."""

    name: str
    """Limit name (``controller_current``, ``voltage``, ...)."""
    value: float | None
    """Joint-side value [N*m or N / rad/s or m/s], None when an input is missing."""
    formula: str
    """The formula, in the spec's symbols."""
    inputs: tuple[tuple[str, float | None, str], ...]
    """``(key, SI value or None, SI unit)`` of each input."""
    missing: tuple[str, ...] = ()
    """Keys that are absent and would make the candidate computable."""


@dataclass(frozen=True, kw_only=True, slots=True)
class LineFit:
    """One line ``v = v0 - g*tau`` that best fits ``min(mechanical limit, voltage line)`` (least squares)."""

    max_actuator_velocity: float
    """Intercept v0 [rad/s or m/s]."""
    speed_effort_gradient: float
    """Slope g [(rad/s)/(N*m) or (m/s)/N]."""
    max_error: float
    """Largest |fit - curve| over ``[0, maxEffort]`` [rad/s or m/s]."""
    rms_error: float
    """Root-mean-square error over ``[0, maxEffort]`` [rad/s or m/s]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class Derivation:
    """The envelope derived from a datasheet, with every candidate, the methods, provenance and notes."""

    datasheet: Datasheet
    """The input."""
    envelope: PerformanceEnvelope
    """The four parameters at the joint, SI."""
    duty: Duty
    """Which motor torque rating was used."""
    max_effort_limits: tuple[Candidate, ...]
    """Candidates in the spec's order."""
    max_effort_limited_by: str
    """Name of the binding candidate."""
    max_actuator_velocity_limits: tuple[Candidate, ...]
    """Candidates in the spec's order."""
    max_actuator_velocity_limited_by: str
    """Name of the binding candidate."""
    speed_effort_gradient_method: str
    """datasheet | resistance | nominal | mechanical | output_rating | output_line | unavailable."""
    speed_effort_gradient_reason: str
    """Why that method, in one sentence."""
    velocity_dependent_resistance_method: str
    """direct | fitted | fitted_before_knee | speed_torque_line | none."""
    provenance: Mapping[str, ParamSource] = field(default_factory=dict)
    """Where each envelope parameter and each input came from (``section.key`` or parameter name)."""
    notes: tuple[str, ...] = ()
    """Defaults used and values derived, in plain words."""
    warnings: tuple[str, ...] = ()
    """Inputs that look like a unit slip (constants that disagree, an efficiency of 0.9 %): the
    envelope is computed from them as given, but they deserve a second look."""
    line_fit: LineFit | None = None
    """Optional line approximation of a mechanical-limited speed curve (not used in the envelope)."""

    def to_dict(self) -> dict[str, object]:
        """The ``derive --json`` object: SI, joint side, the spec's keys plus a few extra ones."""
        data: dict[str, object] = {
            **self.envelope.to_dict(),
            "max_effort_limited_by": self.max_effort_limited_by,
            "max_effort_limits": {c.name: c.value for c in self.max_effort_limits},
            "max_actuator_velocity_limited_by": self.max_actuator_velocity_limited_by,
            "max_actuator_velocity_limits": {c.name: c.value for c in self.max_actuator_velocity_limits},
            "speed_effort_gradient_method": self.speed_effort_gradient_method,
            "notes": list(self.notes),
            "warnings": list(self.warnings),
            "duty": self.duty,
            "speed_effort_gradient_reason": self.speed_effort_gradient_reason,
            "velocity_dependent_resistance_method": self.velocity_dependent_resistance_method,
            "provenance": dict(self.provenance),
        }
        if self.line_fit is not None:
            data["line_fit"] = asdict(self.line_fit)
        return data

"""Readable output of a derivation: the candidate tables, and envelope text for other commands."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence

import numpy as np

from drive_envelope._src.datasheet.result import Candidate, Derivation
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.format import format_table, format_value
from drive_envelope._src.io.envelope_file import envelope_to_json, envelope_to_toml
from drive_envelope._src.params.table import si_unit

ENVELOPE_FORMATS = ("toml", "envelope-json", "usd-snippet")
_RAD_PER_S_TO_RPM = 60.0 / (2.0 * math.pi)


def derivation_report(derivation: Derivation) -> str:
    """The text report of ``drive-envelope derive``: every candidate, the binding one marked (``*``)."""
    env = derivation.envelope
    joint = env.joint
    lines = [
        f"{env.name}: {joint} joint, {derivation.duty} duty (from {derivation.datasheet.source})",
        "",
        f"max_effort = {format_value(env.max_effort, si_unit('max_effort', joint))}"
        f"   limited by {derivation.max_effort_limited_by}",
        _candidate_table(
            derivation.max_effort_limits, derivation.max_effort_limited_by, si_unit("max_effort", joint)
        ),
        "",
        f"max_actuator_velocity = {_speed_text(env.max_actuator_velocity, joint)}"
        f"   limited by {derivation.max_actuator_velocity_limited_by}",
        _candidate_table(
            derivation.max_actuator_velocity_limits,
            derivation.max_actuator_velocity_limited_by,
            si_unit("max_actuator_velocity", joint),
        ),
        "",
        "speed_effort_gradient = "
        f"{format_value(env.speed_effort_gradient, si_unit('speed_effort_gradient', joint))}"
        f"   method {derivation.speed_effort_gradient_method}",
        f"  why: {derivation.speed_effort_gradient_reason}",
        "",
        "velocity_dependent_resistance = "
        f"{format_value(env.velocity_dependent_resistance, si_unit('velocity_dependent_resistance', joint))}"
        f"   ({_RESISTANCE_WORDS[derivation.velocity_dependent_resistance_method]})",
    ]
    if derivation.line_fit is not None:
        fit = derivation.line_fit
        lines += [
            "",
            "single-line approximation of min(mechanical limit, voltage line) over [0, max_effort] "
            "(not used in the envelope):",
            f"  max_actuator_velocity = {format_value(fit.max_actuator_velocity)}, speed_effort_gradient = "
            f"{format_value(fit.speed_effort_gradient)}, max error {format_value(fit.max_error)}, "
            f"rms error {format_value(fit.rms_error)} [{si_unit('max_actuator_velocity', joint)}]",
        ]
    not_from_sheet = {k: v for k, v in derivation.provenance.items() if v != "datasheet"}
    if not_from_sheet:
        lines += ["", "provenance (everything else is from the datasheet):"]
        lines += [f"  {key}: {source}" for key, source in not_from_sheet.items()]
    if derivation.notes:
        lines += ["", "notes:"]
        lines += [f"  - {note}" for note in derivation.notes]
    if derivation.warnings:
        lines += ["", "warnings (the numbers above use these inputs as given):"]
        lines += [f"  - {warning}" for warning in derivation.warnings]
    return "\n".join(lines)


_RESISTANCE_WORDS = {
    "direct": "given directly",
    "fitted": "fitted from operating points",
    "speed_torque_line": "the operating points are the speed-torque line (eq. 2): 0",
    "fitted_before_knee": "fitted from the operating points before they bend into the speed-torque line",
    "none": "no loss data: 0",
}


def _speed_text(value: float, joint: str) -> str:
    text = format_value(value, si_unit("max_actuator_velocity", joint))
    if joint == "revolute":
        text += f" ({value * _RAD_PER_S_TO_RPM:.6g} rpm)"
    return text


def _candidate_table(candidates: Sequence[Candidate], binding: str, unit: str) -> str:
    rows = []
    for candidate in candidates:
        mark = "*" if candidate.name == binding else ""
        if candidate.missing:
            inputs = "missing " + ", ".join(candidate.missing)
        else:
            inputs = ", ".join(
                f"{_SYMBOLS.get(key, key)}={format_value(value, _unit(u))}"
                for key, value, u in candidate.inputs
            )
        rows.append([mark, candidate.name, candidate.formula, inputs, format_value(candidate.value, unit)])
    table = format_table(["", "limit", "formula", "inputs (SI)", "value"], rows)
    return "\n".join("  " + line for line in table.splitlines())


# The spec's symbols for the inputs, so the table reads like the formula column.
_SYMBOLS = {
    "controller.max_current": "I_C,max",
    "controller.max_voltage": "V_max",
    "controller.modulation": "mu_C",
    "motor.torque_constant": "k_t",
    "motor.speed_constant": "k_v",
    "motor.max_torque": "tau_M,max",
    "motor.continuous_torque": "tau_M,max",
    "motor.max_speed": "n_M,max",
    "gear.ratio": "i_G",
    "gear.efficiency": "eta_G",
    "gear.max_torque": "tau_G,max",
    "gear.max_input_speed": "n_G,in,max",
    "screw.lead": "lead",
    "screw.efficiency": "eta_S",
}


def _unit(unit: str) -> str:
    return "" if unit == "1" else unit


def usd_snippet(envelope: PerformanceEnvelope) -> str:
    """USD text (usda) authoring the envelope on a joint prim, angular values in degrees as USD stores them.

    The prim is an ``over``: paste its apiSchemas and attributes into the joint of an articulation.
    """
    angular = envelope.joint == "revolute"
    inst = "angular" if angular else "linear"
    to_deg = 180.0 / math.pi if angular else 1.0
    velocity = envelope.max_actuator_velocity * to_deg
    resistance = envelope.velocity_dependent_resistance / to_deg
    gradient = envelope.speed_effort_gradient * to_deg
    units = ("deg/s", "N*m*s/deg", "(deg/s)/(N*m)") if angular else ("m/s", "N*s/m", "(m/s)/N")
    effort_unit = "N*m" if angular else "N"
    attr = f"physxDrivePerformanceEnvelope:{inst}"
    units_note = "angular values in degrees." if angular else "SI."
    lines = [
        "#usda 1.0",
        f"# PhysX drive performance envelope of {json.dumps(envelope.name)} (drive-envelope derive).",
        f'# Apply to the joint prim of an articulation (rename "Joint"); {units_note}',
        "",
        'over "Joint" (',
        f'    prepend apiSchemas = ["PhysicsDriveAPI:{inst}", "PhysxDrivePerformanceEnvelopeAPI:{inst}"]',
        ")",
        "{",
        f"    float drive:{inst}:physics:maxForce = {_usd_float(envelope.max_effort)}  # {effort_unit}",
        f"    float {attr}:maxActuatorVelocity = {_usd_float(velocity)}  # {units[0]}",
        f"    float {attr}:velocityDependentResistance = {_usd_float(resistance)}  # {units[1]}",
        f"    float {attr}:speedEffortGradient = {_usd_float(gradient)}  # {units[2]}",
        "}",
    ]
    return "\n".join(lines) + "\n"


def _usd_float(value: float) -> str:
    """The value as USD's ``float`` attribute holds it: the shortest text of its float32.

    Float64 digits would be noise USD drops (2160 deg/s derived as 2159.9999999999995); a finite
    value beyond float32 would read back as inf, so it is refused.
    """
    if math.isinf(value):
        return "inf"
    single = np.float32(value)
    if not np.isfinite(single):
        raise InputError(f"usd-snippet: {value!r} is beyond the largest float32 USD can store (3.4e38)")
    return str(single)


def envelope_text(envelope: PerformanceEnvelope, fmt: str) -> str:
    """The envelope as ``toml`` or ``envelope-json`` (envelope files) or as a ``usd-snippet``."""
    if fmt == "envelope-json":
        return envelope_to_json(envelope)
    if fmt == "usd-snippet":
        return usd_snippet(envelope)
    return envelope_to_toml(envelope)

"""The candidate limits of maxEffort and maxActuatorVelocity (spec sections 2.1 and 2.3) and the binding one.

Effort, in this order: controller_current ``I_C,max*k_t*i_G*eta_G``, motor_torque ``tau_M,max*i_G*eta_G``,
gear_torque ``tau_G,max``, output_rating (the output's max_effort cap, or its nominal_effort for
continuous duty) and output_stall (the output's stall effort). Velocity, in this order: voltage
``k_v*V_max*mu_C/i_G``, motor_speed ``n_M,max/i_G``, gear_input_speed ``n_G,in,max/i_G``,
output_rating (the output's max_velocity cap) and output_no_load (the output's no-load velocity).

The smallest candidate binds; an exact tie keeps the first in this order (there is no tolerance).
Every computed candidate must be a finite number above zero: inputs that overflow or underflow
(``1e308``, ``5e-324``) give a one-line error naming them, never ``inf`` or 0.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from drive_envelope._src.datasheet.context import DeriveContext, candidate
from drive_envelope._src.datasheet.result import Candidate, Duty
from drive_envelope._src.datasheet.spec import OutputRating, ParamSource
from drive_envelope._src.errors import InputError
from drive_envelope._src.format import format_value

EFFORT_LIMITS = ("controller_current", "motor_torque", "gear_torque", "output_rating", "output_stall")
VELOCITY_LIMITS = ("voltage", "motor_speed", "gear_input_speed", "output_rating", "output_no_load")
MECHANICAL_LIMITS = ("motor_speed", "gear_input_speed")
"""Velocity limits that do not depend on effort: the gradient is 0 when one of them binds."""
_DEFAULT_MODULATION = 0.9

EFFORT_HINT = (
    "give [controller] max_current with [motor] torque_constant (or speed_constant), "
    "[motor] max_torque (continuous_torque for --duty continuous), [gear] max_torque, "
    "or [output] max_effort (or stall_effort, nominal_effort)"
)
VELOCITY_HINT = (
    "give [controller] max_voltage with [motor] speed_constant (or torque_constant or back_emf_constant), "
    "[motor] max_speed, [gear] max_input_speed, or [output] max_velocity (or no_load_velocity)"
)


def _screw_suffix(ctx: DeriveContext) -> str:
    return " * T * eta_S" if ctx.sheet.screw is not None else ""


def effort_candidates(ctx: DeriveContext, duty: Duty) -> list[Candidate]:
    """The maxEffort candidates in the order of :data:`EFFORT_LIMITS` [N*m or N]."""
    sheet, t, u = ctx.sheet, ctx.transmission, ctx.units
    motor, gear, controller, output = sheet.motor, sheet.gear, sheet.controller, sheet.output
    suffix = _screw_suffix(ctx)
    torque_key = "motor.max_torque" if duty == "peak" else "motor.continuous_torque"
    motor_torque = None
    if motor is not None:
        motor_torque = motor.max_torque if duty == "peak" else motor.continuous_torque
        other = motor.continuous_torque if duty == "peak" else motor.max_torque
        if motor_torque is None and other is not None:
            flag = "continuous" if duty == "peak" else "peak"
            ctx.notes.append(
                f"{torque_key} not given for {duty} duty (use --duty {flag} for the other rating)"
            )
    rating = _output_effort(ctx, duty)
    candidates = [
        candidate(
            "controller_current",
            "I_C,max * k_t * i_G * eta_G" + suffix,
            [
                ("controller.max_current", controller.max_current if controller else None, "A"),
                ("motor.torque_constant", ctx.torque_constant, u["kt"]),
                *ctx.gear_inputs,
                *ctx.screw_inputs,
            ],
            lambda v: t.motor_effort(v[0] * v[1]),
        ),
        candidate(
            "motor_torque",
            "tau_M,max * i_G * eta_G" + suffix,
            [(torque_key, motor_torque, u["torque"]), *ctx.gear_inputs, *ctx.screw_inputs],
            lambda v: t.motor_effort(v[0]),
        ),
        candidate(
            "gear_torque",
            "tau_G,max" + (" * T * eta_S" if suffix else ""),
            [("gear.max_torque", gear.max_torque if gear else None, u["torque"]), *ctx.screw_inputs],
            lambda v: t.gear_output_effort(v[0]),
        ),
        _output_rating("output_rating", output, rating, u["joint_effort"]),
        _output_rating("output_stall", output, "stall_effort", u["joint_effort"]),
    ]
    _check_finite(candidates, "max_effort", ctx)
    return candidates


def _output_effort(ctx: DeriveContext, duty: Duty) -> str:
    """The field of the output rating that caps effort for ``duty``."""
    output = ctx.sheet.output
    if output is None:
        return "max_effort"
    if duty == "continuous":
        if output.nominal_effort is not None:
            return "nominal_effort"
        if output.max_effort is not None:
            ctx.notes.append(
                "output.nominal_effort not given for continuous duty: "
                "output.max_effort (a peak rating) is used"
            )
        return "max_effort"
    if output.max_effort is None and output.stall_effort is None and output.nominal_effort is not None:
        ctx.notes.append(
            "output.max_effort not given: output.nominal_effort (the continuous rating) limits peak duty too"
        )
        return "nominal_effort"
    return "max_effort"


_NOT_CONTINUOUS = {
    "controller_current": ("controller.max_current", "a peak current"),
    "gear_torque": ("gear.max_torque", "the gear's maximum"),
    "output_stall": ("output.stall_effort", "a peak rating"),
}
"""Effort candidates whose input is no continuous rating: they cap continuous duty too (the controller
never gives more current), so they stay candidates, and a note names the one that binds."""


def continuous_duty_note(ctx: DeriveContext, duty: Duty, effort_by: str) -> list[str]:
    """The note when a continuous-duty max_effort comes from a peak rating (see :data:`_NOT_CONTINUOUS`).

    ``output.max_effort`` taken for want of ``output.nominal_effort`` has its own note.
    """
    if duty != "continuous" or effort_by not in _NOT_CONTINUOUS:
        return []
    key, kind = _NOT_CONTINUOUS[effort_by]
    motor, output = ctx.sheet.motor, ctx.sheet.output
    rated = (motor is not None and motor.continuous_torque is not None) or (
        output is not None and output.nominal_effort is not None
    )
    why = (
        "it binds below the continuous rating"
        if rated
        else "no continuous rating is given (motor.continuous_torque or output.nominal_effort)"
    )
    return [f"{key} ({kind}) is used for continuous duty: max_effort is limited by {effort_by}, as {why}"]


def _output_rating(name: str, output: OutputRating | None, field: str, unit: str) -> Candidate:
    """The candidate that is the [output] table's ``field`` itself (a joint-side rating)."""
    value = getattr(output, field) if output is not None else None
    return candidate(name, f"output {field}", [(f"output.{field}", value, unit)], lambda v: v[0])


def velocity_candidates(ctx: DeriveContext) -> list[Candidate]:
    """The maxActuatorVelocity candidates in the order of :data:`VELOCITY_LIMITS` [rad/s or m/s]."""
    sheet, t, u = ctx.sheet, ctx.transmission, ctx.units
    motor, gear, controller, output = sheet.motor, sheet.gear, sheet.controller, sheet.output
    suffix = " / T" if sheet.screw is not None else ""
    kv = ctx.speed_constant
    voltage = controller.max_voltage if controller else None
    modulation = controller.modulation if controller and controller.modulation is not None else None
    if modulation is None:
        modulation = _DEFAULT_MODULATION
        if voltage is not None and kv is not None:
            ctx.notes.append("controller.modulation not given: mu_C = 0.9 (typical PWM duty-cycle limit)")
            ctx.provenance["controller.modulation"] = "default"
    ratio_inputs = ctx.gear_inputs[:1] + ctx.screw_inputs[:1]
    candidates = [
        candidate(
            "voltage",
            "k_v * V_max * mu_C / i_G" + suffix,
            [
                ("motor.speed_constant", kv, u["kv"]),
                ("controller.max_voltage", voltage, "V"),
                ("controller.modulation", modulation, "1"),
                *ratio_inputs,
            ],
            lambda v: t.motor_speed(v[0] * v[1] * v[2]),
        ),
        candidate(
            "motor_speed",
            "n_M,max / i_G" + suffix,
            [("motor.max_speed", motor.max_speed if motor else None, u["speed"]), *ratio_inputs],
            lambda v: t.motor_speed(v[0]),
        ),
        candidate(
            "gear_input_speed",
            "n_G,in,max / i_G" + suffix,
            [("gear.max_input_speed", gear.max_input_speed if gear else None, u["speed"]), *ratio_inputs],
            lambda v: t.motor_speed(v[0]),
        ),
        _output_rating("output_rating", output, "max_velocity", u["joint_speed"]),
        _output_rating("output_no_load", output, "no_load_velocity", u["joint_speed"]),
    ]
    _check_finite(candidates, "max_actuator_velocity", ctx)
    return candidates


_FLOAT32_SMALLEST_NORMAL = 1.1754943508222875e-38


def _check_finite(candidates: Sequence[Candidate], parameter: str, ctx: DeriveContext) -> None:
    """Refuse a candidate that overflowed to inf or underflowed (every input is finite and > 0).

    Underflow is anything below float32's smallest normal number: PhysX, USD and the GPU kernels
    store float32, where such a limit is 0 or a subnormal that flushes to 0.
    """
    for c in candidates:
        if c.value is None or (math.isfinite(c.value) and c.value >= _FLOAT32_SMALLEST_NORMAL):
            continue
        inputs = ", ".join(
            f"{key} = {format_value(value, '' if unit == '1' else unit)}" for key, value, unit in c.inputs
        )
        outcome = (
            "overflows to inf"
            if not math.isfinite(c.value)
            else f"underflows to {c.value:.3g} (below float32's smallest normal number, 1.18e-38)"
        )
        raise InputError(
            f"{ctx.sheet.source}: {parameter} candidate {c.name} ({c.formula}) {outcome} with {inputs}: "
            "a value is out of range (check its unit)"
        )


def binding(candidates: Sequence[Candidate], parameter: str, ctx: DeriveContext, hint: str) -> str:
    """The smallest candidate; an exact tie keeps the first in the spec's order (strict ``<``)."""
    best: tuple[float, str] | None = None
    for c in candidates:
        if c.value is not None and (best is None or c.value < best[0]):
            best = (c.value, c.name)
    if best is None:
        raise InputError(f"{ctx.sheet.source}: no candidate limit for {parameter}: {hint}")
    return best[1]


def value_of(candidates: Sequence[Candidate], name: str) -> float:
    """The value of the candidate called ``name`` (it must have one)."""
    return next(float(c.value) for c in candidates if c.name == name and c.value is not None)


def limit_source(ctx: DeriveContext, name: str, passthrough: str | None) -> ParamSource:
    """``datasheet`` when the binding value is a datasheet number unchanged, else ``derived``."""
    if name.startswith("output_"):
        return "datasheet"
    if name == passthrough and ctx.sheet.screw is None:
        return "datasheet"
    return "derived"

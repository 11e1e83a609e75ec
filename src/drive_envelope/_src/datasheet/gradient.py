"""speedEffortGradient (spec section 2.4): which line the binding velocity limit belongs to, and its slope.

* A mechanical limit binds (motor_speed, gear_input_speed): 0, velocity does not depend on effort.
* The output's max_velocity cap binds: its own gradient (a printed speed_effort_gradient, or
  velocity_at_max_effort), else 0 with a note.
* The output's no_load_velocity binds: the slope of the output's speed-effort line (a printed
  speed_effort_gradient, then no_load_velocity / stall_effort, then the nominal point
  (no_load_velocity - nominal_velocity) / nominal_effort), else 0 with a note.
* The voltage limit binds: the motor's gradient divided by i_G**2 (efficiency does not enter).
  ``auto`` tries, in this order, the printed gradient (``datasheet``), ``R / k_t**2``
  (``resistance``) and ``(n_0 - n_N) / tau_N`` (``nominal``); a method chosen by name must have
  its inputs. Without any, the output's gradient if it has one, else 0 with a note.

A method chosen by name (``--gradient-method``) when the gradient does not come from the motor
(a mechanical or output limit binds) is not an error: a note says it was not needed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from drive_envelope._src.datasheet.context import DeriveContext
from drive_envelope._src.datasheet.limits import MECHANICAL_LIMITS, value_of
from drive_envelope._src.datasheet.result import Candidate, LineFit
from drive_envelope._src.errors import InputError

AUTO_ORDER = ("datasheet", "resistance", "nominal")
"""The order ``auto`` tries the motor's gradient methods in."""


def motor_gradient(ctx: DeriveContext, method: str) -> tuple[float | None, tuple[str, ...], str]:
    """The motor-side gradient by ``method``.

    Returns:
        ``(value [(rad/s)/(N*m) or (m/s)/N] or None, missing keys, formula)``.
    """
    motor = ctx.sheet.motor
    if method == "datasheet":
        value = motor.speed_torque_gradient if motor else None
        return value, () if value is not None else ("motor.speed_torque_gradient",), "printed gradient"
    if method == "resistance":
        resistance = motor.terminal_resistance if motor else None
        kt = ctx.torque_constant
        missing = tuple(
            key
            for key, v in (("motor.terminal_resistance", resistance), ("motor.torque_constant", kt))
            if v is None
        )
        if resistance is None or kt is None:
            return None, missing, "R / k_t^2"
        square = kt * kt  # not kt**2: a huge k_t gives inf (then a gradient of 0), not an OverflowError
        return (resistance / square if square > 0.0 else math.inf), missing, "R / k_t^2"
    keys = ("motor.no_load_speed", "motor.nominal_speed", "motor.nominal_torque")
    values = (motor.no_load_speed, motor.nominal_speed, motor.nominal_torque) if motor else (None, None, None)
    missing = tuple(key for key, v in zip(keys, values, strict=True) if v is None)
    n0, n_n, tau_n = values
    if n0 is None or n_n is None or tau_n is None:
        return None, missing, "(n_0 - n_N) / tau_N"
    return (n0 - n_n) / tau_n, missing, "(n_0 - n_N) / tau_N"


def choose_gradient(
    ctx: DeriveContext, method: str, explicit: bool, velocity_by: str
) -> tuple[float, str, str]:
    """The gradient at the joint, its method and the reason, per the rules of the module docstring."""
    output = ctx.sheet.output
    if velocity_by in MECHANICAL_LIMITS:
        _not_needed(ctx, method, explicit, f"the mechanical limit {velocity_by} binds")
        ctx.provenance["speed_effort_gradient"] = "derived"
        return (
            0.0,
            "mechanical",
            f"the mechanical limit {velocity_by} binds: velocity does not depend on effort",
        )
    if velocity_by == "output_rating":
        _not_needed(ctx, method, explicit, "the output's max_velocity binds")
        return _output_gradient(ctx, output.rating_gradient() if output else None, "max_velocity")
    if velocity_by == "output_no_load":
        _not_needed(ctx, method, explicit, "the output's no_load_velocity binds")
        return _output_gradient(ctx, output.line_gradient() if output else None, "no_load_velocity")
    return _voltage_gradient(ctx, method, explicit)


def _not_needed(ctx: DeriveContext, method: str, explicit: bool, why: str) -> None:
    if explicit and method != "auto":
        ctx.notes.append(f"gradient method {method!r} not needed: {why}, so the motor's gradient is not used")


def _from_curve(ctx: DeriveContext, why: str) -> tuple[float, str, str]:
    """The gradient of ``losses.operating_points`` that are the speed-torque line."""
    assert ctx.curve_gradient is not None
    _check_gradient(ctx, ctx.curve_gradient, "the operating points' line", "losses.operating_points")
    ctx.provenance["speed_effort_gradient"] = "derived"
    return (
        ctx.curve_gradient,
        "operating_points",
        f"{why}: the slope of losses.operating_points, which are the speed-torque line (eq. 2)",
    )


def _output_gradient(ctx: DeriveContext, found: tuple[float, str] | None, key: str) -> tuple[float, str, str]:
    if found is None and ctx.curve_gradient is not None:
        return _from_curve(ctx, f"the output's {key} binds without a printed gradient")
    if found is None:
        ctx.provenance["speed_effort_gradient"] = "default"
        if key == "max_velocity":
            ctx.notes.append(
                "the output's max_velocity binds and gives no gradient: speed_effort_gradient = 0 "
                "(a rectangle). "
                "If output.max_effort and output.max_velocity are a stall torque and a no-load speed, write "
                "them as output.stall_effort and output.no_load_velocity to get the speed-effort line"
            )
        else:
            ctx.notes.append(
                "the output's no_load_velocity binds but nothing gives the line's slope (stall_effort, "
                "nominal_effort with nominal_velocity, or speed_effort_gradient): speed_effort_gradient = 0"
            )
        method = "output_rating" if key == "max_velocity" else "output_line"
        return 0.0, method, f"the output's {key} binds without a gradient"
    value, formula = found
    _check_gradient(ctx, value, formula)
    ctx.provenance["speed_effort_gradient"] = "datasheet" if formula.startswith("output speed") else "derived"
    method = "output_rating" if key == "max_velocity" else "output_line"
    return value, method, f"the output's {key} binds: its line's gradient {formula}"


def _voltage_gradient(ctx: DeriveContext, method: str, explicit: bool) -> tuple[float, str, str]:
    source = ctx.sheet.source
    if method != "auto":
        value, missing, formula = motor_gradient(ctx, method)
        if value is None:
            raise InputError(
                f"{source}: gradient method {method!r} ({formula}) needs {', '.join(missing)}, "
                "which the datasheet does not give; give them or choose another method (auto picks one)"
            )
    for name in [method] if method != "auto" else AUTO_ORDER:
        value, _, formula = motor_gradient(ctx, name)
        if value is not None:
            ctx.provenance["speed_effort_gradient"] = "derived"
            how = "chosen" if method != "auto" else "first available of " + ", ".join(AUTO_ORDER)
            scale = "(i_G*T)^2" if ctx.sheet.screw is not None else "i_G^2"
            joint = ctx.transmission.motor_gradient(value)
            _check_gradient(ctx, joint, f"{formula} / {scale}", _GRADIENT_KEYS[name])
            reason = (
                f"the voltage limit binds: motor gradient {formula} = {value:.6g} {ctx.units['gradient']} "
                f"({how}), divided by {scale}"
            )
            return joint, name, reason
    output = ctx.sheet.output
    found = (output.rating_gradient() or output.line_gradient()) if output else None
    if found is not None:
        _check_gradient(ctx, found[0], found[1])
        ctx.provenance["speed_effort_gradient"] = "datasheet"
        return (
            found[0],
            "output_rating",
            f"the voltage limit binds but no motor gradient: output's {found[1]}",
        )
    if ctx.curve_gradient is not None:
        return _from_curve(ctx, "the voltage limit binds but no motor gradient")
    ctx.provenance["speed_effort_gradient"] = "default"
    ctx.notes.append(
        "speed_effort_gradient = 0: the voltage limit binds but no motor gradient can be formed "
        "(give motor.speed_torque_gradient, motor.terminal_resistance, "
        "or no_load/nominal speed and nominal_torque)"
    )
    return 0.0, "unavailable", "the voltage limit binds but no gradient inputs exist"


_GRADIENT_KEYS = {
    "datasheet": "motor.speed_torque_gradient, gear.ratio",
    "resistance": "motor.terminal_resistance, motor.torque_constant, gear.ratio",
    "nominal": "motor.no_load_speed, motor.nominal_speed, motor.nominal_torque, gear.ratio",
}


def _check_gradient(ctx: DeriveContext, value: float, formula: str, keys: str = "the output's keys") -> None:
    if not math.isfinite(value) or value < 0.0:
        raise InputError(
            f"{ctx.sheet.source}: speed_effort_gradient ({formula}) = {value:g}: a value is out of range "
            f"(check {keys} and their units)"
        )


def line_fit(
    ctx: DeriveContext, method: str, velocity: Sequence[Candidate], velocity_by: str, max_effort: float
) -> LineFit | None:
    """Least-squares line through ``min(v_mech, v_volt - g*tau)`` on ``[0, maxEffort]``."""
    if velocity_by not in MECHANICAL_LIMITS:
        ctx.notes.append("line approximation skipped: it applies only when a mechanical limit binds")
        return None
    v_volt = next((c.value for c in velocity if c.name == "voltage"), None)
    names = [method] if method != "auto" else list(AUTO_ORDER)
    gradient = next((g for g in (motor_gradient(ctx, n)[0] for n in names) if g is not None), None)
    if v_volt is None or gradient is None:
        ctx.notes.append("line approximation skipped: it needs the voltage limit and a motor gradient")
        return None
    v_mech = value_of(velocity, velocity_by)
    g = ctx.transmission.motor_gradient(gradient)
    tau = np.linspace(0.0, max_effort, 2001)
    curve = np.minimum(v_mech, v_volt - g * tau)
    slope, intercept = np.polyfit(tau, curve, 1)
    error = intercept + slope * tau - curve
    return LineFit(
        max_actuator_velocity=float(intercept),
        speed_effort_gradient=float(max(-slope, 0.0)),
        max_error=float(np.max(np.abs(error))),
        rms_error=float(np.sqrt(np.mean(error**2))),
    )

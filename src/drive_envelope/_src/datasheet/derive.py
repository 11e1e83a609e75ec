"""Datasheet-to-sim (spec section 2): the four envelope parameters at the joint, every candidate shown.

* maxEffort = smallest of controller_current ``I_C,max*k_t*i_G*eta_G``, motor_torque
  ``tau_M,max*i_G*eta_G``, gear_torque ``tau_G,max`` and output_rating.
* maxActuatorVelocity = smallest of voltage ``k_v*V_max*mu_C/i_G``, motor_speed ``n_M,max/i_G``,
  gear_input_speed ``n_G,in,max/i_G`` and output_rating.
* speedEffortGradient: 0 when a mechanical limit binds; the motor gradient ``/ i_G**2`` when the
  voltage limit binds (exact ties count as voltage-limited); the output rating's when it binds.
* velocityDependentResistance: the direct value, else a least-squares fit of operating points
  reflected by ``i_G**2*eta_G``, else 0.

Exact ties name the first candidate in the order above; there is no tolerance. A screw multiplies
in as described in :class:`~drive_envelope._src.datasheet.spec.Transmission`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from drive_envelope._src.datasheet.result import Candidate, Derivation, Duty, LineFit
from drive_envelope._src.datasheet.spec import Datasheet, GradientMethod, ParamSource, Transmission
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError

__all__ = ["EFFORT_LIMITS", "VELOCITY_LIMITS", "Candidate", "Derivation", "Duty", "LineFit", "derive"]

EFFORT_LIMITS = ("controller_current", "motor_torque", "gear_torque", "output_rating")
VELOCITY_LIMITS = ("voltage", "motor_speed", "gear_input_speed", "output_rating")
_MECHANICAL = ("motor_speed", "gear_input_speed")
_DEFAULT_MODULATION = 0.9


@dataclass(kw_only=True, slots=True)
class _Context:
    """Working state of one derivation: resolved inputs, units, notes and provenance."""

    sheet: Datasheet
    transmission: Transmission
    units: Mapping[str, str]
    gear_inputs: tuple[tuple[str, float | None, str], ...]
    screw_inputs: tuple[tuple[str, float | None, str], ...]
    torque_constant: float | None = None
    speed_constant: float | None = None
    notes: list[str] = field(default_factory=list)
    provenance: dict[str, ParamSource] = field(default_factory=dict)


def derive(
    datasheet: Datasheet,
    *,
    duty: Duty = "peak",
    gradient_method: GradientMethod | None = None,
    approximate_line: bool = False,
) -> Derivation:
    """Derive the performance envelope at the joint from a datasheet.

    Args:
        datasheet: The validated datasheet (:func:`load_datasheet`).
        duty: ``"peak"`` uses ``motor.max_torque``, ``"continuous"`` uses ``motor.continuous_torque``.
        gradient_method: Overrides the file's ``motor.gradient_method`` (provenance ``user``).
        approximate_line: Also report the single line that best fits ``min(mechanical limit,
            voltage line)`` over ``[0, maxEffort]`` when a mechanical limit binds (the envelope keeps
            the spec's gradient 0).

    Returns:
        The :class:`Derivation`.

    Raises:
        InputError: no candidate for maxEffort or maxActuatorVelocity (naming the inputs that would
            give one), an explicit gradient method whose inputs are missing, or operating points
            with fewer than 2 distinct speeds.
    """
    if duty not in ("peak", "continuous"):
        raise InputError(f"duty: expected 'peak' or 'continuous', got {duty!r}")
    ctx = _context(datasheet)
    method: GradientMethod = datasheet.motor.gradient_method if datasheet.motor else "auto"
    if gradient_method is not None:
        if gradient_method not in ("auto", "resistance", "nominal", "datasheet"):
            raise InputError(
                f"gradient method: expected auto, resistance, nominal or datasheet, got {gradient_method!r}"
            )
        method = gradient_method
        ctx.provenance["motor.gradient_method"] = "user"
    effort = _effort_candidates(ctx, duty)
    velocity = _velocity_candidates(ctx)
    effort_by = _binding(effort, "max_effort", ctx, _EFFORT_HINT)
    velocity_by = _binding(velocity, "max_actuator_velocity", ctx, _VELOCITY_HINT)
    gradient, gradient_method_used, reason = _gradient(ctx, method, velocity_by)
    resistance, resistance_method = _resistance(ctx)
    max_effort = _value_of(effort, effort_by)
    max_velocity = _value_of(velocity, velocity_by)
    envelope = PerformanceEnvelope(
        name=datasheet.name,
        joint=datasheet.joint,
        max_effort=max_effort,
        max_actuator_velocity=max_velocity,
        velocity_dependent_resistance=resistance,
        speed_effort_gradient=gradient,
    )
    ctx.provenance["max_effort"] = _limit_source(ctx, effort_by, "gear_torque")
    ctx.provenance["max_actuator_velocity"] = _limit_source(ctx, velocity_by, None)
    fit = None
    if approximate_line:
        fit = _line_fit(ctx, method, velocity, velocity_by, max_effort)
    return Derivation(
        datasheet=datasheet,
        envelope=envelope,
        duty=duty,
        max_effort_limits=tuple(effort),
        max_effort_limited_by=effort_by,
        max_actuator_velocity_limits=tuple(velocity),
        max_actuator_velocity_limited_by=velocity_by,
        speed_effort_gradient_method=gradient_method_used,
        speed_effort_gradient_reason=reason,
        velocity_dependent_resistance_method=resistance_method,
        provenance=dict(sorted(ctx.provenance.items())),
        notes=tuple(ctx.notes),
        line_fit=fit,
    )


# -- inputs --------------------------------------------------------------------------------------


def _context(sheet: Datasheet) -> _Context:
    """Resolve the transmission, k_t and k_v, recording defaults and derived values."""
    linear = sheet.linear_motor
    units = {
        "torque": "N" if linear else "N*m",
        "speed": "m/s" if linear else "rad/s",
        "kt": "N/A" if linear else "N*m/A",
        "kv": "(m/s)/V" if linear else "(rad/s)/V",
        "gradient": "(m/s)/N" if linear else "(rad/s)/(N*m)",
        "joint_effort": "N" if sheet.joint == "prismatic" else "N*m",
        "joint_speed": "m/s" if sheet.joint == "prismatic" else "rad/s",
        "joint_gradient": "(m/s)/N" if sheet.joint == "prismatic" else "(rad/s)/(N*m)",
        "joint_resistance": "N*s/m" if sheet.joint == "prismatic" else "N*m*s/rad",
    }
    notes: list[str] = []
    provenance: dict[str, ParamSource] = dict(sheet.provenance)
    gear, screw = sheet.gear, sheet.screw
    if gear is None:
        notes.append("no [gear]: direct drive (i_G = 1, eta_G = 1)")
        ratio, efficiency = 1.0, 1.0
        gear_inputs: list[tuple[str, float | None, str]] = []
    else:
        ratio = gear.ratio
        efficiency = 1.0 if gear.efficiency is None else gear.efficiency
        if gear.efficiency is None:
            notes.append("gear.efficiency not given: eta_G = 1.0 (no gear losses) assumed")
            provenance["gear.efficiency"] = "default"
        gear_inputs = [("gear.ratio", ratio, "1"), ("gear.efficiency", efficiency, "1")]
    factor, screw_efficiency = 1.0, 1.0
    screw_inputs: list[tuple[str, float | None, str]] = []
    if screw is not None:
        factor = 2.0 * math.pi / screw.lead
        screw_efficiency = 1.0 if screw.efficiency is None else screw.efficiency
        if screw.efficiency is None:
            notes.append("screw.efficiency not given: eta_S = 1.0 assumed")
            provenance["screw.efficiency"] = "default"
        screw_inputs = [("screw.lead", screw.lead, "m/rev"), ("screw.efficiency", screw_efficiency, "1")]
    ctx = _Context(
        sheet=sheet,
        transmission=Transmission(
            ratio=ratio, efficiency=efficiency, screw_factor=factor, screw_efficiency=screw_efficiency
        ),
        units=units,
        gear_inputs=tuple(gear_inputs),
        screw_inputs=tuple(screw_inputs),
        notes=notes,
        provenance=provenance,
    )
    _motor_constants(ctx)
    return ctx


def _motor_constants(ctx: _Context) -> None:
    """k_t and k_v; one given alone gives the other as its SI reciprocal (an ideal motor)."""
    motor = ctx.sheet.motor
    if motor is None:
        return
    kt = motor.torque_constant
    kv = motor.speed_constant
    if kv is None and motor.back_emf_constant is not None:
        kv = 1.0 / motor.back_emf_constant
        ctx.notes.append(f"k_v = 1/k_e = {kv:.6g} {ctx.units['kv']} (from motor.back_emf_constant)")
        ctx.provenance["motor.speed_constant"] = "derived"
    if kt is None and kv is not None:
        kt = 1.0 / kv
        ctx.notes.append(
            f"motor.torque_constant not given: k_t = 1/k_v = {kt:.6g} {ctx.units['kt']} (SI reciprocal)"
        )
        ctx.provenance["motor.torque_constant"] = "derived"
    elif kv is None and kt is not None:
        kv = 1.0 / kt
        ctx.notes.append(
            f"motor.speed_constant not given: k_v = 1/k_t = {kv:.6g} {ctx.units['kv']} (SI reciprocal)"
        )
        ctx.provenance["motor.speed_constant"] = "derived"
    ctx.torque_constant, ctx.speed_constant = kt, kv


def _screw_suffix(ctx: _Context) -> str:
    return " * T * eta_S" if ctx.sheet.screw is not None else ""


def _candidate(
    name: str,
    formula: str,
    inputs: Sequence[tuple[str, float | None, str]],
    compute: Callable[[list[float]], float],
) -> Candidate:
    """A candidate whose value is ``compute(input values)`` when every input is present, else None."""
    present = [value for _, value, _ in inputs if value is not None]
    missing = tuple(key for key, value, _ in inputs if value is None)
    value = None if missing else float(compute(present))
    return Candidate(name=name, value=value, formula=formula, inputs=tuple(inputs), missing=missing)


# -- maxEffort and maxActuatorVelocity ---------------------------------------------------------------

_EFFORT_HINT = (
    "give [controller] max_current with [motor] torque_constant (or speed_constant), "
    "[motor] max_torque (continuous_torque for --duty continuous), [gear] max_torque, or [output] max_effort"
)
_VELOCITY_HINT = (
    "give [controller] max_voltage with [motor] speed_constant (or torque_constant or back_emf_constant), "
    "[motor] max_speed, [gear] max_input_speed, or [output] max_velocity"
)


def _effort_candidates(ctx: _Context, duty: Duty) -> list[Candidate]:
    sheet, t, u = ctx.sheet, ctx.transmission, ctx.units
    motor, gear, controller, output = sheet.motor, sheet.gear, sheet.controller, sheet.output
    suffix = _screw_suffix(ctx)
    current = controller.max_current if controller else None
    kt = ctx.torque_constant
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
    gear_torque = gear.max_torque if gear else None
    return [
        _candidate(
            "controller_current",
            "I_C,max * k_t * i_G * eta_G" + suffix,
            [
                ("controller.max_current", current, "A"),
                ("motor.torque_constant", kt, u["kt"]),
                *ctx.gear_inputs,
                *ctx.screw_inputs,
            ],
            lambda v: t.motor_effort(v[0] * v[1]),
        ),
        _candidate(
            "motor_torque",
            "tau_M,max * i_G * eta_G" + suffix,
            [(torque_key, motor_torque, u["torque"]), *ctx.gear_inputs, *ctx.screw_inputs],
            lambda v: t.motor_effort(v[0]),
        ),
        _candidate(
            "gear_torque",
            "tau_G,max" + (" * T * eta_S" if suffix else ""),
            [("gear.max_torque", gear_torque, u["torque"]), *ctx.screw_inputs],
            lambda v: t.gear_output_effort(v[0]),
        ),
        _candidate(
            "output_rating",
            "output max_effort",
            [("output.max_effort", output.max_effort if output else None, u["joint_effort"])],
            lambda v: v[0],
        ),
    ]


def _velocity_candidates(ctx: _Context) -> list[Candidate]:
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
    max_speed = motor.max_speed if motor else None
    gear_speed = gear.max_input_speed if gear else None
    return [
        _candidate(
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
        _candidate(
            "motor_speed",
            "n_M,max / i_G" + suffix,
            [("motor.max_speed", max_speed, u["speed"]), *ratio_inputs],
            lambda v: t.motor_speed(v[0]),
        ),
        _candidate(
            "gear_input_speed",
            "n_G,in,max / i_G" + suffix,
            [("gear.max_input_speed", gear_speed, u["speed"]), *ratio_inputs],
            lambda v: t.motor_speed(v[0]),
        ),
        _candidate(
            "output_rating",
            "output max_velocity",
            [("output.max_velocity", output.max_velocity if output else None, u["joint_speed"])],
            lambda v: v[0],
        ),
    ]


def _binding(candidates: Sequence[Candidate], parameter: str, ctx: _Context, hint: str) -> str:
    """The smallest candidate; an exact tie keeps the first in the spec's order (strict ``<``)."""
    best: tuple[float, str] | None = None
    for candidate in candidates:
        if candidate.value is not None and (best is None or candidate.value < best[0]):
            best = (candidate.value, candidate.name)
    if best is None:
        raise InputError(f"{ctx.sheet.source}: no candidate limit for {parameter}: {hint}")
    return best[1]


def _value_of(candidates: Sequence[Candidate], name: str) -> float:
    return next(float(c.value) for c in candidates if c.name == name and c.value is not None)


def _limit_source(ctx: _Context, name: str, passthrough: str | None) -> ParamSource:
    """``datasheet`` when the binding value is a datasheet number unchanged, else ``derived``."""
    if name == "output_rating":
        return "datasheet"
    if name == passthrough and ctx.sheet.screw is None:
        return "datasheet"
    return "derived"


# -- speedEffortGradient --------------------------------------------------------------------------


def _motor_gradient(ctx: _Context, method: str) -> tuple[float | None, tuple[str, ...], str]:
    """The motor-side gradient by ``method``: ``(value or None, missing keys, formula)``."""
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
        return resistance / kt**2, missing, "R / k_t^2"
    keys = ("motor.no_load_speed", "motor.nominal_speed", "motor.nominal_torque")
    values = (motor.no_load_speed, motor.nominal_speed, motor.nominal_torque) if motor else (None, None, None)
    missing = tuple(key for key, v in zip(keys, values, strict=True) if v is None)
    n0, n_n, tau_n = values
    if n0 is None or n_n is None or tau_n is None:
        return None, missing, "(n_0 - n_N) / tau_N"
    return (n0 - n_n) / tau_n, missing, "(n_0 - n_N) / tau_N"


def _gradient(ctx: _Context, method: str, velocity_by: str) -> tuple[float, str, str]:
    """The gradient, its method and the reason, per the spec's rules (see the module docstring)."""
    source = ctx.sheet.source
    explicit: tuple[float | None, tuple[str, ...], str] | None = None
    if method != "auto":
        explicit = _motor_gradient(ctx, method)
        if explicit[0] is None:
            raise InputError(
                f"{source}: gradient method {method!r} ({explicit[2]}) needs {', '.join(explicit[1])}, "
                "which the datasheet does not give; give them or choose another method (auto picks one)"
            )
    output = ctx.sheet.output
    output_gradient = output.gradient() if output else None
    if velocity_by in _MECHANICAL:
        ctx.provenance["speed_effort_gradient"] = "derived"
        return (
            0.0,
            "mechanical",
            f"the mechanical limit {velocity_by} binds: velocity does not depend on effort",
        )
    if velocity_by == "output_rating":
        ctx.provenance["speed_effort_gradient"] = "datasheet" if output_gradient is not None else "default"
        if output_gradient is None:
            ctx.notes.append("the output rating binds and gives no gradient: speed_effort_gradient = 0")
        return output_gradient or 0.0, "output_rating", "the output rating binds: its own gradient is used"
    ordered = [method] if method != "auto" else ["datasheet", "resistance", "nominal"]
    for name in ordered:
        value, _, formula = explicit if explicit is not None else _motor_gradient(ctx, name)
        if value is not None:
            ctx.provenance["speed_effort_gradient"] = "derived"
            how = "chosen" if method != "auto" else "first available of datasheet, resistance, nominal"
            scale = "(i_G*T)^2" if ctx.sheet.screw is not None else "i_G^2"
            reason = (
                f"the voltage limit binds: motor gradient {formula} = {value:.6g} {ctx.units['gradient']} "
                f"({how}), divided by {scale}"
            )
            return ctx.transmission.motor_gradient(value), name, reason
    if output_gradient is not None:
        ctx.provenance["speed_effort_gradient"] = "datasheet"
        return (
            output_gradient,
            "output_rating",
            "the voltage limit binds but no motor gradient: output rating's",
        )
    ctx.provenance["speed_effort_gradient"] = "default"
    ctx.notes.append(
        "speed_effort_gradient = 0: the voltage limit binds but no motor gradient can be formed "
        "(give motor.speed_torque_gradient, motor.terminal_resistance, "
        "or no_load/nominal speed and nominal_torque)"
    )
    return 0.0, "unavailable", "the voltage limit binds but no gradient inputs exist"


# -- velocityDependentResistance ------------------------------------------------------------------


def _resistance(ctx: _Context) -> tuple[float, str]:
    losses, output = ctx.sheet.losses, ctx.sheet.output
    direct = losses.velocity_dependent_resistance if losses else None
    if direct is None and output is not None:
        direct = output.velocity_dependent_resistance
    points = losses.operating_points if losses else None
    if direct is not None:
        if points is not None:
            ctx.notes.append(
                "losses.operating_points ignored: a direct velocity_dependent_resistance is given"
            )
        ctx.provenance["velocity_dependent_resistance"] = "datasheet"
        return direct, "direct"
    if points is None:
        ctx.notes.append(
            "no loss data: velocity_dependent_resistance = 0 (no speed-dependent losses modelled)"
        )
        ctx.provenance["velocity_dependent_resistance"] = "default"
        return 0.0, "none"
    speeds = np.array([p[0] for p in points], dtype=np.float64)
    torques = np.array([p[1] for p in points], dtype=np.float64)
    if np.unique(speeds).size < 2:
        raise InputError(
            f"{ctx.sheet.source}: key 'losses.operating_points': needs at least 2 points with distinct "
            f"speeds, got {len(points)} point(s) with {np.unique(speeds).size} distinct speed(s)"
        )
    # ordinary least squares of torque on speed; the resistance is minus the slope
    centred = speeds - speeds.mean()
    slope = float(np.dot(centred, torques - torques.mean()) / np.dot(centred, centred))
    motor_side = -slope
    if motor_side < 0.0:
        ctx.notes.append(
            f"operating points rise with speed (fitted k_m = {motor_side:.6g}): "
            "velocity_dependent_resistance = 0"
        )
        motor_side = 0.0
    value = ctx.transmission.motor_resistance(motor_side)
    ctx.notes.append(
        f"velocity_dependent_resistance fitted from {len(points)} operating points: motor side "
        f"k_m = {motor_side:.6g}, x i_G^2 * eta_G at the joint"
    )
    ctx.provenance["velocity_dependent_resistance"] = "derived"
    return value, "fitted"


# -- optional line approximation ------------------------------------------------------------------


def _line_fit(
    ctx: _Context, method: str, velocity: Sequence[Candidate], velocity_by: str, max_effort: float
) -> LineFit | None:
    """Least-squares line through ``min(v_mech, v_volt - g*tau)`` on ``[0, maxEffort]``."""
    if velocity_by not in _MECHANICAL:
        ctx.notes.append("line approximation skipped: it applies only when a mechanical limit binds")
        return None
    v_volt = _value_of_or_none(velocity, "voltage")
    names = [method] if method != "auto" else ["datasheet", "resistance", "nominal"]
    gradient = next((g for g in (_motor_gradient(ctx, n)[0] for n in names) if g is not None), None)
    if v_volt is None or gradient is None:
        ctx.notes.append("line approximation skipped: it needs the voltage limit and a motor gradient")
        return None
    v_mech = _value_of(velocity, velocity_by)
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


def _value_of_or_none(candidates: Sequence[Candidate], name: str) -> float | None:
    return next((c.value for c in candidates if c.name == name), None)

"""Datasheet-to-sim (spec section 2): the four envelope parameters at the joint, every candidate shown.

* maxEffort = smallest of controller_current ``I_C,max*k_t*i_G*eta_G``, motor_torque
  ``tau_M,max*i_G*eta_G``, gear_torque ``tau_G,max``, output_rating and output_stall
  (:mod:`~drive_envelope._src.datasheet.limits`).
* maxActuatorVelocity = smallest of voltage ``k_v*V_max*mu_C/i_G``, motor_speed ``n_M,max/i_G``,
  gear_input_speed ``n_G,in,max/i_G``, output_rating and output_no_load.
* speedEffortGradient: 0 when a mechanical limit binds; the motor gradient ``/ i_G**2`` when the
  voltage limit binds (exact ties count as voltage-limited); the output's line when an output
  limit binds (:mod:`~drive_envelope._src.datasheet.gradient`).
* velocityDependentResistance: the direct value, else a least-squares fit of operating points
  reflected by ``i_G**2*eta_G``, else 0 (:mod:`~drive_envelope._src.datasheet.losses`).

Exact ties name the first candidate in the order above; there is no tolerance. A screw multiplies
in as described in :class:`~drive_envelope._src.datasheet.spec.Transmission`.
"""

from __future__ import annotations

import math

from drive_envelope._src.datasheet.context import DeriveContext, build_context
from drive_envelope._src.datasheet.gradient import choose_gradient, line_fit
from drive_envelope._src.datasheet.limits import (
    EFFORT_HINT,
    VELOCITY_HINT,
    binding,
    continuous_duty_note,
    effort_candidates,
    limit_source,
    value_of,
    velocity_candidates,
)
from drive_envelope._src.datasheet.losses import resistance
from drive_envelope._src.datasheet.plausibility import plausibility_warnings
from drive_envelope._src.datasheet.result import Candidate, Derivation, Duty
from drive_envelope._src.datasheet.spec import GRADIENT_METHODS, Datasheet, GradientMethod
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError


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
        duty: ``"peak"`` uses ``motor.max_torque`` and ``output.max_effort``; ``"continuous"`` uses
            ``motor.continuous_torque`` and ``output.nominal_effort``.
        gradient_method: Overrides the file's ``motor.gradient_method`` (provenance ``user``); used
            only when the voltage limit binds (a note says so otherwise).
        approximate_line: Also report the single line that best fits ``min(mechanical limit,
            voltage line)`` over ``[0, maxEffort]`` when a mechanical limit binds (the envelope keeps
            the spec's gradient 0).

    Returns:
        The :class:`Derivation`.

    Raises:
        InputError: ``datasheet`` is not a :class:`Datasheet` (a catalog name, say), no
            candidate for maxEffort or maxActuatorVelocity (naming the inputs that would
            give one), a candidate or gradient out of range (inputs that overflow or underflow), an
            explicit gradient method whose inputs are missing while the voltage limit binds, or
            operating points with fewer than 2 distinct speeds.
    """
    if not isinstance(datasheet, Datasheet):
        # a name or a path reached build_context as an AttributeError ('str' has no 'linear_motor')
        raise InputError(
            f"derive: argument 'datasheet': expected a Datasheet (load_datasheet(path), "
            f"load_catalog_datasheet(name)), got {type(datasheet).__name__} {datasheet!r}"
        )
    if duty not in ("peak", "continuous"):
        raise InputError(f"duty: expected 'peak' or 'continuous', got {duty!r}")
    ctx = build_context(datasheet)
    method: GradientMethod = datasheet.motor.gradient_method if datasheet.motor else "auto"
    explicit = method != "auto"
    if gradient_method is not None:
        if gradient_method not in GRADIENT_METHODS:
            raise InputError(
                f"gradient method: expected one of {', '.join(GRADIENT_METHODS)}, got {gradient_method!r}"
            )
        method, explicit = gradient_method, True
        ctx.provenance["motor.gradient_method"] = "user"
    effort = effort_candidates(ctx, duty)
    velocity = velocity_candidates(ctx)
    effort_by = binding(effort, "max_effort", ctx, EFFORT_HINT)
    velocity_by = binding(velocity, "max_actuator_velocity", ctx, VELOCITY_HINT)
    ctx.notes.extend(continuous_duty_note(ctx, duty, effort_by))
    # the operating points first: when they are the speed-torque line, its slope is a gradient source
    resistance_value, resistance_method = resistance(ctx)
    gradient, gradient_method_used, reason = choose_gradient(ctx, method, explicit, velocity_by)
    max_effort = value_of(effort, effort_by)
    max_velocity = value_of(velocity, velocity_by)
    envelope = PerformanceEnvelope(
        name=datasheet.name,
        joint=datasheet.joint,
        max_effort=max_effort,
        max_actuator_velocity=max_velocity,
        velocity_dependent_resistance=resistance_value,
        speed_effort_gradient=gradient,
    )
    ctx.notes.extend(_envelope_notes(envelope, velocity, velocity_by, ctx))
    ctx.provenance["max_effort"] = limit_source(ctx, effort_by, "gear_torque")
    ctx.provenance["max_actuator_velocity"] = limit_source(ctx, velocity_by, None)
    fit = line_fit(ctx, method, velocity, velocity_by, max_effort) if approximate_line else None
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
        warnings=tuple(plausibility_warnings(ctx)),
        line_fit=fit,
    )


def _envelope_notes(
    envelope: PerformanceEnvelope, velocity: list[Candidate], velocity_by: str, ctx: DeriveContext
) -> list[str]:
    """What the derived numbers imply that a reader of the datasheet would not expect.

    * The speed line reaches zero speed below max_effort (``v_max / G < max_effort``): no operating
      point reaches max_effort; the line decides the stall effort.
    * The effort line reaches zero effort below max_actuator_velocity (``max_effort / R < v_max``):
      no operating point reaches that speed; the resistance decides the no-load speed.
    * The voltage limit binds only because of the default modulation mu_C = 0.9, below a printed
      speed (an output rating or no-load speed).
    """
    notes = []
    unit = ctx.units["joint_effort"]
    gradient, top = envelope.speed_effort_gradient, envelope.max_actuator_velocity
    if gradient > 0.0 and math.isfinite(top) and top / gradient < envelope.max_effort:
        stall = top / gradient
        notes.append(
            f"the speed line reaches zero speed at {stall:.6g} {unit} (max_actuator_velocity / "
            f"speed_effort_gradient), below max_effort = {envelope.max_effort:.6g} {unit}: no operating "
            "point reaches max_effort"
        )
    resistance = envelope.velocity_dependent_resistance
    if resistance > 0.0 and envelope.max_effort / resistance < top:
        speed_unit = ctx.units["joint_speed"]
        notes.append(
            f"the effort line reaches zero effort at {envelope.max_effort / resistance:.6g} {speed_unit} "
            f"(max_effort / velocity_dependent_resistance), below max_actuator_velocity = {top:.6g} "
            f"{speed_unit}: no operating point reaches max_actuator_velocity"
        )
    if velocity_by == "voltage" and ctx.provenance.get("controller.modulation") == "default":
        printed = [c for c in velocity if c.name.startswith("output") and c.value is not None]
        for c in printed:
            if c.value is not None and c.value > envelope.max_actuator_velocity:
                speed_unit = ctx.units["joint_speed"]
                notes.append(
                    f"the voltage limit with the default mu_C = 0.9 ({envelope.max_actuator_velocity:.6g} "
                    f"{speed_unit}) is below the printed {c.name} {c.value:.6g} {speed_unit}: give "
                    "controller.modulation = 1 if the datasheet's speed is at full duty"
                )
    return notes

"""The working state of one derivation: the transmission, k_t and k_v, units, notes and provenance.

:func:`build_context` resolves what every formula of the derivation needs once: the gear and screw
(with their documented defaults, recorded as such), the motor constants (one given alone gives the
other as its SI reciprocal) and the units of the report.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from drive_envelope._src.datasheet.result import Candidate
from drive_envelope._src.datasheet.spec import Datasheet, ParamSource, Transmission

Input = tuple[str, float | None, str]
"""``(key, SI value or None, SI unit)`` of one input of a formula."""


@dataclass(kw_only=True, slots=True)
class DeriveContext:
    """Working state of one derivation: resolved inputs, units, notes and provenance."""

    sheet: Datasheet
    """The datasheet being derived."""
    transmission: Transmission
    """Gear and screw, defaults applied."""
    units: Mapping[str, str]
    """SI units for the report: ``torque``, ``speed``, ``kt``, ``kv``, ``gradient`` (motor side) and
    ``joint_effort``, ``joint_speed``, ``joint_gradient``, ``joint_resistance``."""
    gear_inputs: tuple[Input, ...]
    """``gear.ratio`` and ``gear.efficiency`` as formula inputs (empty for direct drive)."""
    screw_inputs: tuple[Input, ...]
    """``screw.lead`` and ``screw.efficiency`` as formula inputs (empty without a screw)."""
    torque_constant: float | None = None
    """k_t [N*m/A or N/A], given or the SI reciprocal of k_v."""
    speed_constant: float | None = None
    """k_v [(rad/s)/V or (m/s)/V], given, from k_e, or the SI reciprocal of k_t."""
    curve_gradient: float | None = None
    """Delta v / Delta tau at the joint [(rad/s)/(N*m) or (m/s)/N] of ``losses.operating_points``
    that are the speed-torque line (eq. 2); None when they are not (or there are none)."""
    notes: list[str] = field(default_factory=list)
    """Defaults used and values derived, in plain words."""
    provenance: dict[str, ParamSource] = field(default_factory=dict)
    """``section.key`` or parameter name -> where the value came from."""


def build_context(sheet: Datasheet) -> DeriveContext:
    """Resolve the transmission, k_t and k_v, recording defaults and derived values."""
    linear = sheet.linear_motor
    prismatic = sheet.joint == "prismatic"
    units = {
        "torque": "N" if linear else "N*m",
        "speed": "m/s" if linear else "rad/s",
        "kt": "N/A" if linear else "N*m/A",
        "kv": "(m/s)/V" if linear else "(rad/s)/V",
        "gradient": "(m/s)/N" if linear else "(rad/s)/(N*m)",
        "joint_effort": "N" if prismatic else "N*m",
        "joint_speed": "m/s" if prismatic else "rad/s",
        "joint_gradient": "(m/s)/N" if prismatic else "(rad/s)/(N*m)",
        "joint_resistance": "N*s/m" if prismatic else "N*m*s/rad",
    }
    notes: list[str] = list(sheet.notes)
    provenance: dict[str, ParamSource] = dict(sheet.provenance)
    gear, screw = sheet.gear, sheet.screw
    gear_inputs: list[Input] = []
    if gear is None:
        notes.append("no [gear]: direct drive (i_G = 1, eta_G = 1)")
        ratio, efficiency = 1.0, 1.0
    else:
        ratio = gear.ratio
        efficiency = 1.0 if gear.efficiency is None else gear.efficiency
        if gear.efficiency is None:
            notes.append("gear.efficiency not given: eta_G = 1.0 (no gear losses) assumed")
            provenance["gear.efficiency"] = "default"
        gear_inputs = [("gear.ratio", ratio, "1"), ("gear.efficiency", efficiency, "1")]
    factor, screw_efficiency = 1.0, 1.0
    screw_inputs: list[Input] = []
    if screw is not None:
        factor = 2.0 * math.pi / screw.lead
        screw_efficiency = 1.0 if screw.efficiency is None else screw.efficiency
        if screw.efficiency is None:
            notes.append("screw.efficiency not given: eta_S = 1.0 assumed")
            provenance["screw.efficiency"] = "default"
        screw_inputs = [("screw.lead", screw.lead, "m/rev"), ("screw.efficiency", screw_efficiency, "1")]
    ctx = DeriveContext(
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


def _motor_constants(ctx: DeriveContext) -> None:
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


def candidate(
    name: str, formula: str, inputs: Sequence[Input], compute: Callable[[list[float]], float]
) -> Candidate:
    """A candidate whose value is ``compute(input values)`` when every input is present, else None."""
    present = [value for _, value, _ in inputs if value is not None]
    missing = tuple(key for key, value, _ in inputs if value is None)
    value = None if missing else float(compute(present))
    return Candidate(name=name, value=value, formula=formula, inputs=tuple(inputs), missing=missing)

"""Warnings for datasheet inputs that are valid but look like a unit slip.

A derivation still runs (vendors differ, and the user may know better), but inputs that disagree
with each other by more than a factor of two, or an efficiency that reads like a percentage typed
without its ``%``, are named with the numbers, so that a 1000x slip (``mNm/A`` written as a bare
``N*m/A`` number) is loud instead of silent.
"""

from __future__ import annotations

from drive_envelope._src.datasheet.context import DeriveContext
from drive_envelope._src.format import format_value

__all__ = ["FACTOR", "LOWEST_EFFICIENCY", "PLAUSIBLE", "plausibility_warnings"]

FACTOR = 2.0
"""Redundant inputs that disagree by more than this factor draw a warning."""
LOWEST_EFFICIENCY = 0.2
"""An efficiency below this draws a warning (``0.9 %`` typed for ``90 %``)."""
PLAUSIBLE: dict[str, tuple[float, float, str]] = {
    "terminal_resistance": (1e-4, 1e3, "ohm"),
    "torque_constant": (1e-4, 1e2, "N*m/A"),
    "speed_constant": (1e-2, 1e4, "rad/s/V"),
}
"""Rotary motors' constants outside these bounds [SI] are a unit slip far more often than a motor:
from a large servo motor's few milliohms to a coreless micro motor's hundreds of ohms, with margin
(``1000 MΩ`` typed for ``mΩ`` is 1e9 ohm)."""


def plausibility_warnings(ctx: DeriveContext) -> list[str]:
    """One sentence per suspicious input: motor constants, printed vs computed gradient, efficiencies."""
    warnings: list[str] = []
    motor = ctx.sheet.motor
    source = ctx.sheet.source
    if motor is not None and motor.torque_constant is not None and motor.speed_constant is not None:
        product = motor.torque_constant * motor.speed_constant
        if not 1.0 / FACTOR <= product <= FACTOR:
            warnings.append(
                f"{source}: motor.torque_constant * motor.speed_constant = {product:.4g} in SI units, "
                f"an ideal motor has 1 (k_t = 1/k_v): check their units ('mNm/A' vs 'N*m/A', 'rpm/V')"
            )
    kt = ctx.torque_constant
    if motor is not None and None not in (motor.speed_torque_gradient, motor.terminal_resistance, kt):
        printed = float(motor.speed_torque_gradient)  # type: ignore[arg-type]
        computed = float(motor.terminal_resistance) / float(kt) ** 2  # type: ignore[arg-type]
        if computed > 0.0 and not 1.0 / FACTOR <= printed / computed <= FACTOR:
            unit = ctx.units["gradient"]
            warnings.append(
                f"{source}: motor.speed_torque_gradient = {format_value(printed, unit)} but "
                f"terminal_resistance / torque_constant^2 = {format_value(computed, unit)} "
                f"({printed / computed:.3g}x): check their units"
            )
    warnings += _outside_plausible(ctx) + _current_conventions(ctx)
    for key, value in (
        ("gear.efficiency", ctx.transmission.efficiency),
        ("screw.efficiency", ctx.transmission.screw_efficiency),
    ):
        if value < LOWEST_EFFICIENCY:
            warnings.append(
                f"{source}: {key} = {value:.4g} is unusually low: a percentage needs its sign ('90 %' or 0.9)"
            )
    return warnings


def _outside_plausible(ctx: DeriveContext) -> list[str]:
    """Rotary motor constants outside :data:`PLAUSIBLE`, each with the bounds."""
    motor = ctx.sheet.motor
    if motor is None or ctx.sheet.linear_motor:
        return []
    found = []
    for key, (low, high, unit) in PLAUSIBLE.items():
        value = getattr(motor, key, None)
        if value is not None and value > 0.0 and not low <= value <= high:
            found.append(
                f"{ctx.sheet.source}: motor.{key} = {format_value(value, unit)} is outside what motors have "
                f"({format_value(low, unit)} to {format_value(high, unit)}): check its unit prefix "
                "('mohm' vs 'Mohm', 'mNm/A' vs 'N*m/A')"
            )
    return found


def _current_conventions(ctx: DeriveContext) -> list[str]:
    """A torque constant per A rms used with a peak current (or the reverse): a sqrt(2) slip."""
    marks = ctx.sheet.current_conventions
    kt, current = marks.get("motor.torque_constant"), marks.get("controller.max_current")
    if kt is None or current is None or kt == current:
        return []
    factor = "too high by sqrt(2) = 1.414" if kt == "rms" else "too low by sqrt(2) = 1.414"
    fix = "I_rms = I_pk / sqrt(2)" if kt == "rms" else "I_pk = I_rms * sqrt(2)"
    return [
        f"{ctx.sheet.source}: motor.torque_constant is per A {kt} but controller.max_current is marked "
        f"{current}: both are read as plain amperes, so the controller_current limit is {factor} for a "
        f"sinusoidal current; write max_current in the torque constant's convention ({fix})"
    ]

"""Warnings for datasheet inputs that are valid but look like a unit slip.

A derivation still runs (vendors differ, and the user may know better), but inputs that disagree
with each other by more than a factor of two, or an efficiency that reads like a percentage typed
without its ``%``, are named with the numbers, so that a 1000x slip (``mNm/A`` written as a bare
``N*m/A`` number) is loud instead of silent.
"""

from __future__ import annotations

from drive_envelope._src.datasheet.context import DeriveContext
from drive_envelope._src.format import format_value

__all__ = ["FACTOR", "LOWEST_EFFICIENCY", "plausibility_warnings"]

FACTOR = 2.0
"""Redundant inputs that disagree by more than this factor draw a warning."""
LOWEST_EFFICIENCY = 0.2
"""An efficiency below this draws a warning (``0.9 %`` typed for ``90 %``)."""


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
    for key, value in (
        ("gear.efficiency", ctx.transmission.efficiency),
        ("screw.efficiency", ctx.transmission.screw_efficiency),
    ):
        if value < LOWEST_EFFICIENCY:
            warnings.append(
                f"{source}: {key} = {value:.4g} is unusually low: a percentage needs its sign ('90 %' or 0.9)"
            )
    return warnings

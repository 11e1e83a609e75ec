"""Warnings for datasheet inputs that are valid but look like a unit slip.

A derivation still runs (vendors differ, and the user may know better), but inputs that disagree
with each other by more than a factor of two, an efficiency or modulation that reads like a
percentage typed without its ``%``, or a motor constant typed as a bare number of the size vendors
print in ``mNm/A`` with nothing to check it against, are named with the numbers, so that a 1000x
slip (``mNm/A`` written as a bare ``N*m/A`` number) is loud instead of silent.
"""

from __future__ import annotations

from drive_envelope._src.datasheet.context import DeriveContext
from drive_envelope._src.format import format_value

FACTOR = 2.0
"""Redundant inputs that disagree by more than this factor draw a warning."""
SPEED_FACTOR = 6.0
"""A printed no-load speed and ``k_v * V`` that disagree by more than this draw a warning: wide
enough for a motor rated at another voltage than the controller's (48 V on 12 V is 4x), narrow
enough for ``rpm`` read as ``rad/s`` (9.55x)."""
LOWEST_EFFICIENCY = 0.2
"""An efficiency or a controller modulation below this draws a warning (``0.9 %`` typed for ``90 %``)."""
BARE_MOTOR_CONSTANT = 1.0
"""A motor's ``torque_constant`` or ``back_emf_constant`` written as a bare number above this [SI] with
nothing to check it against draws a warning: vendors print them in ``mNm/A`` and ``V/krpm``, so
``91`` is far more often 91 mNm/A than 91 N*m/A. The bounds of :data:`PLAUSIBLE` cannot say so,
since a geared actuator's output-shaft constant is that large (the catalog's Harmonic Drive FHA-8C-50:
1.3 N*m/A), but such a value is printed with its unit, which silences the warning."""
PLAUSIBLE: dict[str, tuple[float, float, str]] = {
    "terminal_resistance": (1e-4, 1e3, "ohm"),
    "torque_constant": (1e-4, 1e2, "N*m/A"),
    "speed_constant": (1e-2, 1e4, "rad/s/V"),
    "no_load_speed": (1e-1, 1.2e4, "rad/s"),
    "max_speed": (1e-1, 1.2e4, "rad/s"),
}
"""Rotary motors' constants outside these bounds [SI] are a unit slip far more often than a motor:
from a large servo motor's few milliohms to a coreless micro motor's hundreds of ohms, with margin
(``1000 MΩ`` typed for ``mΩ`` is 1e9 ohm); speeds up to the fastest micro motors' 100,000 rpm
(``10000 rad/s`` is 95,000 rpm)."""


def plausibility_warnings(ctx: DeriveContext) -> list[str]:
    """One sentence per suspicious input: motor constants, printed vs computed gradient, efficiencies."""
    warnings: list[str] = []
    motor = ctx.sheet.motor
    source = ctx.sheet.source
    warnings += _constants_agree(ctx)
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
    warnings += _outside_plausible(ctx) + _bare_constants(ctx) + _current_conventions(ctx) + _speed_line(ctx)
    controller = ctx.sheet.controller
    for key, value in (
        ("gear.efficiency", ctx.transmission.efficiency),
        ("screw.efficiency", ctx.transmission.screw_efficiency),
        # the default 0.9 is never low; a given one is a fraction read as an efficiency is
        ("controller.modulation", controller.modulation if controller is not None else None),
    ):
        if value is not None and value < LOWEST_EFFICIENCY:
            warnings.append(
                f"{source}: {key} = {value:.4g} is unusually low: a percentage needs its sign ('90 %' or 0.9)"
            )
    return warnings


def _constants_agree(ctx: DeriveContext) -> list[str]:
    """k_t against k_v (or k_e, given instead): an ideal motor has k_t * k_v = k_t / k_e = 1 in SI."""
    motor = ctx.sheet.motor
    if motor is None or motor.torque_constant is None:
        return []
    if motor.speed_constant is not None:
        product = motor.torque_constant * motor.speed_constant
        pair, ideal, units = "motor.torque_constant * motor.speed_constant", "k_t = 1/k_v", "'rpm/V'"
    elif motor.back_emf_constant is not None:
        # k_e = 1/k_v in SI: the same check, or a 'V/krpm' slip passes unseen when k_e is given
        product = motor.torque_constant / motor.back_emf_constant
        pair, ideal, units = "motor.torque_constant / motor.back_emf_constant", "k_t = k_e", "'V/krpm'"
    else:
        return []
    if 1.0 / FACTOR <= product <= FACTOR:
        return []
    return [
        f"{ctx.sheet.source}: {pair} = {product:.4g} in SI units, an ideal motor has 1 ({ideal}): "
        f"check their units ('mNm/A' vs 'N*m/A', {units})"
    ]


def _bare_constants(ctx: DeriveContext) -> list[str]:
    """A bare ``torque_constant`` or ``back_emf_constant`` above :data:`BARE_MOTOR_CONSTANT`, unchecked.

    Given with the other constant, :func:`_constants_agree` checks the pair instead (and a bare value
    that agrees with a printed one is confirmed); a linear motor's force constant is tens of N/A.
    """
    motor, sheet = ctx.sheet.motor, ctx.sheet
    if motor is None or sheet.linear_motor:
        return []
    checked = motor.torque_constant is not None and (
        motor.speed_constant is not None or motor.back_emf_constant is not None
    )
    found = []
    for key, unit, printed in (
        ("torque_constant", "N*m/A", "mNm/A"),
        ("back_emf_constant", "V*s/rad", "V/krpm"),
    ):
        value = getattr(motor, key)
        if checked or value is None or f"motor.{key}" not in sheet.bare_numbers:
            continue
        if value > BARE_MOTOR_CONSTANT:
            found.append(
                f"{sheet.source}: motor.{key} = {value:g} is a bare number, read as {value:g} {unit} (a "
                f"bare number is SI); vendors print it in {printed}: write '{value:g} {printed}' if that "
                f"is what the datasheet says, or '{value:g} {unit}' to keep it"
            )
    return found


def _outside_plausible(ctx: DeriveContext) -> list[str]:
    """Rotary motor constants outside :data:`PLAUSIBLE`, each with the bounds."""
    motor = ctx.sheet.motor
    if motor is None or ctx.sheet.linear_motor:
        return []
    found = []
    for key, (low, high, unit) in PLAUSIBLE.items():
        value = getattr(motor, key, None)
        if value is not None and value > 0.0 and not low <= value <= high:
            hint = (
                "check its unit ('rpm' vs 'rad/s', 'krpm')"
                if unit == "rad/s"
                else "check its unit prefix ('mohm' vs 'Mohm', 'mNm/A' vs 'N*m/A')"
            )
            found.append(
                f"{ctx.sheet.source}: motor.{key} = {format_value(value, unit)} is outside what motors have "
                f"({format_value(low, unit)} to {format_value(high, unit)}): {hint}"
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


def _speed_line(ctx: DeriveContext) -> list[str]:
    """The speed line's redundant ends: a printed no-load speed against ``k_v * V``.

    A DC motor's no-load speed is its speed constant times the supply voltage (a little less, for
    friction, and vendors print it at the motor's rated voltage, not the controller's); the two
    disagreeing by more than :data:`SPEED_FACTOR` is a unit slip on one of them (``rpm`` read as
    ``rad/s`` is 9.55x, ``rpm/V`` as ``rad/s/V`` too), and it moves the joint's speed line.
    """
    motor, controller = ctx.sheet.motor, ctx.sheet.controller
    if motor is None or controller is None or ctx.sheet.linear_motor:
        return []
    kv = motor.speed_constant
    if kv is None and motor.back_emf_constant:
        kv = 1.0 / motor.back_emf_constant
    voltage, printed = controller.max_voltage, motor.no_load_speed
    if not kv or not voltage or not printed:
        return []
    computed = kv * voltage
    if 1.0 / SPEED_FACTOR <= printed / computed <= SPEED_FACTOR:
        return []
    return [
        f"{ctx.sheet.source}: motor.no_load_speed = {format_value(printed, 'rad/s')} but speed_constant "
        f"* controller.max_voltage = {format_value(computed, 'rad/s')} ({printed / computed:.3g}x): "
        "check their units ('rpm' vs 'rad/s', 'rpm/V'); the no-load speed sets the speed line"
    ]

"""The one unit registry of drive_envelope and the conversion of user quantities to SI floats.

pint is used only here, at the input edges. Inside the library every number is an SI float.

Two traps are closed on purpose:

* pint treats angles as dimensionless, so ``60 rpm`` converts to ``6.283 Hz`` and ``1/min`` converts
  to rad/s without the factor 2*pi. A quantity whose SI unit contains an angle (rad/s, N*m*s/rad,
  ...) must therefore carry an angle unit too (rpm, rev/s, deg/s, rad/s, ...); Hz and bare 1/s are
  refused for it as ambiguous. Datasheet spellings of revolutions per minute (``min^-1``, ``1/min``,
  ``r/min``) are read as rpm before parsing.
* Datasheets print torques as ``kg*cm`` or ``oz*in`` (kilogram-force and ounce-force): where a
  torque is expected, a mass times a length is read as the corresponding force times length.
* N*m and J share a dimension: a torque written in joules is refused (it is an energy column).

Hobby-servo speeds are read as printed, time per angle: ``"0.14 s/60°"`` is 60 deg per 0.14 s.
"""

from __future__ import annotations

import functools
import math
import re
from typing import TYPE_CHECKING, Any

from drive_envelope._src.errors import UnitsError

if TYPE_CHECKING:
    import pint

__all__ = ["format_si", "get_registry", "to_si"]

# Vendor spellings -> pint spellings. Applied to the unit part of a string, in this order.
_SPELLINGS: tuple[tuple[str, str], ...] = (
    (r"Ω", "ohm"),
    (r"\bOhm\b", "ohm"),
    (r"µ", "u"),
    (r"μ", "u"),
    (r"⁻¹", "^-1"),
    (r"²", "^2"),
    (r"\bmin\s*\^\s*-\s*1\b|\bmin\s*-\s*1\b|\b1\s*/\s*min\b|\br\s*/\s*min\b|\brev\s*/\s*min\b", "rpm"),
    # what is left of "rev" is a revolution (a lead in mm/rev); pint knows it as "turn"
    (r"\brev\b", "turn"),
    (r"\bm(Nm|N\.m|N-m)\b", "(mN*m)"),
    (r"\bNmm\b", "(N*mm)"),
    (r"\b(Nm|N\.m|N-m)\b", "(N*m)"),
    (r"\bNcm\b", "(N*cm)"),
    (r"\bkgf?\s*[-*.·]?\s*cm\b", "(kgf*cm)"),
    (r"\bozf?\s*[-*.·]?\s*in\b", "(ozf*in)"),
    (r"\blbf?\s*[-*.·]?\s*in\b", "(lbf*in)"),
    (r"\blbf?\s*[-*.·]?\s*ft\b", "(lbf*ft)"),
    (r"·", "*"),
    (r"%", "percent"),
)

_NUMBER_AND_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf)\s*(.*?)\s*$")


@functools.lru_cache(maxsize=1)
def get_registry() -> pint.UnitRegistry:
    """Return the single pint registry of the library (built on first use).

    Returns:
        The shared ``pint.UnitRegistry``; all quantities passed to drive_envelope must come from it.
    """
    import pint

    ureg: Any = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    ureg.define("kilogram_force_centimeter = kilogram_force * centimeter = kgfcm")
    return ureg


def _normalize_unit_text(text: str) -> str:
    for pattern, replacement in _SPELLINGS:
        text = re.sub(pattern, replacement, text)
    return text


def _radian_exponent(ureg: pint.UnitRegistry, units: Any) -> float:
    root: Any = ureg.get_root_units(units)[1]
    exponent: Any = dict(root._units).get("radian", 0.0)  # pint has no public accessor
    return float(exponent)


# A hobby servo's speed as printed: time per angle, "0.14 s/60°" or "0.17 sec/60 deg".
_SERVO_SPEED = re.compile(
    r"^\s*(\d+\.?\d*|\.\d+)\s*(?:s|sec|seconds?)\s*/\s*(\d+\.?\d*)\s*(?:°|º|deg|degrees?)\s*$"
)


def _parse(text: str, where: str) -> pint.Quantity:
    ureg = get_registry()
    servo = _SERVO_SPEED.match(text)
    if servo is not None:
        seconds, degrees = float(servo.group(1)), float(servo.group(2))
        if seconds > 0.0:
            return ureg.Quantity(degrees / seconds, "deg/s")
    match = _NUMBER_AND_UNIT.match(text)
    if match is None:
        raise UnitsError(
            f"{where}: cannot read {text!r} as a number with a unit (e.g. '3000 rpm', '0.091 N*m/A')"
        )
    number, unit_text = match.group(1), match.group(2)
    try:
        magnitude = float(number)
        unit = ureg.Unit(_normalize_unit_text(unit_text)) if unit_text else ureg.dimensionless
    except Exception as exc:  # pint raises several unrelated types for unknown or malformed units
        raise UnitsError(f"{where}: unknown unit {unit_text!r} in {text!r}") from exc
    return ureg.Quantity(magnitude, unit)


def _torque_from_mass_length(q: pint.Quantity, expected: pint.Unit) -> pint.Quantity:
    """Read ``kg*cm``-style torques (mass*length) as kilogram-force*length, as datasheets mean them."""
    ureg = get_registry()
    if (
        q.dimensionality == ureg.Unit("kg*m").dimensionality
        and expected.dimensionality == ureg.Unit("N*m").dimensionality
    ):
        return q * ureg.Quantity(1.0, "standard_gravity")
    return q


def _is_energy_for_torque(quantity: pint.Quantity, expected: str) -> bool:
    """Whether a torque-like quantity was written in joules.

    N*m and J share a dimension, so pint accepts ``"2 J"`` as a torque; on a datasheet that is a
    misread column (energy), never a torque, so it is refused rather than silently accepted.
    """
    names = dict(quantity.units._units)  # pint has no public accessor for the unit names
    return "N*m" in expected.replace(" ", "") and any(name.endswith("joule") for name in names)


def to_si(value: object, expected: str, where: str) -> float:
    """Convert a user quantity to an SI float.

    Args:
        value: A bare number (already in the SI unit ``expected``), a string with units as datasheets
            print them (``"3000 rpm"``, ``"91 mNm/A"``), or a ``pint.Quantity`` of the library registry.
        expected: The SI unit of the result, as pint reads it (``"rad/s"``, ``"N*m"``, ...).
        where: The file and key (or argument) the value comes from; it starts every error message.

    Returns:
        The magnitude in ``expected`` [SI].

    Raises:
        UnitsError: unknown unit, wrong dimension, a missing angle unit on an angular quantity, or a
            value that is not a number.
    """
    ureg = get_registry()
    if isinstance(value, bool) or value is None:
        raise UnitsError(f"{where}: expected a number or a quantity string in {expected}, got {value!r}")
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str):
        quantity = _parse(value, where)
    elif isinstance(value, ureg.Quantity):
        quantity = value
    else:
        raise UnitsError(
            f"{where}: expected a number or a quantity string in {expected}, "
            f"got {type(value).__name__} {value!r}"
        )
    target = ureg.Unit(expected)
    quantity = _torque_from_mass_length(quantity, target)
    if quantity.dimensionality != target.dimensionality:
        raise UnitsError(
            f"{where}: {value!r} has dimension {quantity.dimensionality}, expected a quantity in {expected}"
        )
    if _is_energy_for_torque(quantity, expected):
        raise UnitsError(
            f"{where}: {value!r} is an energy unit (J); a torque is expected here, in {expected} "
            "(write N*m, mNm, ...)"
        )
    if _radian_exponent(ureg, quantity.units) != _radian_exponent(ureg, target):
        raise UnitsError(
            f"{where}: {value!r} has no matching angle unit for {expected}; angles are explicit here "
            "(write rpm, rev/s, deg/s or rad/s: Hz and 1/s are ambiguous)"
        )
    magnitude: Any = quantity.m_as(target)
    result = float(magnitude)
    if math.isnan(result):
        raise UnitsError(f"{where}: {value!r} is not a number")
    return result


def format_si(value: float, unit: str) -> str:
    """Format an SI float with its unit for reports: ``12.06 N*m``, ``inf rad/s``."""
    if math.isinf(value):
        return f"{'-' if value < 0 else ''}inf {unit}"
    return f"{value:.6g} {unit}"

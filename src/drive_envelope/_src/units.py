"""The one unit registry of drive_envelope and the conversion of user quantities to SI floats.

pint is used only here, at the input edges. Inside the library every number is an SI float.

A bare number is SI everywhere: a number in a file, a quoted number (``"12"``) and a number given
on the command line all mean the key's SI unit. Strings with units are read as vendors print
them (the spellings, each mapping to exactly one unit, are listed in ``docs/datasheet.md``).

Traps closed on purpose:

* pint treats angles as dimensionless, so ``60 rpm`` converts to ``6.283 Hz`` and ``1/min`` converts
  to rad/s without the factor 2*pi. A quantity whose SI unit contains an angle (rad/s, N*m*s/rad,
  ...) must therefore carry an angle unit too (rpm, rev/s, deg/s, rad/s, ...); Hz and bare 1/s are
  refused for it as ambiguous. Datasheet spellings of revolutions per minute (``min^-1``, ``1/min``,
  ``r/min``, ``RPM``) are read as rpm before parsing.
* Datasheets print torques as ``kg*cm`` or ``oz*in`` (kilogram-force and ounce-force): where a
  torque is expected, a mass times a length is read as the corresponding force times length.
* N*m and J share a dimension: a torque written in joules is refused (it is an energy column).
* A comma in a number is refused: ``16,1`` (decimal comma) and ``1,500`` (thousands separator or
  decimal comma?) cannot both be read safely, so the message shows how to write it. A space (or a
  thin space) between groups of three digits is a thousands separator: ``"12 000 rpm"``.
* rms and peak markers (``Arms``, ``Apk``, ``Vrms``) are read as plain amperes and volts: matching
  the conventions of k_t, the current limit and R is the user's job (the docs say so).

Hobby-servo speeds are read as printed, time per angle: ``"0.14 s/60°"`` is 60 deg per 0.14 s.
"""

from __future__ import annotations

import functools
import math
import numbers
import re
from typing import TYPE_CHECKING, Any, SupportsFloat

from drive_envelope._src.errors import UnitsError

if TYPE_CHECKING:
    import pint

_ANGLE_SPEED = r"(?:rpm|RPM|Rpm)"
# Vendor spellings -> pint spellings. Applied to the unit part of a string, in this order.
_SPELLINGS: tuple[tuple[str, str], ...] = (
    (r"Ω", "ohm"),
    (r"µ", "u"),
    (r"μ", "u"),
    (r"⁻¹", "^-1"),
    (r"²", "^2"),
    (r"³", "^3"),
    (r"[·⋅•]", "*"),
    (r"\b([kMm]?)(?:Ohms?|ohms)\b", r"\1ohm"),
    # words and run-together symbols of one unit each: "10 Amps", "rpm/Volt", "Vs/rad"
    (r"\b(m?)(?:Amps?|amps?|Amperes?|amperes?)\b", r"\1A"),
    (r"\b(m?)(?:Volts?|volts?)\b", r"\1V"),
    (r"\bVs\b", "(V*s)"),
    # rms / peak markers on amperes and volts: the unit is the ampere (volt); conventions are the user's
    (r"\b([Am]?A)\s*\(?\s*(?:rms|RMS|pk|PK|peak)\s*\)?(?![A-Za-z])", r"\1"),
    (r"\b([mk]?V)\s*\(?\s*(?:rms|RMS|pk|PK|peak)\s*\)?(?![A-Za-z])", r"\1"),
    (r"\b([mk]?V)\s*(?:DC|dc|Dc)\b", r"\1"),
    (r"\b[kK]" + _ANGLE_SPEED + r"\b", "krpm"),
    (r"\b" + _ANGLE_SPEED + r"\b", "rpm"),
    (r"\bmin\s*\^\s*-\s*1\b|\bmin\s*-\s*1\b|\b1\s*/\s*min\b|\br\s*/\s*min\b|\brev\s*/\s*min\b", "rpm"),
    (r"/\s*1000\s*rpm\b", "/krpm"),
    # what is left of "rev" is a revolution (a lead in mm/rev); pint knows it as "turn"
    (r"\brev\b", "turn"),
    (r"\bm(Nm|N\.m|N-m)\b", "(mN*m)"),
    (r"\bNmm\b", "(N*mm)"),
    (r"\b(Nm|N\.m|N-m)\b", "(N*m)"),
    (r"\bN\s*[-.]?\s*cm\b", "(N*cm)"),
    # kilogram-force lengths (a servo's "kg.cm"); not kg*cm^2, an inertia
    (r"\b[kK][gG]f?\s*[-*.]?\s*(cm|mm)\b(?!\s*\^)", r"(kgf*\1)"),
    (r"\b(?:ozf?\s*[-*.]?\s*in|in\s*[-*.]?\s*ozf?)\b", "(ozf*in)"),
    (r"\b(?:lbf?\s*[-*.]?\s*in|in\s*[-*.]?\s*lbf?)\b", "(lbf*in)"),
    (r"\b(?:lbf?\s*[-*.]?\s*ft|ft\s*[-*.]?\s*lbf?)\b", "(lbf*ft)"),
    (r"%", "percent"),
)
# A hobby motor's "KV": rpm per volt (never kilovolt, which is written kV). Only as the whole unit.
_HOBBY_KV = re.compile(r"^(?:KV|Kv)$")

_THOUSANDS = "[ \u00a0\u2009\u202f]"
_NUMBER_AND_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf)\s*(.*?)\s*$")
_GROUPED = re.compile(rf"^\s*([-+]?\d{{1,3}}(?:{_THOUSANDS}\d{{3}})+)(?![\d])(.*)$", re.DOTALL)
_COMMA_NUMBER = re.compile(r"^\s*([-+]?\d+(?:[.,]\d+)*,\d+(?:[.,]\d+)*)")

# SI unit -> what it is, in words, with an example, for error messages.
_WORDS: dict[str, tuple[str, str]] = {
    "N*m": ("a torque", "2.5 Nm"),
    "N": ("a force", "100 N"),
    "rad/s": ("an angular speed", "3000 rpm"),
    "m/s": ("a linear speed", "20 mm/s"),
    "N*m/A": ("a torque constant", "91 mNm/A"),
    "N/A": ("a force constant", "20 N/A"),
    "rad/s/V": ("a speed constant", "100 rpm/V"),
    "m/s/V": ("a speed constant", "0.01 m/s/V"),
    "V*s/rad": ("a back-EMF constant", "10 V/krpm"),
    "V*s/m": ("a back-EMF constant", "20 V*s/m"),
    "rad/s/(N*m)": ("a speed-torque gradient", "9 rpm/mNm"),
    "m/s/N": ("a speed-force gradient", "0.1 mm/s/N"),
    "N*m*s/rad": ("a velocity-dependent resistance", "0.02 N*m*s/rad"),
    "N*s/m": ("a velocity-dependent resistance", "5 N*s/m"),
    "A": ("a current", "24 A"),
    "V": ("a voltage", "24 V"),
    "ohm": ("a resistance", "170 mohm"),
    "dimensionless": ("a plain number", "6 or 0.9"),
    "m": ("a length", "5 mm"),
    "m/turn": ("a lead (travel per revolution)", "5 mm/rev"),
    "kg*m^2": ("an inertia", "68 g*cm^2"),
    "s": ("a time", "5 ms"),
}


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


def describe_unit(unit: str) -> str:
    """``"a torque in N*m (e.g. '2.5 Nm')"``: an SI unit of this library in words, for messages."""
    words, example = _WORDS.get(unit.replace(" ", ""), (f"a quantity in {unit}", ""))
    if words.startswith("a quantity"):
        return words
    return f"{words} in {unit} (e.g. {example!r})"


def _normalize_unit_text(text: str) -> str:
    if _HOBBY_KV.match(text.strip()):
        return "(rpm/V)"
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


def _ungroup(text: str) -> str:
    """``"12 000 rpm"`` -> ``"12000 rpm"``: spaces between groups of three digits are separators."""
    match = _GROUPED.match(text)
    if match is None:
        return text
    return re.sub(_THOUSANDS, "", match.group(1)) + match.group(2)


def _refuse_comma(text: str, where: str) -> None:
    """A comma in the number is refused with a hint: it is either ambiguous or a decimal comma."""
    match = _COMMA_NUMBER.match(text)
    if match is None:
        return
    number = match.group(1)
    rest = text[match.end() :]
    if re.fullmatch(r"[-+]?\d{1,3}(?:,\d{3})+", number):
        plain = (number.replace(",", "") + rest).strip()
        options = repr(plain)
        if number.count(",") == 1:
            options += f" (thousands separator) or {(repr(float(number.replace(',', '.'))) + rest).strip()!r}"
            options += " (decimal comma)"
        raise UnitsError(
            f"{where}: {text.strip()!r}: a comma in a number is ambiguous (thousands separator or "
            f"decimal comma); write {options}"
        )
    fixed = number.replace(".", "").replace(",", ".") if number.count(",") == 1 else number
    raise UnitsError(
        f"{where}: {text.strip()!r}: a decimal comma is not read; write {(fixed + rest).strip()!r} "
        "(decimal point, no thousands separator)"
    )


# "46 RPM ±10%", "24 V +/- 5 %": the nominal is read, the tolerance said (a warning)
_TOLERANCE = re.compile(r"\s*(?:±|\+/-|\+-)\s*(\d+\.?\d*|\.\d+)\s*%\s*$")
# "DC24V": a supply voltage with its kind in front
_DC_PREFIX = re.compile(r"^\s*(?:DC|dc)\s*(?=[-+]?[\d.])")


def _without_tolerance(text: str, where: str) -> str:
    """``text`` without a trailing ``±N %`` tolerance, which is said in a warning (the nominal is read)."""
    import warnings

    match = _TOLERANCE.search(text)
    if match is None:
        return text
    nominal = text[: match.start()].strip()
    warnings.warn(
        f"{where}: {text.strip()!r}: read the nominal {nominal!r}; its tolerance of ±{match.group(1)} % "
        "is not modelled (a unit with this spread differs by that much)",
        stacklevel=4,
    )
    return nominal


def _parse(text: str, where: str) -> tuple[pint.Quantity | None, float]:
    """Parse a quantity string: ``(quantity, magnitude)``; the quantity is None for a bare number (SI)."""
    ureg = get_registry()
    text = _DC_PREFIX.sub("", _without_tolerance(text, where))
    servo = _SERVO_SPEED.match(text)
    if servo is not None:
        seconds, degrees = float(servo.group(1)), float(servo.group(2))
        if seconds > 0.0:
            return ureg.Quantity(degrees / seconds, "deg/s"), degrees / seconds
    _refuse_comma(text, where)
    match = _NUMBER_AND_UNIT.match(_ungroup(text))
    if match is None:
        raise UnitsError(
            f"{where}: cannot read {text!r} as a number with a unit (e.g. '3000 rpm', '0.091 N*m/A')"
        )
    number, unit_text = match.group(1), match.group(2)
    # ROBOTIS prints units in brackets: "3.3 [N.m]", "31 [rev/min]"
    bracketed = re.fullmatch(r"\[\s*([^\[\]]+?)\s*\]", unit_text)
    if bracketed is not None:
        unit_text = bracketed.group(1)
    magnitude = float(number)
    if math.isinf(magnitude) and "inf" not in number.lower():
        raise UnitsError(f"{where}: {text!r} is beyond the float range (about 1.8e308)")
    if not unit_text:
        return None, magnitude
    try:
        unit = ureg.Unit(_normalize_unit_text(unit_text))
    except Exception as exc:  # pint raises several unrelated types for unknown or malformed units
        raise UnitsError(f"{where}: unknown unit {unit_text!r} in {text!r}") from exc
    return ureg.Quantity(magnitude, unit), magnitude


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


def _bare_number(value: SupportsFloat, where: str) -> float:
    try:
        result = float(value)
    except OverflowError:
        raise UnitsError(f"{where}: {value} is beyond the float range (about 1.8e308)") from None
    if math.isnan(result):
        raise UnitsError(f"{where}: expected a number, got NaN")
    return result


def to_si(value: object, expected: str, where: str) -> float:
    """Convert a user quantity to an SI float.

    Args:
        value: A bare number or a string holding only a number (both already in the SI unit
            ``expected``), a string with units as datasheets print them (``"3000 rpm"``,
            ``"91 mNm/A"``), or a ``pint.Quantity`` of the library registry.
        expected: The SI unit of the result, as pint reads it (``"rad/s"``, ``"N*m"``, ...).
        where: The file and key (or argument) the value comes from; it starts every error message.

    Returns:
        The magnitude in ``expected`` [SI].

    Raises:
        UnitsError: unknown unit, wrong dimension (the message says what was expected, in words),
            a missing angle unit on an angular quantity, a comma in the number, a number beyond the
            float range, or a value that is not a number.
    """
    ureg = get_registry()
    if isinstance(value, bool) or value is None:
        raise UnitsError(f"{where}: expected {describe_unit(expected)}, got {value!r}")
    if isinstance(value, numbers.Real):  # NumPy's scalars too (numpy.float32 is not a float)
        return _bare_number(value, where)
    if isinstance(value, str):
        parsed, magnitude = _parse(value, where)
        if parsed is None:
            return _bare_number(magnitude, where)
        quantity = parsed
    elif isinstance(value, ureg.Quantity):
        quantity = value
    else:
        raise UnitsError(f"{where}: expected {describe_unit(expected)}, got {type(value).__name__} {value!r}")
    target = ureg.Unit(expected)
    quantity = _torque_from_mass_length(quantity, target)
    if quantity.dimensionality != target.dimensionality:
        raise UnitsError(
            f"{where}: {value!r} is not {describe_unit(expected)}; its dimension is {quantity.dimensionality}"
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
    magnitude_si: Any = quantity.m_as(target)
    result = float(magnitude_si)
    if math.isnan(result):
        raise UnitsError(f"{where}: {value!r} is not a number")
    if math.isinf(result) and not math.isinf(float(quantity.magnitude)):
        raise UnitsError(f"{where}: {value!r} is beyond the float range in {expected}")
    return result


def converts_to(value: object, unit: str) -> bool:
    """Whether ``value`` is a string with units that :func:`to_si` reads as ``unit``.

    A bare number (or a string holding only one) is not: it fits every unit, so it suggests nothing.
    """
    if not isinstance(value, str):
        return False
    try:
        parsed, _ = _parse(value, "")
        if parsed is None:
            return False
        to_si(value, unit, "")
    except UnitsError:
        return False
    return True


def format_si(value: float, unit: str) -> str:
    """Format an SI float with its unit for reports: ``12.06 N*m``, ``inf rad/s``."""
    if math.isinf(value):
        return f"{'-' if value < 0 else ''}inf {unit}"
    return f"{value:.6g} {unit}"

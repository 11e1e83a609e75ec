"""Unit traps: every datasheet spelling converts to the right SI value, and the traps are closed."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from drive_envelope._src.units import format_si, get_registry, to_si
from drive_envelope.errors import InputError, UnitsError

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm, by definition of a revolution
KGF = 9.80665  # N per kgf (standard gravity, exact)
OZF_IN = 0.028349523125 * KGF * 0.0254  # N*m per ozf*in (avoirdupois ounce, exact)


@pytest.mark.parametrize(
    "spelling",
    ["3000 rpm", "3000 min^-1", "3000 min-1", "3000 1/min", "3000 r/min", "3000 rev/min", "3000 min⁻¹"],
)
def test_rpm_spellings_are_two_pi_over_sixty(spelling: str) -> None:
    """Read every revolutions-per-minute spelling as 2*pi/60 rad/s per rpm."""
    assert to_si(spelling, "rad/s", "k") == pytest.approx(3000 * RPM, rel=1e-15)


@pytest.mark.parametrize("spelling", ["50 Hz", "50 1/s", "50 s^-1"])
def test_hz_and_bare_per_second_are_refused_for_angular_speed(spelling: str) -> None:
    """Refuse Hz and 1/s where rad/s is expected: pint would silently drop the 2*pi."""
    with pytest.raises(UnitsError, match="angle"):
        to_si(spelling, "rad/s", "file.toml: key 'motor.max_speed'")


def test_pint_itself_has_the_hz_trap() -> None:
    """Show the trap being closed: plain pint turns 60 rpm into 6.28 Hz."""
    ureg = get_registry()
    assert ureg.Quantity(60, "rpm").m_as("Hz") == pytest.approx(2 * math.pi)


def test_torque_in_joules_is_refused() -> None:
    """Refuse J for a torque although N*m and J share a dimension."""
    with pytest.raises(UnitsError, match="energy"):
        to_si("2 J", "N*m", "k")
    with pytest.raises(UnitsError, match="energy"):
        to_si("2 mJ/A", "N*m/A", "k")


@pytest.mark.parametrize(
    ("spelling", "expected"),
    [
        ("2 Nm", 2.0),
        ("2 N.m", 2.0),
        ("2 N*m", 2.0),
        ("2 N·m", 2.0),
        ("2 N-m", 2.0),
        ("250 mNm", 0.25),
        ("250 Nmm", 0.25),
        ("25 Ncm", 0.25),
        ("10 kgf*cm", 10 * KGF * 0.01),
        ("10 kg*cm", 10 * KGF * 0.01),
        ("10 kg-cm", 10 * KGF * 0.01),
        ("10 kgcm", 10 * KGF * 0.01),
        ("100 oz*in", 100 * OZF_IN),
        ("100 oz-in", 100 * OZF_IN),
        ("100 ozf*in", 100 * OZF_IN),
    ],
)
def test_torque_spellings(spelling: str, expected: float) -> None:
    """Read datasheet torque spellings, a servo's kg*cm as kilogram-force centimetres."""
    assert to_si(spelling, "N*m", "k") == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("spelling", "unit", "expected"),
    [
        ("91 mNm/A", "N*m/A", 0.091),
        ("0.091 N*m/A", "N*m/A", 0.091),
        ("100 rpm/V", "rad/s/V", 100 * RPM),
        ("25 V/krpm", "V*s/rad", 25 / (1000 * RPM)),
        ("0.16 V/(r/min)", "V*s/rad", 0.16 / RPM),
        ("9 rpm/mNm", "rad/s/(N*m)", 9 * RPM / 1e-3),
        ("1 (rad/s)/(N*m)", "rad/s/(N*m)", 1.0),
        ("170 mohm", "ohm", 0.17),
        ("170 mΩ", "ohm", 0.17),
        ("1.5 Ω", "ohm", 1.5),
        ("1.5 Ohm", "ohm", 1.5),
        ("92 %", "dimensionless", 0.92),
        ("92%", "dimensionless", 0.92),
        ("68 g*cm^2", "kg*m^2", 68e-7),
        ("68 g*cm²", "kg*m^2", 68e-7),
        ("5 mm/rev", "m/turn", 0.005),
        ("20 N/A", "N/A", 20.0),
        ("0.14 s/60°", "rad/s", math.radians(60) / 0.14),
        ("0.17 sec/60 deg", "rad/s", math.radians(60) / 0.17),
    ],
)
def test_vendor_spellings(spelling: str, unit: str, expected: float) -> None:
    """Read constants, resistances, percentages, inertias, leads and servo speeds as printed."""
    assert to_si(spelling, unit, "k") == pytest.approx(expected, rel=1e-12)


def test_wrong_dimension_names_key_value_and_expected_unit() -> None:
    """Name the key, the value and the expected unit when a torque is given in rpm."""
    with pytest.raises(UnitsError) as info:
        to_si("3000 rpm", "N*m", "ak.toml: key 'motor.max_torque'")
    message = str(info.value)
    assert message.startswith("ak.toml: key 'motor.max_torque'")
    assert "'3000 rpm'" in message and "N*m" in message
    assert "\n" not in message


@pytest.mark.parametrize("value", ["3000 furlongs", "fast", "3 rpm rpm", [1, 2], None, True])
def test_unreadable_values_are_units_errors(value: object) -> None:
    """Raise a UnitsError (an InputError) for unknown units and non-numeric values."""
    with pytest.raises(InputError):
        to_si(value, "rad/s", "k")


def test_nan_is_refused() -> None:
    """Never let a NaN through."""
    with pytest.raises(UnitsError):
        to_si("nan rpm", "rad/s", "k")


@given(st.floats(min_value=-1e9, max_value=1e9, allow_nan=False))
def test_bare_numbers_are_si(value: float) -> None:
    """Pass bare numbers through unchanged: they are already in the key's SI unit."""
    assert to_si(value, "rad/s", "k") == value


@given(st.floats(min_value=1e-3, max_value=1e6, allow_nan=False))
def test_rpm_round_trip(value: float) -> None:
    """Convert rpm to rad/s by exactly 2*pi/60 for any magnitude."""
    assert to_si(f"{value!r} rpm", "rad/s", "k") == pytest.approx(value * RPM, rel=1e-12)


def test_format_si() -> None:
    """Format SI values for reports, infinity included."""
    assert format_si(12.05568, "N*m") == "12.0557 N*m"
    assert format_si(math.inf, "rad/s") == "inf rad/s"


def test_numpy_scalars_are_numbers() -> None:
    """numpy.float32 is not a Python float: a gain read from an array still converts (its own bits)."""
    import numpy as np

    assert to_si(np.float32(2.5), "N*m", "kp") == 2.5
    assert to_si(np.int64(3), "N*m", "kp") == 3.0
    with pytest.raises(UnitsError, match=r"^kp: expected a torque in N\*m .*, got bool"):
        to_si(np.bool_(True), "N*m", "kp")

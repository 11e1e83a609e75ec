"""Units as vendors print them: every accepted spelling, read from real datasheet text.

Each case quotes the text it was typed from and names the document. Expected values are written as
arithmetic from the definitions (a revolution is 2*pi rad, 1 kgf = 9.80665 N, 1 lbf = 4.4482216152605 N,
1 ozf = 1/16 lbf, 1 in = 0.0254 m), never taken from the code under test. Where no vendor text with a
spelling was found in the public documents searched, the case says so and cites issue 18's list.

Documents quoted (short names used below):

* [RS01] RobStride Dynamics, "RS01 instruction manual" (RS01User Manual260428.pdf), sections 1.2-1.4,
  https://github.com/RobStride/Product_Information (commit ba7236bc), Product Literature/RS01.
* [C21] Magmotor calculation data sheet C 21 - H - 175 FX (no. 500210265, 8/17/2022),
  https://cdn.shopify.com/s/files/1/0563/1226/6948/files/500210265revA_with_perf_curve_magmotor_servo_motor.pdf
* [POLOLU] Pololu, "Micro Metal Gearmotors" datasheet Rev 6.2, p. 4 (items 3063/3073, HPCB 6V 50:1),
  https://www.pololu.com/file/0J1487/pololu-micro-metal-gearmotors-rev-6-2.pdf, and the comparison
  table on https://www.pololu.com/product/3073.
* [FH1331] FAULHABER DC-Micromotors series 1331 ... SR data sheet (type 1331 T 006 SR),
  transcribed at https://paperzz.com/doc/7782699/3-2-mnm-dc-micromotors (decimal commas as printed).
* [FT3215] FEETECH ST-3215-C001 specifications, https://www.feetechrc.com/74v-19-kgcm-plastic-case-metal-
  tooth-magnetic-code-double-axis-ttl-series-steering-gear (as in ftservo/ftservo-wiki @9522ce19).
* [FS5103B] FEETECH FS5103B-FB product text, https://opencircuit.shop/product/feetech-standard-servo-fs5103b-fb-position
* [MG996R] TowerPro MG996R, https://towerpro.com.tw/product/mg996R/ ("11kgf·cm" at 6 V).
* [L16] Actuonix L16-R general data, https://docs.wcproducts.com/welcome/electronics/miniature-linear-servo-actuators/general-info/general-data
* [KOLL] Kollmorgen, "Motor Data Legend" (07 Nov 2013), https://www.kollmorgen.com/en-us/developer-network/motor-data-legend
* [TMOTOR] CubeMars / T-Motor AK80-9 (KV100) product page, as cited in the catalog entry.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from drive_envelope._src.units import to_si
from drive_envelope.errors import UnitsError

RPM = 2.0 * math.pi / 60.0  # rad/s per rev/min
KGF = 9.80665  # N per kilogram-force (standard gravity)
LBF = 4.4482216152605  # N per pound-force (0.45359237 kg * 9.80665 m/s^2)
OZF = LBF / 16.0  # N per ounce-force
INCH = 0.0254  # m
FOOT = 0.3048  # m


@pytest.mark.parametrize(
    ("text", "unit", "expected", "source"),
    [
        # revolutions per minute
        ("650 RPM", "rad/s", 650 * RPM, "[POLOLU] p. 4 column header 'RPM (±20%)': no-load speed 650"),
        ("2628 RPM", "rad/s", 2628 * RPM, "[C21] 'RPM nl = 2628 RPM No Load Velocity'"),
        ("315 rpm", "rad/s", 315 * RPM, "[RS01] 1.3 'No load speed: 315 rpm±10%'"),
        ("100 Rpm", "rad/s", 100 * RPM, "no vendor text found; issue 18's list ('Rpm')"),
        ("3000 1/min", "rad/s", 3000 * RPM, "[KOLL] 'nn 1/min Rated speed'"),
        # thousands separated by a space, as FAULHABER prints them
        ("12 000 rpm", "rad/s", 12000 * RPM, "[FH1331] line 27 'Speed up to ne max. ... 12 000 ... rpm'"),
        ("10 600 rpm", "rad/s", 10600 * RPM, "[FH1331] line 5 'No-load speed no 10 600 ... rpm'"),
        ("12\u2009000 rpm", "rad/s", 12000 * RPM, "[FH1331] line 27, typeset with a thin space"),
        ("1 790 rpm/V", "rad/s/V", 1790 * RPM, "[FH1331] line 9 'Speed constant kn 1 790 ... rpm/V'"),
        # direct-current volts
        ("36 VDC", "V", 36.0, "[RS01] 1.2 'Rated voltage: 36 VDC'"),
        ("6VDC", "V", 6.0, "[L16] 'Input Voltage 6VDC'"),
        ("36 Vdc", "V", 36.0, "[C21] 'V in =* 36 Vdc Input Voltage'"),
        ("560 V DC", "V", 560.0, "[KOLL] 'Un V DC Bus Link voltage' (unit column 'V DC')"),
        # resistance
        ("4.60 Ohms", "ohm", 4.60, "[C21] 'Rt =* 4.60 Ohms(@20° C) Terminal Resistance+Amplifier'"),
        ("3.07 Ohm", "ohm", 3.07, "[KOLL] 'R20 Ohm Winding resistance measured Phase- Phase'"),
        ("0.54 ohms", "ohm", 0.54, "no vendor text found; issue 18's list ('ohms')"),
        ("170 mOhm", "ohm", 0.170, "T-Motor AK80-6 'Resistance phase to phase = 170 +- 5 mOhm' (catalog)"),
        # hobby KV: rpm per volt, only as the whole unit
        ("100 KV", "rad/s/V", 100 * RPM, "[TMOTOR] 'KV100' written value-first, as issue 18 asks ('270 KV')"),
        ("270 Kv", "rad/s/V", 270 * RPM, "no vendor text found; issue 18's list ('Kv')"),
        # back-EMF constants
        ("13.70 V/krpm", "V*s/rad", 13.70 / (1000 * RPM), "[C21] 'Ke =* 13.70 V/krpm Voltage Constant'"),
        ("9.6Vrms/kRPM", "V*s/rad", 9.6 / (1000 * RPM), "[RS01] 1.3 back EMF '9.6Vrms/kRPM'"),
        ("0.096Vrms/rpm", "V*s/rad", 0.096 / RPM, "RobStride RS02 manual 1.3 back EMF '0.096Vrms/rpm'"),
        (
            "18.8 V/1000 rpm",
            "V*s/rad",
            18.8 / (1000 * RPM),
            "[KOLL] 'KE ... per 1000 rpm'; AMK-style 'V/1000 rpm'",
        ),
        ("0.56 mV/rpm", "V*s/rad", 0.56e-3 / RPM, "[FH1331] line 10 'Back-EMF constant kE 0,56 ... mV/rpm'"),
        ("0.56 mV/min^-1", "V*s/rad", 0.56e-3 / RPM, "FAULHABER's current sheets print kE in 'mV/min-1'"),
        ("0.56 mV/min-1", "V*s/rad", 0.56e-3 / RPM, "FAULHABER's current sheets print kE in 'mV/min-1'"),
        # rms / peak markers: plain amperes (the conventions are the user's to match)
        ("1.22N.m/Arms", "N*m/A", 1.22, "[RS01] 1.3 torque constant '1.22N.m/Arms'"),
        ("0.5 Arms", "A", 0.5, "[RS01] 1.3 no-load current '0.5 Arms'"),
        ("23Apk", "A", 23.0, "[RS01] 1.3 peak phase current '23Apk'"),
        (
            "105 A rms",
            "A",
            105.0,
            "no vendor text found in the documents searched; issue 18's list ('A rms')",
        ),
        # torques: kilogram-force lengths
        ("19.5kg.cm", "N*m", 19.5 * KGF * 0.01, "[FT3215] 'Peak stall torque 19.5kg.cm@6V'"),
        ("3.8 kg-cm", "N*m", 3.8 * KGF * 0.01, "[FS5103B] '53 oz-in (3.8 kg-cm)'"),
        ("7.4 kg⋅mm", "N*m", 7.4 * KGF * 0.001, "[POLOLU] p. 4 stall extrapolation '7.4 kg⋅mm'"),
        ("0.74 kg⋅cm", "N*m", 0.74 * KGF * 0.01, "[POLOLU] product 3073 comparison table '0.74 kg⋅cm'"),
        ("11kgf·cm", "N*m", 11 * KGF * 0.01, "[MG996R] stall torque '11kgf·cm' at 6 V"),
        (
            "0.6kg•cm",
            "N*m",
            0.6 * KGF * 0.01,
            "Melonbotics Super Servo docs: 'taper ... until it reaches 0.6kg•cm'",
        ),
        # torques: ounce-force and pound-force lengths
        ("145 oz-in", "N*m", 145 * OZF * INCH, "[C21] 'T gs = 145 oz-in Stall Torque'"),
        ("10 oz⋅in", "N*m", 10 * OZF * INCH, "[POLOLU] product 3073 comparison table '10 oz⋅in'"),
        ("18.5 oz-in/A", "N*m/A", 18.5 * OZF * INCH, "[C21] 'Kt = 18.5 oz-in/A Torque Constant'"),
        (
            "21.33 in-lb",
            "N*m",
            21.33 * LBF * INCH,
            "VEX CIM motor stats as quoted: '21.33 in-lb stall torque'",
        ),
        ("50 in*lbf", "N*m", 50 * LBF * INCH, "no vendor text found; issue 18's list ('in*lbf')"),
        ("50 lbf*in", "N*m", 50 * LBF * INCH, "no vendor text found; issue 18's list ('lbf*in')"),
        ("2 ft-lb", "N*m", 2 * LBF * FOOT, "no vendor datasheet found; issue 18's list ('ft-lb')"),
        ("2 ft*lbf", "N*m", 2 * LBF * FOOT, "no vendor text found; issue 18's list ('ft*lbf')"),
        ("1.7 N.m", "N*m", 1.7, "[RS01]-style 'N.m' ('Peak load: 17 N.m')"),
        # servo speed: time per 60 degrees
        ("0.238sec/60°", "rad/s", math.radians(60) / 0.238, "[FT3215] 'No load speed 0.238sec/60°@6V'"),
        ("0.16 sec/60°", "rad/s", math.radians(60) / 0.16, "[FS5103B] 'Key specs at 6 V: 0.16 sec/60°'"),
    ],
)
def test_vendor_spelling_reads_as_printed(text: str, unit: str, expected: float, source: str) -> None:
    """Read each spelling from a datasheet as exactly one SI value."""
    assert to_si(text, unit, f"test ({source})") == pytest.approx(expected, rel=1e-12)


def test_two_spellings_on_one_sheet_agree() -> None:
    """Pololu prints one stall torque as 7.4 kg⋅mm, 0.74 kg⋅cm and 10 oz⋅in: the readings agree.

    [POLOLU]: the datasheet's 7.4 kg⋅mm and the product table's 0.74 kg⋅cm are the same number; the
    table's 10 oz⋅in is the same torque rounded to two digits: 0.0726 N*m vs 0.0706 N*m (3 %).
    """
    mm = to_si("7.4 kg⋅mm", "N*m", "k")
    cm = to_si("0.74 kg⋅cm", "N*m", "k")
    oz = to_si("10 oz⋅in", "N*m", "k")
    assert mm == pytest.approx(cm, rel=1e-12)
    assert oz == pytest.approx(cm, rel=0.03)


def test_feetech_prints_one_torque_in_two_units() -> None:
    """[FS5103B] '53 oz-in (3.8 kg-cm)': 53*OZF*INCH = 0.3743 N*m, 3.8*KGF/100 = 0.3727 N*m."""
    assert to_si("53 oz-in", "N*m", "k") == pytest.approx(to_si("3.8 kg-cm", "N*m", "k"), rel=0.005)


def test_faulhaber_speed_and_back_emf_constants_are_reciprocal() -> None:
    """[FH1331] kn = 1 790 rpm/V and kE = 0,56 mV/rpm: kn * kE = 1790 * 0.56e-3 = 1.0024 (print rounding)."""
    kn = to_si("1 790 rpm/V", "rad/s/V", "k")
    ke = to_si("0.56 mV/rpm", "V*s/rad", "k")
    assert kn * ke == pytest.approx(1790 * 0.56e-3, rel=1e-12)


def test_v_per_1000_rpm_is_mv_per_rpm() -> None:
    """[KOLL] KE in 'mVmin' is 'per 1000 rpm': x V/1000 rpm == x V/krpm == x mV/rpm == x mV/min^-1."""
    values = [to_si(f"18.8 {u}", "V*s/rad", "k") for u in ("V/1000 rpm", "V/krpm", "mV/rpm", "mV/min^-1")]
    assert max(values) == pytest.approx(min(values), rel=1e-14)


@pytest.mark.parametrize(
    ("text", "unit", "fragment", "source"),
    [
        ("0,56 mV/rpm", "V*s/rad", "write '0.56 mV/rpm'", "[FH1331] line 10 kE '0,56'"),
        ("2,83 Ω", "ohm", "write '2.83 Ω'", "[FH1331] line 2 terminal resistance '2,83' Ω"),
        ("11,20 mNm", "N*m", "write '11.20 mNm'", "[FH1331] line 7 stall torque '11,20' mNm"),
        ("16,1 Nm", "N*m", "write '16.1 Nm'", "issue 18's example (became 16.0 N*m before)"),
        (
            "5,300 RPM",
            "rad/s",
            "'5300 RPM' (thousands separator) or '5.3 RPM' (decimal comma)",
            "VEX CIM '5,300 RPM'",
        ),
    ],
)
def test_a_comma_in_a_number_is_refused_with_the_fix(
    text: str, unit: str, fragment: str, source: str
) -> None:
    """Refuse decimal commas and comma thousands separators, naming the key and the way to write it."""
    with pytest.raises(UnitsError) as info:
        to_si(text, unit, f"sheet.toml: key 'motor.x' ({source})")
    message = str(info.value)
    assert message.startswith("sheet.toml: key 'motor.x'")
    assert fragment in message
    assert "\n" not in message


@pytest.mark.parametrize("text", ["1 0000 rpm", "12 00 rpm", "12  000 rpm"])
def test_a_space_separates_only_groups_of_three(text: str) -> None:
    """Read a space as a thousands separator only between groups of three digits."""
    with pytest.raises(UnitsError):
        to_si(text, "rad/s", "k")


def test_kilovolt_is_not_hobby_kv() -> None:
    """'KV' and 'Kv' alone are rpm/V; 'kV' stays the kilovolt (a voltage, refused as a speed constant)."""
    assert to_si("2 kV", "V", "k") == 2000.0
    with pytest.raises(UnitsError, match="speed constant"):
        to_si("100 kV", "rad/s/V", "k")


def test_kg_cm_squared_stays_an_inertia() -> None:
    """'kg*cm^2' is an inertia, not kilogram-force: the kgf reading applies only to a bare length."""
    assert to_si("2 kg*cm^2", "kg*m^2", "k") == pytest.approx(2e-4, rel=1e-12)


@pytest.mark.parametrize(
    ("value", "where"),
    [
        (12.5, "a number in the file"),
        ("12.5", "a quoted number"),
        ("12 500", "a quoted number with a separator"),
    ],
)
def test_a_bare_number_is_si_however_it_is_written(value: object, where: str) -> None:
    """A bare number is the key's SI unit, whether written as a number or as a string."""
    expected = 12500.0 if value == "12 500" else 12.5
    assert to_si(value, "rad/s", where) == expected
    assert to_si(value, "N*m", where) == expected


@pytest.mark.parametrize(
    ("text", "words"), [("3000 rpm", "a torque in N*m"), ("2.5 Nm", "an angular speed in rad/s")]
)
def test_wrong_dimension_names_the_expected_unit_in_words(text: str, words: str) -> None:
    """Say what the key takes, in words and with an example."""
    unit = "N*m" if "torque" in words else "rad/s"
    with pytest.raises(UnitsError, match=re.escape(words)):
        to_si(text, unit, "k")


@pytest.mark.parametrize("value", [1e400, "1e400 rpm", "1e400", 10**400, "-1e400 N*m"])
def test_numbers_beyond_the_float_range_are_refused(value: object) -> None:
    """Refuse a number that does not fit a float instead of reading it as infinity."""
    unit = "N*m" if "N*m" in str(value) else "rad/s"
    if value == 1e400:  # the literal is already inf in Python: a written infinity is accepted
        assert to_si(value, unit, "k") == math.inf
        return
    with pytest.raises(UnitsError, match="float range"):
        to_si(value, unit, "k")


def test_a_conversion_beyond_the_float_range_is_refused() -> None:
    """1e308 kN*m is a finite number whose SI value overflows: refused, not inf."""
    with pytest.raises(UnitsError, match="float range"):
        to_si("1e308 kN*m", "N*m", "k")


_DOC_UNITS = {
    "angular speed": "rad/s",
    "torque": "N*m",
    "voltage": "V",
    "current": "A",
    "resistance": "ohm",
    "torque constant": "N*m/A",
    "speed constant": "rad/s/V",
    "back-EMF constant": "V*s/rad",
    "gradient": "rad/s/(N*m)",
}
_DOC_MIXED = {"%": "dimensionless", "g*cm^2": "kg*m^2", "kg*m^2": "kg*m^2", "mm/rev": "m/turn"}


def _documented_spellings() -> list[tuple[str, str]]:
    """(text, SI unit) for every spelling in docs/datasheet.md's unit table."""
    doc = Path(__file__).resolve().parents[1] / "docs" / "datasheet.md"
    rows = [line for line in doc.read_text(encoding="utf-8").splitlines() if line.startswith("| ")]
    start = next(i for i, line in enumerate(rows) if line.startswith("| quantity | accepted spellings"))
    cases = []
    for row in rows[start + 2 :]:
        _, quantity, spellings, _ = (cell.strip() for cell in row.split("|"))
        if quantity not in _DOC_UNITS and quantity != "fractions, inertia, lead":
            break
        for token in re.findall(r"`([^`]+)`", spellings):
            unit = _DOC_UNITS.get(quantity) or _DOC_MIXED[token]
            text = token.strip('"') if token.startswith('"') else f"2 {token}"
            cases.append((text, unit))
    return cases


def test_every_documented_spelling_is_accepted() -> None:
    """The docs' unit list matches what is read: every spelling there converts to its quantity's unit."""
    cases = _documented_spellings()
    assert len(cases) > 60
    for text, unit in cases:
        value = to_si(text, unit, f"docs/datasheet.md {text!r}")
        assert math.isfinite(value) and value > 0.0, text


@pytest.mark.parametrize(
    ("text", "unit", "expected"),
    [
        ("3.3 [N.m]", "N*m", 3.3),  # ROBOTIS e-Manual
        ("31 [rev/min]", "rad/s", 31 * RPM),
        ("30 Kg.cm", "N*m", 30 * 9.80665 * 0.01),  # kilogram-force centimetres
        ("16 N-cm", "N*m", 0.16),
        ("DC24V", "V", 24.0),  # Harmonic Drive
        ("10 Amps", "A", 10.0),  # Magmotor
        ("100 rpm/Volt", "rad/s/V", 100 * RPM),
        ("0.05 Vs/rad", "V*s/rad", 0.05),
    ],
)
def test_vendor_spellings_are_read(text: str, unit: str, expected: float) -> None:
    """Issue 23 item 10: each spelling names exactly one unit, so it is read, not refused."""
    assert to_si(text, unit, "k") == pytest.approx(expected, rel=1e-12)


def test_a_tolerance_reads_the_nominal_and_says_so() -> None:
    """Issue 23 item 10: '46 RPM ±10%' is 46 rpm, and the tolerance is named in a warning."""
    with pytest.warns(
        UserWarning, match=r"k: '46 RPM ±10%': read the nominal '46 RPM'; its tolerance of ±10 %"
    ):
        assert to_si("46 RPM ±10%", "rad/s", "k") == pytest.approx(46 * RPM, rel=1e-12)

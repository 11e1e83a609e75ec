"""Datasheet slips that gave a silently wrong number (issue 23, items 7-10), each from its case.

Golden values by hand: 46 rpm = 46 * 2*pi/60 = 4.817108 rad/s; the XM430-W350's line from
(0 rpm, 4.1 N*m) to (46 rpm, 0 N*m) has Delta v / Delta tau = 4.817108 / 4.1 = 1.174904 (rad/s)/(N*m).
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.load import datasheet_from_mapping

RPM = 2.0 * math.pi / 60.0


def _derive(data: dict[str, Any]) -> Any:
    return derive(datasheet_from_mapping(data, source="sheet.toml"))


def test_operating_points_that_are_the_speed_torque_line_give_its_gradient() -> None:
    """Item 7: the contract case, XM430-W350 at 12 V. Either slope may carry the line, not neither."""
    result = _derive(
        {
            "name": "XM430-W350",
            "joint": "revolute",
            "controller": {"max_voltage": "12 V"},
            "output": {"max_effort": "4.1 N*m", "max_velocity": "46 rpm"},
            "losses": {"operating_points": [["0 rpm", "4.1 N*m"], ["46 rpm", "0 N*m"]]},
        }
    )
    env = result.envelope
    assert env.max_effort == 4.1
    assert env.max_actuator_velocity == pytest.approx(46 * RPM, rel=1e-12)
    assert env.velocity_dependent_resistance == 0.0
    assert env.speed_effort_gradient == pytest.approx(46 * RPM / 4.1, rel=1e-12)
    assert result.speed_effort_gradient_method == "operating_points"


def test_a_printed_gradient_still_wins_over_the_points() -> None:
    """The points' line is a fallback: a printed speed_effort_gradient is used as printed."""
    result = _derive(
        {
            "name": "x",
            "joint": "revolute",
            "output": {"max_effort": "4.1 N*m", "max_velocity": "46 rpm", "speed_effort_gradient": 0.5},
            "losses": {"operating_points": [["0 rpm", "4.1 N*m"], ["46 rpm", "0 N*m"]]},
        }
    )
    assert result.envelope.speed_effort_gradient == 0.5


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
    """Item 10: each spelling names exactly one unit, so it is read, not refused."""
    from drive_envelope._src.units import to_si

    assert to_si(text, unit, "k") == pytest.approx(expected, rel=1e-12)


def test_a_tolerance_reads_the_nominal_and_says_so() -> None:
    """Item 10: '46 RPM ±10%' is 46 rpm, and the tolerance is named in a warning."""
    from drive_envelope._src.units import to_si

    with pytest.warns(
        UserWarning, match=r"k: '46 RPM ±10%': read the nominal '46 RPM'; its tolerance of ±10 %"
    ):
        assert to_si("46 RPM ±10%", "rad/s", "k") == pytest.approx(46 * RPM, rel=1e-12)


def _warnings(motor: dict[str, Any], controller: dict[str, Any]) -> tuple[str, ...]:
    data = {"name": "m", "joint": "revolute", "motor": motor, "controller": controller}
    return tuple(_derive(data).warnings)


def test_a_torque_constant_per_arms_with_a_peak_current_is_a_warning() -> None:
    """Item 8: RobStride's own table, 1.22 N.m/Arms and 23Apk; one convention each, no warning."""
    (line,) = _warnings({"torque_constant": "1.22 N.m/Arms"}, {"max_current": "23Apk", "max_voltage": "48 V"})
    assert "torque_constant is per A rms but controller.max_current is marked peak" in line
    assert "too high by sqrt(2)" in line
    assert (
        _warnings({"torque_constant": "1.22 N.m/Arms"}, {"max_current": "16 Arms", "max_voltage": "48 V"})
        == ()
    )
    assert (
        _warnings({"torque_constant": "1.22 N*m/A"}, {"max_current": "23 Apk", "max_voltage": "48 V"}) == ()
    )


@pytest.mark.parametrize(
    ("key", "value", "bound"),
    [
        ("terminal_resistance", "1000 MΩ", "1e+09 ohm"),  # typed for mΩ
        ("torque_constant", "91 N*m/A", None),  # plausible (a large motor): no warning
        ("torque_constant", "910 N*m/A", "910 N*m/A"),  # mNm/A typed as N*m/A
    ],
)
def test_motor_constants_beyond_any_motor_are_a_warning(key: str, value: str, bound: str | None) -> None:
    """Item 9: a 1e9 ohm winding makes the gradient 1e9x; it is named, with the bounds."""
    found = [w for w in _warnings({key: value, "torque_constant": "0.1 N*m/A"} if key != "torque_constant"
                                  else {key: value}, {"max_current": "10 A", "max_voltage": "24 V"})
             if "is outside what motors have" in w]  # fmt: skip
    if bound is None:
        assert found == []
    else:
        (line,) = found
        assert f"motor.{key} = {bound} is outside what motors have" in line


@pytest.mark.parametrize(
    ("no_load_speed", "expected"),
    [
        ("5240 rpm", None),  # 229 rpm/V * 24 V = 5496 rpm: the printed end of the line, 0.95x
        ("5240 rad/s", "9.1x"),  # the same number read as rad/s moves the speed line 9.55x
        ("1310 rpm", None),  # printed at a quarter of the voltage (4x): still no warning
    ],
)
def test_a_no_load_speed_against_kv_times_voltage_is_a_warning(
    no_load_speed: str, expected: str | None
) -> None:
    """Item 9, the speed line: the printed n_0 against k_v * V (a slip of rpm for rad/s is named)."""
    found = [
        w
        for w in _warnings(
            {"speed_constant": "229 rpm/V", "no_load_speed": no_load_speed, "torque_constant": "41.7 mN*m/A"},
            {"max_current": "10 A", "max_voltage": "24 V"},
        )
        if "motor.no_load_speed" in w
    ]
    if expected is None:
        assert found == []
    else:
        (line,) = found
        assert f"speed_constant * controller.max_voltage = 575.54 rad/s ({expected})" in line
        assert "'rpm' vs 'rad/s'" in line


def test_a_motor_speed_beyond_any_motor_is_a_warning() -> None:
    """Item 9: 50,000 rad/s (477,000 rpm) is no motor's speed; the bounds are named."""
    found = [
        w
        for w in _warnings(
            {"max_speed": "50000 rad/s", "torque_constant": "0.1 N*m/A"},
            {"max_current": "10 A", "max_voltage": "24 V"},
        )
        if "is outside what motors have" in w
    ]
    (line,) = found
    assert "motor.max_speed = 50000 rad/s is outside what motors have (0.1 rad/s to 12000 rad/s)" in line
    assert "check its unit ('rpm' vs 'rad/s'" in line

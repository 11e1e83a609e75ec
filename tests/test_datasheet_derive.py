"""Worked examples of the datasheet-to-sim derivation, one per branch, computed by hand.

The base drive is the spec's reduced AK80-6 example: k_t = 0.091 N*m/A, k_v = 100 rpm/V,
R = 170 mohm, i_G = 6, eta_G = 0.92, I_C,max = 24 A, V_max = 24 V, mu_C = 0.9 (default):

    controller_current = 24 * 0.091 * 6 * 0.92                    = 12.05568 N*m
    voltage            = 100 rpm/V * 24 V * 0.9 / 6 = 360 rpm     = 12*pi rad/s
    gradient           = 0.17 / 0.091**2 / 6**2                   = 0.5702478... (rad/s)/(N*m)
"""

from __future__ import annotations

import copy
import math
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from _datasheets import sheet_from
from drive_envelope._src.datasheet.catalog import load_catalog_datasheet
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.limits import EFFORT_LIMITS, VELOCITY_LIMITS
from drive_envelope._src.datasheet.load import datasheet_from_mapping
from drive_envelope.errors import InputError

RPM = 2.0 * math.pi / 60.0

BASE: dict[str, Any] = {
    "name": "T-Motor AK80-6",
    "motor": {
        "torque_constant": "0.091 N*m/A",
        "speed_constant": "100 rpm/V",
        "terminal_resistance": "170 mohm",
    },
    "gear": {"ratio": 6.0, "efficiency": 0.92},
    "controller": {"max_current": "24 A", "max_voltage": "24 V"},
}
BASE_EFFORT = 24 * 0.091 * 6 * 0.92
BASE_VELOCITY = 12 * math.pi
BASE_GRADIENT = 0.17 / 0.091**2 / 36


def sheet(**sections: Any) -> Any:
    """BASE with some sections updated (a key set to None is removed)."""
    return sheet_from(BASE, "test.toml", **sections)


def test_spec_example_json() -> None:
    """Reproduce the issue's JSON example exactly (keys, names, values)."""
    d = derive(sheet()).to_dict()
    assert d["name"] == "T-Motor AK80-6" and d["joint"] == "revolute"
    assert d["max_effort"] == pytest.approx(12.05568, rel=1e-15)
    assert d["max_actuator_velocity"] == pytest.approx(37.69911184307751, rel=1e-15)
    assert d["velocity_dependent_resistance"] == 0.0
    assert d["speed_effort_gradient"] == pytest.approx(0.5702478229950758, rel=1e-14)
    assert d["max_effort_limited_by"] == "controller_current"
    assert d["max_effort_limits"] == {
        "controller_current": pytest.approx(12.05568),
        "motor_torque": None,
        "gear_torque": None,
        "output_rating": None,
        "output_stall": None,
    }
    assert d["max_actuator_velocity_limited_by"] == "voltage"
    assert list(d["max_actuator_velocity_limits"]) == list(VELOCITY_LIMITS)
    assert d["max_actuator_velocity_limits"]["motor_speed"] is None
    assert d["speed_effort_gradient_method"] == "resistance"
    assert isinstance(d["notes"], list)
    required = {
        "name", "joint", "max_effort", "max_actuator_velocity", "velocity_dependent_resistance",
        "speed_effort_gradient", "max_effort_limited_by", "max_effort_limits",
        "max_actuator_velocity_limited_by", "max_actuator_velocity_limits", "speed_effort_gradient_method",
        "notes",
    }  # fmt: skip
    assert required <= set(d)


# -- maxEffort: each limit binding ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("sections", "binding", "expected"),
    [
        ({}, "controller_current", BASE_EFFORT),
        ({"motor": {"max_torque": "1.5 N*m"}}, "motor_torque", 1.5 * 6 * 0.92),
        ({"gear": {"max_torque": "10 N*m"}}, "gear_torque", 10.0),
        ({"output": {"max_effort": "5 N*m"}}, "output_rating", 5.0),
    ],
)
def test_each_effort_limit_binds(sections: dict[str, Any], binding: str, expected: float) -> None:
    """Pick the smallest effort candidate and name it."""
    d = derive(sheet(**sections))
    assert d.max_effort_limited_by == binding
    assert d.envelope.max_effort == pytest.approx(expected, rel=1e-14)


def test_effort_tie_names_the_first_candidate() -> None:
    """Name controller_current on an exact tie with motor_torque (no tolerance)."""
    d = derive(
        sheet(
            motor={"torque_constant": 0.5, "max_torque": 5.0},
            gear={"ratio": 2.0, "efficiency": 1.0},
            controller={"max_current": 10.0},
        )
    )
    limits = {c.name: c.value for c in d.max_effort_limits}
    assert limits["controller_current"] == limits["motor_torque"] == 10.0
    assert d.max_effort_limited_by == "controller_current"


def test_continuous_duty_uses_continuous_torque() -> None:
    """Use motor.continuous_torque with duty continuous and max_torque with peak."""
    data = sheet(motor={"max_torque": "2.5 N*m", "continuous_torque": "0.5 N*m"})
    assert derive(data).max_effort_limited_by == "controller_current"
    cont = derive(data, duty="continuous")
    assert cont.max_effort_limited_by == "motor_torque"
    assert cont.envelope.max_effort == pytest.approx(0.5 * 6 * 0.92)


def test_missing_duty_rating_is_null_with_a_note() -> None:
    """Report motor_torque as null, with a note, when the duty's rating is absent."""
    d = derive(sheet(motor={"continuous_torque": "0.5 N*m"}))
    assert d.to_dict()["max_effort_limits"]["motor_torque"] is None
    assert any("--duty continuous" in note for note in d.notes)


# -- maxActuatorVelocity: each limit binding -----------------------------------------------------


@pytest.mark.parametrize(
    ("sections", "binding", "expected", "method"),
    [
        ({}, "voltage", BASE_VELOCITY, "resistance"),
        ({"motor": {"max_speed": "300 rpm"}}, "motor_speed", 50 * RPM, "mechanical"),
        ({"gear": {"max_input_speed": "600 rpm"}}, "gear_input_speed", 100 * RPM, "mechanical"),
        ({"output": {"max_velocity": "3 rad/s"}}, "output_rating", 3.0, "output_rating"),
    ],
)
def test_each_velocity_limit_binds(
    sections: dict[str, Any], binding: str, expected: float, method: str
) -> None:
    """Pick the smallest velocity candidate and the gradient method that goes with it."""
    d = derive(sheet(**sections))
    assert d.max_actuator_velocity_limited_by == binding
    assert d.envelope.max_actuator_velocity == pytest.approx(expected, rel=1e-14)
    assert d.speed_effort_gradient_method == method


def test_mechanical_limit_gives_zero_gradient() -> None:
    """Set the gradient to 0 when a mechanical limit binds, whatever the motor gradient."""
    d = derive(sheet(motor={"max_speed": "300 rpm", "speed_torque_gradient": "9 rpm/mNm"}))
    assert d.envelope.speed_effort_gradient == 0.0
    assert d.speed_effort_gradient_method == "mechanical"


def test_voltage_mechanical_tie_counts_as_voltage_limited() -> None:
    """Treat an exact tie between voltage and motor speed as voltage-limited."""
    d = derive(
        sheet(
            motor={
                "speed_constant": 2.0,
                "torque_constant": 0.5,
                "terminal_resistance": 1.0,
                "max_speed": 10.0,
            },
            gear={"ratio": 2.0, "efficiency": 1.0},
            controller={"max_voltage": 10.0, "modulation": 0.5},
        )
    )
    limits = {c.name: c.value for c in d.max_actuator_velocity_limits}
    assert limits["voltage"] == limits["motor_speed"] == 5.0
    assert d.max_actuator_velocity_limited_by == "voltage"
    assert d.speed_effort_gradient_method == "resistance"
    assert d.envelope.speed_effort_gradient == pytest.approx(1.0 / 0.25 / 4.0)


def test_output_rating_gradient_from_velocity_at_max_effort() -> None:
    """Use the output rating's gradient (v_max - v_at_max_effort) / max_effort when it binds."""
    d = derive(
        sheet(output={"max_effort": "4 N*m", "max_velocity": "3 rad/s", "velocity_at_max_effort": "1 rad/s"})
    )
    assert d.max_actuator_velocity_limited_by == "output_rating"
    assert d.envelope.speed_effort_gradient == pytest.approx((3 - 1) / 4)
    assert d.speed_effort_gradient_method == "output_rating"


# -- speedEffortGradient methods -----------------------------------------------------------------

DATASHEET_GRADIENT = 9 * RPM / 1e-3 / 36  # 9 rpm/mNm at the motor, / i_G**2
NOMINAL_GRADIENT = (400 * RPM / 0.5) / 36  # (2400 - 2000) rpm / 0.5 N*m, / i_G**2
FULL_MOTOR = {
    "speed_torque_gradient": "9 rpm/mNm",
    "no_load_speed": "2400 rpm",
    "nominal_speed": "2000 rpm",
    "nominal_torque": "0.5 N*m",
}


@pytest.mark.parametrize(
    ("method", "expected"),
    [
        ("auto", DATASHEET_GRADIENT),
        ("datasheet", DATASHEET_GRADIENT),
        ("resistance", BASE_GRADIENT),
        ("nominal", NOMINAL_GRADIENT),
    ],
)
def test_gradient_methods(method: str, expected: float) -> None:
    """Form the motor gradient by the chosen method and divide by i_G squared."""
    d = derive(sheet(motor={**FULL_MOTOR, "gradient_method": method}))
    assert d.envelope.speed_effort_gradient == pytest.approx(expected, rel=1e-13)
    assert d.speed_effort_gradient_method == ("datasheet" if method == "auto" else method)


def test_gradient_method_argument_overrides_the_file() -> None:
    """Let derive(gradient_method=...) override the file's choice and record it as user input."""
    d = derive(sheet(motor={**FULL_MOTOR, "gradient_method": "datasheet"}), gradient_method="nominal")
    assert d.speed_effort_gradient_method == "nominal"
    assert d.provenance["motor.gradient_method"] == "user"


def test_auto_falls_back_to_nominal() -> None:
    """Take the nominal point when neither a printed gradient nor a resistance exists."""
    d = derive(sheet(motor={"terminal_resistance": None, **FULL_MOTOR, "speed_torque_gradient": None}))
    assert d.speed_effort_gradient_method == "nominal"
    assert d.envelope.speed_effort_gradient == pytest.approx(NOMINAL_GRADIENT)


def test_auto_without_inputs_is_unavailable() -> None:
    """Report 0, method unavailable, with a note, when auto finds no gradient inputs."""
    d = derive(sheet(motor={"terminal_resistance": None}))
    assert d.envelope.speed_effort_gradient == 0.0
    assert d.speed_effort_gradient_method == "unavailable"
    assert any("speed_effort_gradient = 0" in note for note in d.notes)


def test_auto_falls_back_to_output_gradient() -> None:
    """Use the output rating's gradient when the voltage limit binds and no motor gradient exists."""
    d = derive(
        sheet(motor={"terminal_resistance": None}, output={"speed_effort_gradient": "0.25 (rad/s)/(N*m)"})
    )
    assert d.max_actuator_velocity_limited_by == "voltage"
    assert d.speed_effort_gradient_method == "output_rating"
    assert d.envelope.speed_effort_gradient == 0.25


def test_explicit_method_with_missing_inputs_is_an_error_when_the_voltage_limit_binds() -> None:
    """Refuse an explicit method whose inputs are missing when its gradient is needed (voltage binds)."""
    with pytest.raises(InputError, match=r"test.toml: gradient method 'nominal'.*motor.no_load_speed"):
        derive(sheet(motor={"gradient_method": "nominal"}))


def test_explicit_method_not_needed_when_a_mechanical_limit_binds() -> None:
    """Say in a note that the method was not needed when the motor's gradient is not used (issue 18)."""
    d = derive(sheet(motor={"max_speed": "300 rpm"}), gradient_method="nominal")
    assert d.max_actuator_velocity_limited_by == "motor_speed"
    assert d.envelope.speed_effort_gradient == 0.0
    assert any("gradient method 'nominal' not needed" in note for note in d.notes)


def test_efficiency_does_not_enter_the_gradient() -> None:
    """Keep the gradient independent of the gear efficiency (the spec's rule)."""
    a = derive(sheet(gear={"efficiency": 0.5})).envelope.speed_effort_gradient
    b = derive(sheet(gear={"efficiency": 1.0})).envelope.speed_effort_gradient
    assert a == b == pytest.approx(BASE_GRADIENT)


# -- k_t <-> k_v, defaults ------------------------------------------------------------------------


def test_kt_from_kv_is_the_si_reciprocal() -> None:
    """Derive k_t = 1/k_v (SI) when only k_v is given, with a note and provenance."""
    d = derive(sheet(motor={"torque_constant": None}))
    kv = 100 * RPM
    assert d.envelope.max_effort == pytest.approx(24 * (1 / kv) * 6 * 0.92)
    assert d.provenance["motor.torque_constant"] == "derived"
    assert any("k_t = 1/k_v" in note for note in d.notes)


def test_kv_from_back_emf_constant() -> None:
    """Use k_v = 1/k_e when the back-EMF constant is given instead of k_v."""
    d = derive(sheet(motor={"speed_constant": None, "back_emf_constant": "10 V/krpm"}))
    kv = 1 / (10 / (1000 * RPM))
    assert d.envelope.max_actuator_velocity == pytest.approx(kv * 24 * 0.9 / 6)


def test_defaults_are_noted() -> None:
    """Note the gear efficiency and modulation defaults and mark them as defaults."""
    d = derive(sheet(gear={"efficiency": None}))
    assert d.envelope.max_effort == pytest.approx(24 * 0.091 * 6)
    assert d.provenance["gear.efficiency"] == "default"
    assert d.provenance["controller.modulation"] == "default"
    assert any("eta_G = 1.0" in note for note in d.notes)


def test_no_gear_is_direct_drive() -> None:
    """Treat an absent [gear] as ratio 1, efficiency 1."""
    data = copy.deepcopy(BASE)
    del data["gear"]
    d = derive(datasheet_from_mapping(data, source="t"))
    assert d.envelope.max_effort == pytest.approx(24 * 0.091)
    assert d.envelope.max_actuator_velocity == pytest.approx(100 * RPM * 24 * 0.9)


# -- missing data ---------------------------------------------------------------------------------


def test_missing_candidates_are_null_and_listed() -> None:
    """Report a candidate whose inputs are absent as null, naming the missing keys."""
    d = derive(sheet())
    gear = next(c for c in d.max_effort_limits if c.name == "gear_torque")
    assert gear.value is None and gear.missing == ("gear.max_torque",)


def test_no_effort_candidate_is_an_error_naming_inputs() -> None:
    """Refuse a datasheet with no maxEffort candidate, naming the inputs that would give one."""
    with pytest.raises(
        InputError, match=r"no candidate limit for max_effort: give \[controller\] max_current"
    ):
        derive(sheet(controller={"max_current": None}))


def test_no_velocity_candidate_is_an_error() -> None:
    """Refuse a datasheet with no maxActuatorVelocity candidate."""
    with pytest.raises(InputError, match="no candidate limit for max_actuator_velocity"):
        derive(sheet(controller={"max_voltage": None}))


# -- velocityDependentResistance --------------------------------------------------------------------


def test_fitted_resistance_from_two_operating_points() -> None:
    """Fit k_m from operating points and reflect it by i_G**2 * eta_G."""
    points = [["1000 rpm", "0.20 N*m"], ["3000 rpm", "0.17 N*m"]]
    d = derive(sheet(losses={"operating_points": points}))
    k_m = 0.03 / (2000 * RPM)
    assert d.envelope.velocity_dependent_resistance == pytest.approx(k_m * 36 * 0.92, rel=1e-12)
    assert d.velocity_dependent_resistance_method == "fitted"


def test_fitted_resistance_least_squares_with_a_stall_point() -> None:
    """Fit three points (one at stall) by ordinary least squares: slope -7.5e-4 by hand."""
    points = [[0, 1.0], [100, 0.9], [200, 0.85]]
    d = derive(sheet(gear={"ratio": 1.0, "efficiency": 1.0}, losses={"operating_points": points}))
    assert d.envelope.velocity_dependent_resistance == pytest.approx(7.5e-4, rel=1e-12)


def test_rising_points_give_zero_with_a_note() -> None:
    """Clamp a negative fitted k_m to 0 and say so."""
    d = derive(sheet(losses={"operating_points": [[100, 0.1], [200, 0.2]]}))
    assert d.envelope.velocity_dependent_resistance == 0.0
    assert any("rise with speed" in note for note in d.notes)


@pytest.mark.parametrize("points", [[[100, 0.1]], [[100, 0.1], [100, 0.2]], []])
def test_fewer_than_two_distinct_speeds_is_an_error(points: list[Any]) -> None:
    """Refuse operating points with fewer than 2 distinct speeds."""
    with pytest.raises(InputError, match=r"losses\.operating_points.*2 points with distinct speeds"):
        derive(sheet(losses={"operating_points": points}))


def test_direct_resistance_wins_over_points() -> None:
    """Use the direct value and note that the operating points were ignored."""
    d = derive(
        sheet(
            losses={"velocity_dependent_resistance": "0.01 N*m*s/rad", "operating_points": [[1, 1], [2, 0]]}
        )
    )
    assert d.envelope.velocity_dependent_resistance == 0.01
    assert d.velocity_dependent_resistance_method == "direct"
    assert any("ignored" in note for note in d.notes)


def test_output_resistance_is_not_scaled() -> None:
    """Take a direct k_tau_v from [output] as it is, at the joint."""
    d = derive(sheet(output={"velocity_dependent_resistance": 0.02}))
    assert d.envelope.velocity_dependent_resistance == 0.02


# -- prismatic joints --------------------------------------------------------------------------------

LEAD = 0.005
T = 2 * math.pi / LEAD  # rad/m


def screw_sheet(**extra: dict[str, Any]) -> Any:
    data: dict[str, Any] = {
        "name": "ball-screw axis",
        "joint": "prismatic",
        "motor": {"torque_constant": "0.05 N*m/A", "terminal_resistance": "1 ohm"},
        "gear": {"ratio": 4, "efficiency": 0.9, "max_torque": "2 N*m"},
        "controller": {"max_current": "10 A", "max_voltage": "24 V"},
        "screw": {"lead": "5 mm/rev", "efficiency": 0.8},
    }
    for section, values in extra.items():
        data.setdefault(section, {}).update(values)
    return datasheet_from_mapping(data, source="screw.toml")


def test_prismatic_with_screw() -> None:
    """Convert through a screw: effort x T*eta_S, speed / T, gradient / T**2."""
    d = derive(screw_sheet())
    limits = {c.name: c.value for c in d.max_effort_limits}
    assert limits["controller_current"] == pytest.approx(10 * 0.05 * 4 * 0.9 * T * 0.8, rel=1e-13)
    assert limits["gear_torque"] == pytest.approx(2 * T * 0.8, rel=1e-13)
    assert d.max_effort_limited_by == "controller_current"  # 1809.56 N < 2010.62 N
    kv = 1 / 0.05  # SI reciprocal of k_t
    assert d.envelope.max_actuator_velocity == pytest.approx(kv * 24 * 0.9 / 4 / T, rel=1e-13)
    assert d.envelope.speed_effort_gradient == pytest.approx((1 / 0.05**2) / 16 / T**2, rel=1e-13)
    assert d.envelope.joint == "prismatic"


def test_prismatic_fitted_resistance_through_screw() -> None:
    """Reflect a fitted k_m by i_G**2*eta_G and the screw's T**2*eta_S."""
    d = derive(screw_sheet(losses={"operating_points": [[100, 0.3], [200, 0.2]]}))
    assert d.envelope.velocity_dependent_resistance == pytest.approx(0.001 * 16 * 0.9 * T**2 * 0.8, rel=1e-12)


def test_prismatic_output_values_are_not_converted() -> None:
    """Keep [output] values of a prismatic joint as they are (N, m/s)."""
    d = derive(screw_sheet(output={"max_effort": "100 N", "max_velocity": "20 mm/s"}))
    assert d.envelope.max_effort == 100.0
    assert d.envelope.max_actuator_velocity == pytest.approx(0.02)


def test_linear_motor_without_screw() -> None:
    """Read motor data of a prismatic joint without a screw as linear (N/A, N, m/s)."""
    data = {
        "name": "linear motor",
        "joint": "prismatic",
        "motor": {"torque_constant": "20 N/A", "max_speed": "3 m/s"},
        "controller": {"max_current": "5 A", "max_voltage": "48 V"},
    }
    d = derive(datasheet_from_mapping(data, source="lin.toml"))
    assert d.envelope.max_effort == pytest.approx(100.0)
    assert d.envelope.max_actuator_velocity == pytest.approx(1 / 20 * 48 * 0.9)
    assert d.max_actuator_velocity_limited_by == "voltage"


# -- the optional line approximation -------------------------------------------------------------------


def test_line_fit_is_reported_only_on_request_and_keeps_the_envelope() -> None:
    """Report the best single line for a mechanical-limited drive without changing the gradient."""
    data = sheet(motor={"max_speed": "2100 rpm"})  # 350 rpm < 360 rpm voltage
    plain = derive(data)
    fitted = derive(data, approximate_line=True)
    assert plain.line_fit is None
    assert fitted.envelope == plain.envelope and fitted.envelope.speed_effort_gradient == 0.0
    fit = fitted.line_fit
    assert fit is not None
    assert 0.0 < fit.speed_effort_gradient < BASE_GRADIENT
    assert fit.max_error > 0.0 and fit.rms_error <= fit.max_error


# -- properties ----------------------------------------------------------------------------------------

positive = st.floats(min_value=0.01, max_value=100.0, allow_nan=False)


@given(current=positive, kt=positive, ratio=positive, eff=st.floats(0.1, 1.0), tau_m=positive, tau_g=positive)
def test_max_effort_is_the_first_smallest_candidate(
    current: float, kt: float, ratio: float, eff: float, tau_m: float, tau_g: float
) -> None:
    """Equal the smallest candidate, named by the first one in the spec's order."""
    data = {
        "name": "p",
        "motor": {"torque_constant": kt, "max_torque": tau_m, "max_speed": 100.0},
        "gear": {"ratio": ratio, "efficiency": eff, "max_torque": tau_g},
        "controller": {"max_current": current},
    }
    d = derive(datasheet_from_mapping(data, source="p"))
    values = [c.value for c in d.max_effort_limits]
    present = [v for v in values if v is not None]
    assert d.envelope.max_effort == min(present)
    assert d.max_effort_limited_by == EFFORT_LIMITS[values.index(min(present))]


@given(ratio=st.floats(min_value=0.5, max_value=200.0))
def test_ratio_scaling(ratio: float) -> None:
    """Scale voltage speed by 1/i_G and the gradient by 1/i_G**2."""
    d = derive(sheet(gear={"ratio": ratio}))
    assert d.envelope.max_actuator_velocity == pytest.approx(100 * RPM * 24 * 0.9 / ratio, rel=1e-12)
    assert d.envelope.speed_effort_gradient == pytest.approx(0.17 / 0.091**2 / ratio**2, rel=1e-12)


def _derive(data: dict[str, Any]) -> Any:
    """Derive a datasheet written as a mapping, as from ``sheet.toml``."""
    return derive(datasheet_from_mapping(data, source="sheet.toml"))


def test_operating_points_that_are_the_speed_torque_line_give_its_gradient() -> None:
    """Issue 23 item 7: the contract case, XM430-W350 at 12 V. Either slope may carry the line.

    By hand: 46 rpm = 46 * 2*pi/60 = 4.817108 rad/s; the line from (0 rpm, 4.1 N*m) to (46 rpm, 0 N*m)
    has Delta v / Delta tau = 4.817108 / 4.1 = 1.174904 (rad/s)/(N*m).
    """
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
    """Issue 23 item 7: the points' line is a fallback: a printed speed_effort_gradient is used as printed."""
    result = _derive(
        {
            "name": "x",
            "joint": "revolute",
            "output": {"max_effort": "4.1 N*m", "max_velocity": "46 rpm", "speed_effort_gradient": 0.5},
            "losses": {"operating_points": [["0 rpm", "4.1 N*m"], ["46 rpm", "0 N*m"]]},
        }
    )
    assert result.envelope.speed_effort_gradient == 0.5


def _warnings(motor: dict[str, Any], controller: dict[str, Any]) -> tuple[str, ...]:
    data = {"name": "m", "joint": "revolute", "motor": motor, "controller": controller}
    return tuple(_derive(data).warnings)


def test_a_torque_constant_per_arms_with_a_peak_current_is_a_warning() -> None:
    """Issue 23 item 8: RobStride's own table, 1.22 N.m/Arms and 23Apk; one convention each, no warning."""
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
    """Issue 23 item 9: a 1e9 ohm winding makes the gradient 1e9x; it is named, with the bounds."""
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
    """Issue 23 item 9, the speed line: the printed n_0 against k_v * V (a slip of rpm for rad/s is named)."""
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
    """Issue 23 item 9: 50,000 rad/s (477,000 rpm) is no motor's speed; the bounds are named."""
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


def _hand_typed_sheet(**motor: object) -> dict[str, object]:
    return {
        "name": "hand-typed",
        "motor": dict(motor),
        "gear": {"ratio": "10:1", "efficiency": "90 %"},
        "controller": {"max_current": "24 A", "max_voltage": "48 V"},
    }


def test_a_torque_constant_typed_without_its_unit_draws_a_warning() -> None:
    # 91 read as SI N*m/A with 100 rpm/V (10.47 (rad/s)/V): k_t * k_v = 952.9 where an ideal motor has 1
    motor = {"torque_constant": 91, "speed_constant": "100 rpm/V"}
    sheet = datasheet_from_mapping(_hand_typed_sheet(**motor), source="s.toml")
    (warning,) = derive(sheet).warnings
    assert warning.startswith("s.toml: motor.torque_constant * motor.speed_constant = 952.9 in SI units")


def test_constants_that_agree_draw_no_warning() -> None:
    # 91 mNm/A and 105 rpm/V: 0.091 * 10.9956 = 1.0006
    motor = {"torque_constant": "91 mNm/A", "speed_constant": "105 rpm/V"}
    sheet = datasheet_from_mapping(_hand_typed_sheet(**motor), source="s")
    assert derive(sheet).warnings == ()


def test_a_printed_gradient_that_disagrees_with_resistance_draws_a_warning() -> None:
    # R/k_t^2 = 0.571 / 0.0369^2 = 419.36 (rad/s)/(N*m); 15.8 rpm/mNm = 1654.57: 3.95x
    motor = {
        "torque_constant": "36.9 mNm/A",
        "speed_constant": "259 rpm/V",
        "terminal_resistance": "0.571 ohm",
        "speed_torque_gradient": "15.8 rpm/mNm",
    }
    warnings = derive(datasheet_from_mapping(_hand_typed_sheet(**motor), source="m.toml")).warnings
    assert len(warnings) == 1 and "(3.95x): check their units" in warnings[0]
    motor["speed_torque_gradient"] = "4 rpm/mNm"  # 418.88 (rad/s)/(N*m): agrees
    assert derive(datasheet_from_mapping(_hand_typed_sheet(**motor), source="m.toml")).warnings == ()


def test_a_rotary_motor_on_a_prismatic_joint_asks_for_a_screw() -> None:
    data = {"name": "x", "joint": "prismatic", "motor": {"max_torque": "1 N*m", "max_speed": "3000 rpm"}}
    with pytest.raises(InputError, match=r"a rotary motor on a prismatic joint needs \[screw\] lead"):
        datasheet_from_mapping(data, source="d.toml")


def test_derive_notes_a_speed_line_below_max_effort() -> None:
    """CubeMars AK70-10: max_actuator_velocity / speed_effort_gradient = 23.4 N*m < max_effort 24.8."""
    result = derive(load_catalog_datasheet("cubemars-ak70-10"))
    env = result.envelope
    stall = env.max_actuator_velocity / env.speed_effort_gradient
    assert stall < env.max_effort == pytest.approx(24.8)
    (note,) = [n for n in result.notes if n.startswith("the speed line reaches zero speed")]
    assert f"{stall:.6g} N*m" in note and "no operating point reaches max_effort" in note


def test_derive_notes_a_default_modulation_below_a_printed_speed() -> None:
    """AK80-6: 100 rpm/V * 24 V * 0.9 / 6 = 37.699 rad/s, below the printed 38.2 rad/s output rating."""
    result = derive(load_catalog_datasheet("tmotor-ak80-6"))
    assert result.envelope.max_actuator_velocity == pytest.approx(
        100 * 2 * 3.141592653589793 / 60 * 24 * 0.9 / 6
    )
    assert any("below the printed output_rating 38.2 rad/s" in note for note in result.notes)


@pytest.mark.parametrize("bad", ["tmotor-ak80-6", {"name": "x", "motor": {"max_torque": "2 N*m"}}, None])
def test_derive_names_a_datasheet_argument_that_is_not_one(bad: object) -> None:
    """A catalog name, a plain dict or None: one line pointing to the loaders.

    ``derive("tmotor-ak80-6")`` was ``AttributeError: 'str' object has no attribute 'linear_motor'``.
    """
    with pytest.raises(
        InputError,
        match=r"^derive: argument 'datasheet': expected a Datasheet \(load_datasheet\(path\), "
        r"load_catalog_datasheet\(name\)\)",
    ) as info:
        derive(bad)  # type: ignore[arg-type]
    assert "\n" not in str(info.value) and type(bad).__name__ in str(info.value)
    assert derive(load_catalog_datasheet("tmotor-ak80-6")).envelope.max_effort == 12.0

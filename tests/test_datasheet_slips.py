"""A new user's slips with `derive`: each was silent (or blamed the wrong thing) and is now named.

The base drive is the guide's reduced AK80-6: k_t = 91 mNm/A, R = 170 mohm, i_G = 6, I = 24 A,
V = 24 V. Hand values: 1 rpm = 2*pi/60 rad/s = 0.1047198 rad/s; 1 V/krpm = 1 V / (1000 rpm) =
1 / 104.7198 V*s/rad = 0.00954930 V*s/rad.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from _datasheets import sheet_from
from drive_envelope._src.cli.main import main
from drive_envelope._src.datasheet.catalog import catalog_entries, load_catalog_datasheet
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.load import datasheet_from_mapping, load_datasheet
from drive_envelope.errors import InputError

RPM = 2.0 * math.pi / 60.0

BASE: dict[str, Any] = {
    "name": "x",
    "motor": {"torque_constant": "91 mNm/A", "terminal_resistance": "170 mohm"},
    "gear": {"ratio": 6},
    "controller": {"max_current": "24 A", "max_voltage": "24 V"},
}

KV_BARE = """\
name = "x"
[motor]
torque_constant = "91 mNm/A"
terminal_resistance = "170 mohm"
max_torque = "2.5 N*m"
speed_constant = 100
[gear]
ratio = "6:1"
[controller]
max_current = "24 A"
max_voltage = "24 V"
"""


def _sheet(**sections: Any) -> Any:
    """BASE with keys of some sections replaced (None removes a key)."""
    return sheet_from(BASE, "u.toml", **sections)


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


# --- 1. a bare torque constant, with nothing to check it against -----------------------------------


@pytest.mark.parametrize("written", [91, 91.0, "91"])
def test_a_bare_torque_constant_above_one_draws_a_warning(written: object) -> None:
    """`torque_constant = 91` (meant: 91 mNm/A) is 91 N*m/A: max_effort = 24 A * 91 N*m/A * 6 = 13104 N*m.

    91 N*m/A is inside PLAUSIBLE (output-shaft constants are that large), and without a speed constant
    the k_t * k_v check has nothing to compare, so the bare number itself is named.
    """
    result = derive(_sheet(motor={"torque_constant": written}))
    assert result.envelope.max_effort == pytest.approx(13104.0, rel=1e-12)
    (warning,) = result.warnings
    assert warning.startswith("u.toml: motor.torque_constant = 91 is a bare number, read as 91 N*m/A")
    assert "write '91 mNm/A'" in warning and "\n" not in warning


@pytest.mark.parametrize(
    "motor",
    [
        {"torque_constant": "91 N*m/A"},  # the unit written: what the user means, kept silent
        {"torque_constant": 0.091},  # bare, but a motor's usual SI size (0.091 N*m/A)
        {"torque_constant": 1.0},  # the bound itself: above 1 only
        # bare 91 N*m/A with k_v = 1/91 (rad/s)/V: the pair agrees (k_t * k_v = 1), which confirms it
        {"torque_constant": 91, "speed_constant": 1 / 91},
    ],
)
def test_a_torque_constant_with_its_unit_or_a_usual_size_draws_no_warning(motor: dict[str, Any]) -> None:
    """No false alarm: a unit, a value below 1 N*m/A, or an agreeing second constant keep it silent."""
    assert derive(_sheet(motor=motor)).warnings == ()


def test_a_bare_back_emf_constant_above_one_draws_a_warning() -> None:
    """`back_emf_constant = 10` (meant: 10 V/krpm = 0.0955 V*s/rad) is 10 V*s/rad; k_t is derived from it."""
    (warning,) = derive(_sheet(motor={"torque_constant": None, "back_emf_constant": 10})).warnings
    assert "motor.back_emf_constant = 10 is a bare number, read as 10 V*s/rad" in warning
    assert "write '10 V/krpm'" in warning


def test_catalog_motor_constants_typed_bare_in_si_draw_no_warning() -> None:
    """Every catalog entry with a motor constant, its k_t and k_e retyped as bare SI numbers: silent.

    The Harmonic Drive FHA-8C-50's output-shaft 1.3 N*m/A is above 1, but its back-EMF constant
    (0.16 V/(r/min) = 1.528 V*s/rad) agrees with it (1.3 / 1.528 = 0.85), so the pair is checked instead.
    """
    checked = []
    for entry in catalog_entries():
        motor = load_catalog_datasheet(entry.key).motor
        if motor is None or (motor.torque_constant is None and motor.back_emf_constant is None):
            continue
        overrides = {
            f"motor.{key}": repr(value)
            for key in ("torque_constant", "back_emf_constant", "speed_constant")
            if (value := getattr(motor, key)) is not None
        }
        sheet = load_catalog_datasheet(entry.key, overrides=overrides)
        assert (
            "motor.torque_constant" in sheet.bare_numbers or "motor.back_emf_constant" in sheet.bare_numbers
        )
        assert derive(sheet).warnings == (), entry.key
        checked.append(entry.key)
    assert "harmonic-drive-fha-8c-50" in checked and "tmotor-ak80-6" in checked


# --- 2. k_t against k_e ------------------------------------------------------------------------------


def test_a_torque_constant_that_disagrees_with_the_back_emf_constant_draws_a_warning() -> None:
    """91 mNm/A with 30 V/krpm: k_e = 30 * 0.00954930 = 0.286479 V*s/rad, k_t / k_e = 0.091 / 0.286479
    = 0.3176.

    An ideal motor has k_t = k_e in SI (k_e = 1/k_v), so this is the k_t * k_v check with k_e.
    """
    (warning,) = derive(_sheet(motor={"back_emf_constant": "30 V/krpm"})).warnings
    assert warning.startswith(
        "u.toml: motor.torque_constant / motor.back_emf_constant = 0.3176 in SI units, an ideal motor has 1"
    )


def test_a_torque_constant_that_agrees_with_the_back_emf_constant_draws_no_warning() -> None:
    """91 mNm/A with 9.53 V/krpm = 0.0910 V*s/rad: k_t / k_e = 1.0000."""
    assert derive(_sheet(motor={"back_emf_constant": "9.53 V/krpm"})).warnings == ()


# --- 3. a modulation typed as a tiny percentage ------------------------------------------------------


def test_a_modulation_below_the_lowest_efficiency_draws_a_warning() -> None:
    """`modulation = "0.9 %"` is mu_C = 0.009: the voltage limit 91 mNm/A -> k_v = 1/0.091 = 10.989
    (rad/s)/V; 10.989 * 24 V * 0.009 / 6 = 0.395604 rad/s, a hundredth of what 90 % gives."""
    result = derive(_sheet(controller={"modulation": "0.9 %"}))
    assert result.envelope.max_actuator_velocity == pytest.approx(24 * 0.009 / 0.091 / 6, rel=1e-12)
    (warning,) = result.warnings
    assert warning == (
        "u.toml: controller.modulation = 0.009 is unusually low: a percentage needs its sign ('90 %' or 0.9)"
    )
    assert derive(_sheet(controller={"modulation": "90 %"})).warnings == ()


# --- 4. continuous duty from peak ratings ------------------------------------------------------------


def test_continuous_duty_from_the_peak_current_says_so() -> None:
    """No motor.continuous_torque: max_effort = 24 A * 0.091 N*m/A * 6 = 13.104 N*m is the controller's
    (peak) current limit, and a note names controller.max_current."""
    result = derive(_sheet(), duty="continuous")
    assert result.max_effort_limited_by == "controller_current"
    assert result.envelope.max_effort == pytest.approx(13.104, rel=1e-12)
    assert (
        "controller.max_current (a peak current) is used for continuous duty: max_effort is limited by "
        "controller_current, as no continuous rating is given (motor.continuous_torque or "
        "output.nominal_effort)"
    ) in result.notes


def test_continuous_duty_of_a_servo_from_its_stall_torque_says_so() -> None:
    """A servo printing only stall torque 4.1 N*m and no-load speed 46 rpm: max_effort = 4.1 N*m, a peak."""
    data = {"name": "servo", "output": {"stall_effort": "4.1 N*m", "no_load_velocity": "46 rpm"}}
    result = derive(datasheet_from_mapping(data, source="s.toml"), duty="continuous")
    assert result.envelope.max_effort == 4.1
    assert any(
        n.startswith("output.stall_effort (a peak rating) is used for continuous duty") for n in result.notes
    )
    peak = derive(datasheet_from_mapping(data, source="s.toml"))
    assert not any("continuous duty" in n for n in peak.notes)


def test_continuous_duty_from_the_continuous_torque_has_no_peak_note() -> None:
    """continuous_torque 1 N*m: 1 * 6 = 6 N*m binds below the current limit's 13.104 N*m; no note.

    With continuous_torque 3 N*m (18 N*m) the current limit binds below it: named, as a cap that holds
    at any duty.
    """
    result = derive(_sheet(motor={"continuous_torque": "1 N*m"}), duty="continuous")
    assert result.envelope.max_effort == pytest.approx(6.0, rel=1e-12)
    assert not any("is used for continuous duty" in n for n in result.notes)
    capped = derive(_sheet(motor={"continuous_torque": "3 N*m"}), duty="continuous")
    assert capped.envelope.max_effort == pytest.approx(13.104, rel=1e-12)
    assert any("binds below the continuous rating" in n for n in capped.notes)


# --- 5. a ratio below 1 -----------------------------------------------------------------------------


@pytest.mark.parametrize(("written", "shown"), [(0.16667, "0.16667"), ("0.16667", "'0.16667'")])
def test_a_numeric_ratio_below_one_is_noted(written: object, shown: str) -> None:
    """ratio = 0.16667 (6:1 typed inverted) is a speed-up: 1 / 0.16667 = 5.99988; the joint then gets
    24 A * 0.091 N*m/A * 0.16667 = 0.364007 N*m. It is read as written, with a note."""
    result = derive(_sheet(gear={"ratio": written}))
    assert result.envelope.max_effort == pytest.approx(24 * 0.091 * 0.16667, rel=1e-12)
    (note,) = [n for n in result.notes if "below 1" in n]
    assert note.startswith(
        f"'gear.ratio' = {shown} is below 1: read as a speed-up gear, the joint turning 5.99988"
    )
    assert not any("below 1" in n for n in derive(_sheet(gear={"ratio": 6})).notes)
    assert not any("below 1" in n for n in derive(_sheet(gear={"ratio": "1:6"})).notes)  # its own note


# --- 6. envelope show and plot print derive's warnings -----------------------------------------------


def test_envelope_show_prints_the_datasheets_warnings(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`speed_constant = 100` is 100 (rad/s)/V: k_t * k_v = 0.091 * 100 = 9.1, as `derive` warns."""
    path = tmp_path / "kv_bare.toml"
    path.write_text(KV_BARE, encoding="utf-8")
    code, out, err = _run(capsys, "envelope", "show", str(path))
    assert code == 0 and "max_effort" in out
    assert err == (
        f"drive-envelope: warning: {path}: motor.torque_constant * motor.speed_constant = 9.1 in SI units, "
        "an ideal motor has 1 (k_t = 1/k_v): check their units ('mNm/A' vs 'N*m/A', 'rpm/V')\n"
    )
    code, _, err = _run(capsys, "envelope", "show", "tmotor-ak80-6")
    assert code == 0 and err == ""


def test_plot_prints_the_datasheets_warnings(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The same file drawn: the one warning on stderr; an envelope file draws none."""
    pytest.importorskip("matplotlib")
    path = tmp_path / "kv_bare.toml"
    path.write_text(KV_BARE, encoding="utf-8")
    code, _, err = _run(capsys, "plot", str(path), "-o", str(tmp_path / "x.png"))
    (line,) = [line for line in err.splitlines() if "warning" in line]
    assert code == 0 and "motor.torque_constant * motor.speed_constant = 9.1 in SI units" in line
    envelope = tmp_path / "env.toml"
    envelope.write_text(
        'name = "e"\nmax_effort = 10\nmax_actuator_velocity = 5\nvelocity_dependent_resistance = 0\n'
        "speed_effort_gradient = 0\n",
        encoding="utf-8",
    )
    code, _, err = _run(capsys, "plot", str(envelope), "-o", str(tmp_path / "e.png"))
    assert code == 0 and "warning" not in err


# --- 7. a TOML duplicate names its key ---------------------------------------------------------------


def test_a_toml_duplicate_key_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Line 4 repeats [output] max_effort: named as JSON and YAML duplicates are, with its line."""
    path = tmp_path / "dup.toml"
    path.write_text('name = "x"\n[output]\nmax_effort = "8 N*m"\nmax_effort = "9 N*m"\n', encoding="utf-8")
    with pytest.raises(InputError) as info:
        load_datasheet(path)
    assert (
        str(info.value) == f"{path}: duplicate key 'output.max_effort' (line 4): each key may be written once"
    )
    for argv in (["derive", str(path)], ["envelope", "show", str(path)]):
        code, _, err = _run(capsys, *argv)
        assert code == 2 and "duplicate key 'output.max_effort' (line 4)" in err and err.count("\n") == 1


def test_every_toml_reader_names_a_duplicate_key(tmp_path: Path) -> None:
    """The naming lives in the one mapping reader: a scenario's duplicate key is named too."""
    from drive_envelope._src.io.files import read_mapping

    path = tmp_path / "scenario.toml"
    path.write_text("[joint]\ninertia = 1\n\n[joint]\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"scenario\.toml: duplicate table \[joint\] \(line 4\)"):
        read_mapping(path)
    path.write_text('[drive]\n"stiffness" = 1\nstiffness = 2\n', encoding="utf-8")
    with pytest.raises(InputError, match=r"duplicate key 'drive\.stiffness' \(line 3\): each key"):
        read_mapping(path)


def test_a_toml_table_written_twice_is_named(tmp_path: Path) -> None:
    """[output] on lines 2 and 4: TOML's "Cannot declare ('output',) twice" names the table."""
    path = tmp_path / "dup.toml"
    path.write_text('name = "x"\n[output]\nmax_effort = 1\n[output]\nmax_velocity = 2\n', encoding="utf-8")
    with pytest.raises(InputError, match=r"dup\.toml: duplicate table \[output\] \(line 4\)"):
        load_datasheet(path)


# --- 8. a bad override value blames the override -----------------------------------------------------


def test_a_bad_override_value_names_the_override(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`--set output.no_load_velocity="50 Hz"`: the command line's value, not the file's; the same value
    in the file still names the file."""
    path = tmp_path / "a.toml"
    path.write_text('name = "x"\n[output]\nmax_effort = "8 N*m"\n', encoding="utf-8")
    code, _, err = _run(capsys, "derive", str(path), "--set", "output.no_load_velocity=50 Hz")
    assert code == 2
    assert err.startswith(
        "drive-envelope: error: override 'output.no_load_velocity': '50 Hz' has no matching"
    )
    assert str(path) not in err and err.count("\n") == 1
    path.write_text('name = "x"\n[output]\nno_load_velocity = "50 Hz"\n', encoding="utf-8")
    code, _, err = _run(capsys, "derive", str(path))
    assert code == 2 and f"{path}: key 'output.no_load_velocity': '50 Hz'" in err


def test_operating_points_rising_from_zero_effort_are_not_a_no_load_speed(tmp_path: Path) -> None:
    """1 oz-in at 100 rpm rising to 100 oz-in at 2000 rpm: said to rise, not to fall to zero at 100 rpm."""
    path = tmp_path / "rising.toml"
    path.write_text(
        'name = "x"\n[motor]\nmax_torque = "145 oz-in"\nmax_speed = "2628 RPM"\n[losses]\n'
        'operating_points = [["100 RPM", "1 oz-in"], ["2000 RPM", "100 oz-in"]]\n',
        encoding="utf-8",
    )
    result = derive(load_datasheet(path))
    assert any(note.startswith("operating points rise with speed (fitted slope") for note in result.notes)
    assert not any("fall to zero effort" in note for note in result.notes)
    assert result.envelope.velocity_dependent_resistance == 0.0


def test_a_resistance_that_zeroes_the_effort_below_the_speed_limit_is_noted(tmp_path: Path) -> None:
    """8 N*m and R = 5 N*m*s/rad reach zero effort at 8 / 5 = 1.6 rad/s, below the 10 rad/s limit."""
    path = tmp_path / "resistance.toml"
    path.write_text(
        'name = "x"\n[output]\nmax_effort = "8 N*m"\nmax_velocity = "10 rad/s"\n'
        "velocity_dependent_resistance = 5\n",
        encoding="utf-8",
    )
    notes = derive(load_datasheet(path)).notes
    assert (
        "the effort line reaches zero effort at 1.6 rad/s (max_effort / velocity_dependent_resistance), "
        "below max_actuator_velocity = 10 rad/s: no operating point reaches max_actuator_velocity"
    ) in notes

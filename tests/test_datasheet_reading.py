"""Reading datasheets as users write them: YAML and JSON traps, duplicate keys, numbers beyond float
range, ratios written both ways, servo ratings as a speed-effort line, and the hints on mistakes.

Each "silently wrong" case of issue 18 and the reliability cases of issue 15 is here, with its
expected value computed by hand in the test.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import pytest

from drive_envelope._src.cli.main import main
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.load import (
    _FIXED,
    _LINEAR,
    _ROTARY,
    DATASHEET_SECTIONS,
    KEY_ALIASES,
    SECTION_CLASSES,
    SECTION_KEYS,
    datasheet_from_mapping,
    load_datasheet,
)
from drive_envelope._src.io.files import read_mapping
from drive_envelope.errors import InputError

RPM = 2.0 * math.pi / 60.0
KGF = 9.80665

# The spec's reduced AK80-6 drive: 24 A * 0.091 N*m/A * 6 * 0.92 = 12.05568 N*m.
AK80 = """\
name: AK80-6
motor:
  torque_constant: 0.091 N*m/A
  speed_constant: 100 rpm/V
  terminal_resistance: 170 mohm
gear:
  ratio: {ratio}
  efficiency: 0.92
controller:
  max_current: 24 A
  max_voltage: 24 V
"""


def write(tmp_path: Path, name: str, text: str) -> Path:
    """Write ``text`` to ``tmp_path/name`` and return the path."""
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# --- YAML: what the user wrote, never what YAML 1.1 makes of it ----------------------------------


@pytest.mark.parametrize(("written", "expected"), [("6:1", 6.0), ("10:1", 10.0), ("6", 6.0), ("'6:1'", 6.0)])
def test_yaml_ratio_stays_what_was_written(tmp_path: Path, written: str, expected: float) -> None:
    """An unquoted 6:1 was the sexagesimal integer 361 (2.5 N*m became 902.5 N*m); now it is 6."""
    sheet = load_datasheet(write(tmp_path, "ak.yaml", AK80.format(ratio=written)))
    assert sheet.gear is not None and sheet.gear.ratio == expected
    assert derive(sheet).envelope.max_effort == pytest.approx(24 * 0.091 * expected * 0.92, rel=1e-15)


def test_yaml_scalars_follow_yaml_1_2(tmp_path: Path) -> None:
    """6:1 and 1:50 stay strings, 010 is ten (not octal 8), 1e3 is a float, yes and dates stay text."""
    data = read_mapping(write(tmp_path, "y.yaml", "a: 6:1\nb: 1:50\nc: 010\nd: 1e3\ne: yes\nf: 2024-01-02\n"))
    assert data == {"a": "6:1", "b": "1:50", "c": 10, "d": 1000.0, "e": "yes", "f": "2024-01-02"}


def test_yaml_ratio_smaller_first_is_a_reduction_with_a_note(tmp_path: Path) -> None:
    """'1:50' was read as i_G = 0.02 with no note; now it is a reduction of 50, and the report says so."""
    sheet = load_datasheet(write(tmp_path, "ak.yaml", AK80.format(ratio="1:50")))
    assert sheet.gear is not None and sheet.gear.ratio == 50.0
    result = derive(sheet)
    assert any("'1:50' read as a reduction of 50" in note for note in result.notes)
    assert result.envelope.max_effort == pytest.approx(24 * 0.091 * 50 * 0.92, rel=1e-15)


def test_a_speed_up_gear_is_written_as_a_number() -> None:
    """A ratio below 1 is accepted as a number (i_G = 0.02: the output turns 50 times faster)."""
    sheet = datasheet_from_mapping({"name": "x", "gear": {"ratio": 0.02}}, source="t.toml")
    assert sheet.gear is not None and sheet.gear.ratio == 0.02


@pytest.mark.parametrize("ratio", ["51.45:1", "51.45 : 1"])
def test_pololu_ratio_with_decimals(ratio: str) -> None:
    """Pololu Micro Metal Gearmotors datasheet Rev 6.2 prints the 50:1 gearbox as '51.45:1'."""
    sheet = datasheet_from_mapping({"name": "x", "gear": {"ratio": ratio}}, source="t.toml")
    assert sheet.gear is not None and sheet.gear.ratio == pytest.approx(51.45, rel=1e-15)


@pytest.mark.parametrize("ratio", ["6:0", "6:1:2", "six:1", "0:6"])
def test_unreadable_ratio_is_a_one_line_error(ratio: str) -> None:
    """Refuse ratios that are not two positive numbers, naming the key."""
    with pytest.raises(InputError) as info:
        datasheet_from_mapping({"name": "x", "gear": {"ratio": ratio}}, source="t.toml")
    assert "gear.ratio" in str(info.value) and "\n" not in str(info.value)


# --- duplicate keys and numbers beyond float range (issue 15) --------------------------------------


def test_duplicate_key_in_json_is_refused_naming_it(tmp_path: Path) -> None:
    """JSON silently keeps the last of two equal keys; the file is refused instead."""
    path = write(tmp_path, "d.json", '{"name": "x", "gear": {"ratio": 6, "ratio": 9}}')
    with pytest.raises(InputError) as info:
        read_mapping(path)
    message = str(info.value)
    assert "d.json" in message and "'ratio'" in message and "\n" not in message


def test_duplicate_key_in_yaml_is_refused_naming_it_and_its_line(tmp_path: Path) -> None:
    """YAML also keeps the last duplicate; the message names the key and the line."""
    path = write(tmp_path, "d.yaml", "name: x\ngear:\n  ratio: 6\n  ratio: 9\n")
    with pytest.raises(InputError) as info:
        read_mapping(path)
    message = str(info.value)
    assert "d.yaml" in message and "'ratio'" in message and "line 4" in message and "\n" not in message


def test_duplicate_key_in_toml_is_refused(tmp_path: Path) -> None:
    """TOML refuses duplicates itself; the error is one line naming the file."""
    path = write(tmp_path, "d.toml", 'name = "x"\n[gear]\nratio = 6\nratio = 9\n')
    with pytest.raises(InputError) as info:
        read_mapping(path)
    assert "d.toml" in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("name", "text", "key"),
    [
        ("big.json", '{"name": "x", "gear": {"ratio": 1e400}}', "gear.ratio"),
        ("big.json", '{"name": "x", "gear": {"ratio": ' + "9" * 400 + "}}", "gear.ratio"),
        ("big.toml", 'name = "x"\n[gear]\nratio = 1e400\n', "gear.ratio"),
        ("big.toml", 'name = "x"\n[controller]\nmax_current = ' + "9" * 400 + "\n", "controller.max_current"),
        ("big.yaml", "name: x\ngear:\n  ratio: 1e400\n", "gear.ratio"),
        ("big.yaml", "name: x\ngear:\n  ratio: " + "9" * 400 + "\n", "gear.ratio"),
    ],
)
def test_numbers_beyond_float_range_name_the_key(tmp_path: Path, name: str, text: str, key: str) -> None:
    """A literal beyond about 1.8e308 is refused naming its dotted key, not read as inf."""
    with pytest.raises(InputError) as info:
        read_mapping(write(tmp_path, name, text))
    message = str(info.value)
    assert key in message and "float range" in message and "\n" not in message


def test_written_infinity_stays_infinity(tmp_path: Path) -> None:
    """TOML's inf is a written infinity, not an overflow: it reaches the key's own rule."""
    data = read_mapping(write(tmp_path, "inf.toml", "x = inf\n"))
    assert data == {"x": math.inf}


@pytest.mark.parametrize(
    ("key", "value", "effort"),
    [
        ("motor.torque_constant", "1e308", None),  # 24 * 1e308 * 6 * 0.92 overflows
        ("motor.torque_constant", "5e-324", None),  # R / k_t^2 overflows
        ("gear.ratio", "1e308", None),  # 24 * 0.091 * 1e308 * 0.92 overflows
        ("gear.ratio", "5e-324", None),  # k_v * V * mu_C / 5e-324 overflows
        ("controller.max_current", "1e308", 1e308 * 0.091 * 6 * 0.92),  # finite: the hand value
    ],
)
def test_derive_extreme_values_are_a_number_or_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], key: str, value: str, effort: float | None
) -> None:
    """`derive` with 1e308 or 5e-324 in k_t or the ratio: a correct number or a one-line error, exit 2."""
    path = write(tmp_path, "ak.yaml", AK80.format(ratio=6))
    code = main(["derive", str(path), "--set", f"{key}={value}", "--format", "envelope-json"])
    out, err = capsys.readouterr()
    if effort is not None:
        assert code == 0
        assert json.loads(out)["max_effort"] == pytest.approx(effort, rel=1e-12)
        return
    assert code == 2 and out == ""
    assert err.strip().count("\n") == 0 and "Traceback" not in err
    assert key in err and "out of range" in err


def test_derive_tiny_torque_constant_gives_the_hand_values(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """k_t = 1e-15 N*m/A: maxEffort = 24 * 1e-15 * 6 * 0.92, gradient = 0.17 / (1e-15)^2 / 6^2.

    Both stay within float32's normal range (PhysX's); a limit below it is refused (next test).
    """
    path = write(tmp_path, "ak.yaml", AK80.format(ratio=6))
    assert (
        main(["derive", str(path), "--set", "motor.torque_constant=1e-15", "--format", "envelope-json"]) == 0
    )
    envelope = json.loads(capsys.readouterr().out)
    assert envelope["max_effort"] == pytest.approx(24 * 1e-15 * 6 * 0.92, rel=1e-12)
    assert envelope["speed_effort_gradient"] == pytest.approx(0.17 / 1e-30 / 36, rel=1e-12)


def test_derive_limit_below_float32_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """k_t = 1e-100 N*m/A gives maxEffort 1.3e-98 N*m, 0 in PhysX's float32: refused, naming the inputs."""
    path = write(tmp_path, "ak.yaml", AK80.format(ratio=6))
    assert main(["derive", str(path), "--set", "motor.torque_constant=1e-100"]) == 2
    err = capsys.readouterr().err
    assert "controller_current" in err and "underflows to 1.32e-98" in err and err.strip().count("\n") == 0


def test_derive_gradient_overflow_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """R = 1e308 ohm makes R / k_t^2 overflow: a one-line error naming the inputs, exit 2."""
    path = write(tmp_path, "ak.yaml", AK80.format(ratio=6))
    assert main(["derive", str(path), "--set", "motor.terminal_resistance=1e308"]) == 2
    err = capsys.readouterr().err
    assert "speed_effort_gradient" in err and "motor.torque_constant" in err and err.strip().count("\n") == 0


# --- a bare number is SI, however it is written -----------------------------------------------------


def test_bare_number_is_si_in_the_file_quoted_and_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """controller.max_voltage = 24, = "24" and --set 24 give the same envelope (24 V)."""
    base = {"name": "x", "motor": {"torque_constant": 0.091, "speed_constant": "100 rpm/V"}}
    numbers = []
    for value in (24, "24"):
        sheet = datasheet_from_mapping(
            {**base, "controller": {"max_current": 24, "max_voltage": value}}, source="t"
        )
        numbers.append(derive(sheet).envelope.max_actuator_velocity)
    path = write(
        tmp_path, "x.json", json.dumps({**base, "controller": {"max_current": 24, "max_voltage": 12}})
    )
    assert main(["derive", str(path), "--set", "controller.max_voltage=24", "--format", "envelope-json"]) == 0
    numbers.append(json.loads(capsys.readouterr().out)["max_actuator_velocity"])
    expected = 100 * RPM * 24 * 0.9  # k_v * V * mu_C (default 0.9), no gear
    assert numbers == [pytest.approx(expected, rel=1e-15)] * 3


def test_duplicate_set_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Two --set for one key: refused with one line instead of keeping the last silently."""
    path = write(tmp_path, "ak.yaml", AK80.format(ratio=6))
    code = main(["derive", str(path), "--set", "gear.ratio=6", "--set", "gear.ratio=9"])
    err = capsys.readouterr().err
    assert code == 2 and "gear.ratio" in err and err.strip().count("\n") == 0


# --- hints on mistakes ------------------------------------------------------------------------------


def test_wrong_dimension_suggests_the_neighbouring_key() -> None:
    """'100 rpm/V' under motor.torque_constant is a speed constant: the message suggests that key."""
    with pytest.raises(InputError) as info:
        datasheet_from_mapping({"name": "x", "motor": {"torque_constant": "100 rpm/V"}}, source="s.toml")
    message = str(info.value)
    assert "'motor.torque_constant'" in message
    assert "a torque constant in N*m/A" in message
    assert "did you mean motor.speed_constant?" in message


def test_a_bare_number_never_suggests_a_key() -> None:
    """A bare number fits every unit, so a rule violation suggests nothing."""
    with pytest.raises(InputError) as info:
        datasheet_from_mapping({"name": "x", "motor": {"torque_constant": -1}}, source="s.toml")
    assert "did you mean" not in str(info.value)


@pytest.mark.parametrize(
    ("key", "hint"), [("motr", "'motor'"), ("max_torque", "[motor]"), ("supplier", None)]
)
def test_unknown_top_level_key_suggests_only_what_is_close(key: str, hint: str | None) -> None:
    """'motr' suggests motor; 'max_torque' belongs in [motor]; 'supplier' suggests nothing."""
    with pytest.raises(InputError) as info:
        datasheet_from_mapping({"name": "x", key: 1}, source="s.toml")
    message = str(info.value)
    if hint is None:
        assert "did you mean" not in message and "belongs" not in message
    else:
        assert hint in message


# --- servo and gearmotor ratings: the speed-effort line ---------------------------------------------


def test_stall_torque_and_no_load_speed_give_the_line() -> None:
    """FEETECH ST-3215-C001 at 6 V: 'Peak stall torque 19.5kg.cm', 'No load speed 0.238sec/60°'.

    k_vt = v_0 / tau_stall = (pi/3 / 0.238) / (19.5 * 9.80665 / 100) (rad/s)/(N*m).
    """
    sheet = datasheet_from_mapping(
        {"name": "st3215", "output": {"stall_torque": "19.5 kg.cm", "no_load_speed": "0.238 sec/60°"}},
        source="t",
    )
    env = derive(sheet).envelope
    v0 = (math.pi / 3) / 0.238
    tau = 19.5 * KGF / 100
    assert env.max_effort == pytest.approx(tau, rel=1e-15)
    assert env.max_actuator_velocity == pytest.approx(v0, rel=1e-15)
    assert env.speed_effort_gradient == pytest.approx(v0 / tau, rel=1e-12)


@pytest.mark.parametrize(
    ("alias", "key"), [("stall_torque", "stall_effort"), ("no_load_speed", "no_load_velocity")]
)
def test_alias_and_key_mean_the_same(alias: str, key: str) -> None:
    """stall_torque is stall_effort and no_load_speed is no_load_velocity."""
    other = {"stall_effort": "2 N*m", "no_load_velocity": "60 rpm"}
    a = dict(other)
    a[alias] = a.pop(key)
    one = derive(datasheet_from_mapping({"name": "x", "output": a}, source="t")).envelope
    two = derive(datasheet_from_mapping({"name": "x", "output": other}, source="t")).envelope
    assert one == two


def test_alias_with_its_key_is_refused() -> None:
    """stall_torque and stall_effort both given: they are one key, keep one."""
    with pytest.raises(InputError, match="same key"):
        datasheet_from_mapping(
            {"name": "x", "output": {"stall_torque": "2 N*m", "stall_effort": "2 N*m", "no_load_speed": 1}},
            source="t",
        )


def test_stall_force_on_a_revolute_joint_is_refused() -> None:
    """A revolute joint has a stall_torque; stall_force is for a prismatic one."""
    with pytest.raises(InputError, match="stall_torque"):
        datasheet_from_mapping(
            {"name": "x", "output": {"stall_force": "2 N", "no_load_speed": 1}}, source="t"
        )


def test_linear_servo_stall_force() -> None:
    """Actuonix L16-R 63:1 (WCP general data): 'Max Speed (no load) 20mm/s', stall force not printed.

    With a stall_force the line is v_0 / F_stall; here 0.020 m/s / 100 N (illustrative force).
    """
    sheet = datasheet_from_mapping(
        {"name": "l16", "joint": "prismatic", "output": {"stall_force": "100 N", "no_load_speed": "20 mm/s"}},
        source="t",
    )
    env = derive(sheet).envelope
    assert env.speed_effort_gradient == pytest.approx(0.020 / 100, rel=1e-12)


def test_nominal_point_gives_the_line_without_a_stall_torque() -> None:
    """RobStride-style ratings: no-load 315 rpm, rated 6 N*m at 100 rpm, peak 17 N*m.

    The line through (0, v_0) and (tau_N, v_N): k_vt = (315 - 100) rpm / 6 N*m.
    """
    output = {
        "max_effort": "17 N*m",
        "no_load_velocity": "315 rpm",
        "nominal_effort": "6 N*m",
        "nominal_velocity": "100 rpm",
    }
    env = derive(datasheet_from_mapping({"name": "x", "output": output}, source="t")).envelope
    assert env.speed_effort_gradient == pytest.approx((315 - 100) * RPM / 6, rel=1e-12)
    assert env.max_effort == 17.0
    assert env.max_actuator_velocity == pytest.approx(315 * RPM, rel=1e-15)


@pytest.mark.parametrize(
    ("output", "fragment"),
    [
        ({"nominal_velocity": "100 rpm", "nominal_effort": 6, "max_effort": 17}, "no_load_velocity"),
        ({"nominal_velocity": "100 rpm", "no_load_velocity": "315 rpm", "max_effort": 17}, "nominal_effort"),
        (
            {"nominal_velocity": "400 rpm", "no_load_velocity": "315 rpm", "nominal_effort": 6},
            "must be below",
        ),
    ],
)
def test_nominal_velocity_needs_its_line(output: dict[str, Any], fragment: str) -> None:
    """A nominal speed needs its effort and the no-load speed, and lies below the no-load speed."""
    with pytest.raises(InputError, match=fragment):
        datasheet_from_mapping({"name": "x", "output": output}, source="t")


def test_caps_only_note_tells_how_to_get_the_line() -> None:
    """max_effort and max_velocity alone are caps: a rectangle, with a note naming the line's keys."""
    result = derive(
        datasheet_from_mapping({"name": "x", "output": {"max_effort": 2, "max_velocity": 6}}, source="t")
    )
    assert result.envelope.speed_effort_gradient == 0.0
    assert any("output.stall_effort and output.no_load_velocity" in note for note in result.notes)


def test_gradient_method_not_needed_is_a_note() -> None:
    """--gradient-method resistance on ratings only: not an error; a note says it was not needed."""
    sheet = datasheet_from_mapping(
        {"name": "x", "output": {"stall_effort": 2, "no_load_velocity": 6}}, source="t"
    )
    result = derive(sheet, gradient_method="resistance")
    assert result.envelope.speed_effort_gradient == pytest.approx(6 / 2, rel=1e-15)
    assert any("gradient method 'resistance' not needed" in note for note in result.notes)


def test_continuous_duty_uses_the_nominal_effort() -> None:
    """RobStride RS01: 'Rated load: 6 N.m' is the continuous rating, 'Peak load: 17 N.m' the peak."""
    output = {"max_effort": "17 N.m", "no_load_velocity": "315 rpm", "nominal_effort": "6 N.m"}
    sheet = datasheet_from_mapping({"name": "rs01", "output": output}, source="t")
    assert derive(sheet, duty="continuous").envelope.max_effort == 6.0
    assert derive(sheet).envelope.max_effort == 17.0


def test_the_smaller_of_stall_and_cap_binds() -> None:
    """A cap below the stall torque binds the effort; the line still comes from stall and no-load."""
    output = {"max_effort": 1.5, "stall_effort": 2.0, "no_load_velocity": 6.0}
    result = derive(datasheet_from_mapping({"name": "x", "output": output}, source="t"))
    assert result.envelope.max_effort == 1.5
    assert result.max_effort_limited_by == "output_rating"
    assert result.envelope.speed_effort_gradient == pytest.approx(6.0 / 2.0, rel=1e-15)


def _fields_without_a_key(section_class: type) -> list[str]:
    """The fields of a section class that neither carry a file rule nor say they are not a file key."""
    return [
        item.name
        for item in dataclasses.fields(section_class)
        if "kind" not in item.metadata and item.metadata.get("file_key", True)
    ]


def test_section_fields_and_file_keys_are_one_table() -> None:
    """Every section field is a file key (or says it is not one), every file key is a field, and
    every rule is one the reader can read: the file format and the dataclasses cannot drift."""
    readable = {*_ROTARY, *_LINEAR, *_FIXED, "enum", "points", "lead"}
    assert list(SECTION_CLASSES) == list(SECTION_KEYS) == list(DATASHEET_SECTIONS)
    for section, section_class in SECTION_CLASSES.items():
        assert _fields_without_a_key(section_class) == [], f"[{section}] fields without a file rule"
        names = {item.name for item in dataclasses.fields(section_class)}
        for key, (kind, bound, side) in SECTION_KEYS[section].items():
            assert key in names, f"{section}.{key} is not a field of {section_class.__name__}"
            assert kind in readable, f"{section}.{key}: kind {kind!r}"
            assert bound in (">0", ">=0", "(0,1]", ""), f"{section}.{key}: bound {bound!r}"
            assert side in ("motor", "joint"), f"{section}.{key}: side {side!r}"
        for alias, target in KEY_ALIASES.get(section, {}).items():
            assert target in SECTION_KEYS[section], f"{section}.{alias} -> {target}"


def test_a_field_without_a_file_rule_is_found() -> None:
    """The check above fails on a section class given a field without a rule."""

    @dataclasses.dataclass(frozen=True)
    class Drifted:
        ruled: float | None = dataclasses.field(default=None, metadata={"kind": "torque"})
        not_a_key: str = dataclasses.field(default="", metadata={"file_key": False})
        unruled: float | None = None

    assert _fields_without_a_key(Drifted) == ["unruled"]

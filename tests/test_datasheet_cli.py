"""`drive-envelope derive` and `catalog` through the CLI: output, bad input (exit 2, one line), files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main

AK80 = """\
name = "T-Motor AK80-6"
joint = "revolute"

[motor]
torque_constant = "0.091 N*m/A"
speed_constant = "100 rpm/V"
terminal_resistance = "170 mohm"

[gear]
ratio = 6.0
efficiency = 0.92

[controller]
max_current = "24 A"
max_voltage = "24 V"
"""


def write(tmp_path: Path, text: str, name: str = "sheet.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_derive_json_matches_the_spec_example(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Print the spec's JSON object for the reduced AK80-6 example."""
    code, out, _ = run(capsys, "derive", str(write(tmp_path, AK80)), "--json")
    assert code == 0
    data = json.loads(out)
    assert data["max_effort"] == pytest.approx(12.05568)
    assert data["max_actuator_velocity"] == pytest.approx(37.69911184307751)
    assert data["speed_effort_gradient"] == pytest.approx(0.5702478229950758)
    assert data["max_effort_limited_by"] == "controller_current"
    assert data["max_actuator_velocity_limited_by"] == "voltage"
    assert data["speed_effort_gradient_method"] == "resistance"


def test_derive_report_marks_the_binding_limit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Print a table per parameter with formulas, inputs and the binding limit starred."""
    code, out, _ = run(capsys, "derive", str(write(tmp_path, AK80)))
    assert code == 0
    assert "limited by controller_current" in out
    assert "I_C,max * k_t * i_G * eta_G" in out
    star_lines = [line for line in out.splitlines() if line.strip().startswith("*")]
    assert any("controller_current" in line for line in star_lines)
    assert any("voltage" in line for line in star_lines)
    assert "method resistance" in out and "notes:" in out


def test_round_trip_derive_envelope_show(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Write the envelope with --format toml --output and read it back with `envelope show`."""
    out_file = tmp_path / "env.toml"
    code, out, err = run(
        capsys, "derive", str(write(tmp_path, AK80)), "--format", "toml", "--output", str(out_file)
    )
    assert code == 0 and out_file.exists() and "wrote" in err and "wrote" not in out
    assert out == out_file.read_text(encoding="utf-8")  # stdout stays the envelope file itself
    code, shown, _ = run(capsys, "envelope", "show", str(out_file), "--json")
    assert code == 0
    data = json.loads(shown)
    assert data["max_effort"] == 12.05568 or data["max_effort"] == pytest.approx(12.05568, rel=1e-15)
    assert data["max_actuator_velocity"] == pytest.approx(12 * math.pi, rel=1e-15)
    assert data["speed_effort_gradient"] == pytest.approx(0.17 / 0.091**2 / 36, rel=1e-14)
    assert data["name"] == "T-Motor AK80-6"


def test_json_format_to_stdout_is_an_envelope_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Print an envelope file (not the derivation) with --format envelope-json and no --output."""
    code, out, _ = run(capsys, "derive", str(write(tmp_path, AK80)), "--format", "envelope-json")
    assert code == 0
    data = json.loads(out)
    assert set(data) == {
        "name",
        "joint",
        "max_effort",
        "max_actuator_velocity",
        "velocity_dependent_resistance",
        "speed_effort_gradient",
    }


def test_usd_snippet_in_degrees(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Write angular values in degrees as USD stores them."""
    code, out, _ = run(capsys, "derive", str(write(tmp_path, AK80)), "--format", "usd-snippet")
    assert code == 0
    assert "PhysxDrivePerformanceEnvelopeAPI:angular" in out
    line = next(x for x in out.splitlines() if "maxActuatorVelocity" in x)
    assert float(line.split("=")[1].split("#")[0]) == pytest.approx(360 * 6.0)  # 360 rpm = 2160 deg/s
    # USD's float holds float32: its shortest text, not float64 noise (was 2159.9999999999995)
    assert "maxActuatorVelocity = 2160.0  # deg/s" in line


@pytest.mark.usd
def test_usd_snippet_parses_as_usda(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Produce a layer that USD reads, with the attributes on the prim."""
    sdf = pytest.importorskip("pxr.Sdf")
    out_file = tmp_path / "env.usda"
    code, _, _ = run(capsys, "derive", str(write(tmp_path, AK80)), "--output", str(out_file))
    assert code == 0
    layer = sdf.Layer.FindOrOpen(str(out_file))
    prim = layer.GetPrimAtPath("/Joint")
    value = prim.attributes["physxDrivePerformanceEnvelope:angular:speedEffortGradient"].default
    assert value == pytest.approx(0.17 / 0.091**2 / 36 * 180 / math.pi, rel=1e-6)


def test_duty_and_gradient_method_flags(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Honour --duty continuous and --gradient-method."""
    text = AK80.replace(
        "[gear]",
        'max_torque = "2.5 N*m"\ncontinuous_torque = "0.5 N*m"\n'
        'no_load_speed = "2400 rpm"\nnominal_speed = "2000 rpm"\nnominal_torque = "0.5 N*m"\n\n[gear]',
    )
    path = write(tmp_path, text)
    _, out, _ = run(
        capsys, "derive", str(path), "--json", "--duty", "continuous", "--gradient-method", "nominal"
    )
    data = json.loads(out)
    assert data["max_effort_limited_by"] == "motor_torque"
    assert data["max_effort"] == pytest.approx(0.5 * 6 * 0.92)
    assert data["speed_effort_gradient_method"] == "nominal"
    assert data["provenance"]["motor.gradient_method"] == "user"


def test_set_override_is_user_provenance(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Override a datasheet value with --set and record it as user input."""
    _, out, _ = run(
        capsys, "derive", str(write(tmp_path, AK80)), "--json", "--set", "controller.max_voltage=48 V"
    )
    data = json.loads(out)
    assert data["max_actuator_velocity"] == pytest.approx(24 * math.pi)
    assert data["provenance"]["controller.max_voltage"] == "user"


def test_catalog_name_with_override(capsys: pytest.CaptureFixture[str]) -> None:
    """Accept --set on a catalog actuator too."""
    code, out, _ = run(capsys, "derive", "tmotor-ak80-6", "--json", "--set", "controller.max_voltage=12 V")
    assert code == 0
    assert json.loads(out)["provenance"]["controller.max_voltage"] == "user"


def test_approximate_line_flag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Add the line fit to the JSON when asked and a mechanical limit binds."""
    text = AK80.replace("[gear]", 'max_speed = "2100 rpm"\n\n[gear]')
    _, out, _ = run(capsys, "derive", str(write(tmp_path, text)), "--json", "--approximate-line")
    data = json.loads(out)
    assert data["speed_effort_gradient"] == 0.0 and data["speed_effort_gradient_method"] == "mechanical"
    assert data["line_fit"]["speed_effort_gradient"] > 0.0


# -- bad input: exit 2, one line naming file, key and reason, no traceback, nothing written ------------

BAD_CASES = [
    ("malformed", 'name = "x"\n[motor\n', "malformed TOML"),
    ("unknown key", AK80.replace("torque_constant", "torque_constnat"), "did you mean 'torque_constant'"),
    ("unknown section", AK80.replace("[controller]", "[controler]"), "did you mean 'controller'"),
    ("key at top level", 'name = "x"\ntorque_constant = 1.0\n', "belongs in section [motor]"),
    ("ratio 0", AK80.replace("ratio = 6.0", "ratio = 0"), "'gear.ratio': expected a value > 0, got 0"),
    ("negative resistance", AK80.replace('"170 mohm"', '"-170 mohm"'), "'motor.terminal_resistance'"),
    ("efficiency > 1", AK80.replace("efficiency = 0.92", "efficiency = 1.2"), "fraction in (0, 1]"),
    ("efficiency percent", AK80.replace("efficiency = 0.92", 'efficiency = "120 %"'), "'gear.efficiency'"),
    ("missing name", AK80.replace('name = "T-Motor AK80-6"\n', ""), "missing required key 'name'"),
    ("torque in rpm", AK80.replace('"0.091 N*m/A"', '"3000 rpm"'),
     "'motor.torque_constant': '3000 rpm' is not a torque constant in N*m/A"),
    ("unknown unit", AK80.replace('"24 A"', '"24 blorps"'), "unknown unit 'blorps'"),
    ("not a number", AK80.replace("ratio = 6.0", "ratio = [6]"), "'gear.ratio'"),
    ("bad enum", AK80.replace("[gear]", 'gradient_method = "resistence"\n\n[gear]'),
     "did you mean 'resistance'"),
    ("bad joint", AK80.replace('"revolute"', '"rotary"'), "key 'joint'"),
    ("both kv and ke", AK80.replace("[gear]", 'back_emf_constant = "10 V/krpm"\n\n[gear]'),
     "say the same thing"),
    ("screw on revolute", AK80 + '\n[screw]\nlead = "5 mm"\n', "a screw needs joint"),
    ("gear without ratio", AK80.replace("ratio = 6.0\n", ""), "section [gear] needs key 'ratio'"),
    ("no-load below nominal",
     AK80.replace("[gear]", 'no_load_speed = "1000 rpm"\nnominal_speed = "2000 rpm"\n\n[gear]'),
     "'motor.no_load_speed'"),
    ("explicit method missing", AK80.replace("[gear]", 'gradient_method = "datasheet"\n\n[gear]'),
     "gradient method 'datasheet'"),
    ("no velocity candidate", AK80.replace('max_voltage = "24 V"', ""),
     "no candidate limit for max_actuator_velocity"),
    ("velocity_at_max_effort too big",
     AK80 + '\n[output]\nmax_effort = 1.0\nmax_velocity = 1.0\nvelocity_at_max_effort = 2.0\n', "exceeds"),
    ("k_tau_v twice",
     AK80 + "\n[losses]\nvelocity_dependent_resistance = 0.1\n"
     "[output]\nvelocity_dependent_resistance = 0.1\n",
     "both [losses] and [output]"),
    ("one operating point", AK80 + '\n[losses]\noperating_points = [["1000 rpm", "0.2 N*m"]]\n',
     "distinct speeds"),
]  # fmt: skip


@pytest.mark.parametrize(("label", "text", "expected"), BAD_CASES, ids=[c[0] for c in BAD_CASES])
def test_bad_input_exits_2_with_one_line(
    label: str, text: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Exit 2 with one line naming the file and the reason; write nothing."""
    path = write(tmp_path, text)
    out_file = tmp_path / "out.toml"
    code, out, err = run(capsys, "derive", str(path), "--output", str(out_file))
    assert code == 2, label
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"drive-envelope: error: {path}: ")
    assert expected in lines[0]
    assert "Traceback" not in err
    assert not out_file.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["sheet.toml"]  # no temporary file left behind


def test_missing_file_and_unknown_catalog_name(capsys: pytest.CaptureFixture[str]) -> None:
    """Refuse a missing file and an unknown catalog name (suggesting the nearest) with exit 2."""
    code, _, err = run(capsys, "derive", "nowhere/sheet.toml")
    assert code == 2 and "no such file" in err
    code, _, err = run(capsys, "derive", "tmotor-ak80")
    assert code == 2 and "did you mean 'tmotor-ak80-6'" in err


def test_bad_set_override(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Refuse a malformed or unknown --set with exit 2."""
    path = str(write(tmp_path, AK80))
    assert run(capsys, "derive", path, "--set", "controller.max_voltag=12")[0] == 2
    assert run(capsys, "derive", path, "--set", "novalue")[0] == 2


# -- catalog ---------------------------------------------------------------------------------------------


def test_catalog_lists_and_shows(capsys: pytest.CaptureFixture[str]) -> None:
    """List every catalog actuator and print one datasheet with its sources."""
    code, out, _ = run(capsys, "catalog")
    assert code == 0 and "tmotor-ak80-6" in out and "actuonix-l16-63-6-r" in out
    code, out, _ = run(capsys, "catalog", "--json")
    assert len(json.loads(out)["actuators"]) >= 8
    code, out, _ = run(capsys, "catalog", "tmotor-ak80-6")
    assert code == 0 and "https://" in out and "[motor]" in out


def test_derive_by_catalog_name(capsys: pytest.CaptureFixture[str]) -> None:
    """Derive a catalog actuator by its key or by its name."""
    code, out, _ = run(capsys, "derive", "tmotor-ak80-6", "--json")
    assert code == 0
    by_key = json.loads(out)
    code, out, _ = run(capsys, "derive", "T-Motor AK80-6", "--json")
    assert code == 0 and json.loads(out)["max_effort"] == by_key["max_effort"]


def test_json_and_yaml_datasheets(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Accept the same keys in JSON and (when PyYAML is installed) YAML files."""
    import tomllib

    data = tomllib.loads(AK80)
    json_file = tmp_path / "sheet.json"
    json_file.write_text(json.dumps(data), encoding="utf-8")
    code, out, _ = run(capsys, "derive", str(json_file), "--json")
    assert code == 0 and json.loads(out)["max_effort"] == pytest.approx(12.05568)
    yaml = pytest.importorskip("yaml")
    yaml_file = tmp_path / "sheet.yaml"
    yaml_file.write_text(yaml.safe_dump(data), encoding="utf-8")
    code, out, _ = run(capsys, "derive", str(yaml_file), "--json")
    assert code == 0 and json.loads(out)["max_effort"] == pytest.approx(12.05568)


def test_json_is_short_for_format_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Print the same derivation object with --json as with --format json (one flag, two spellings)."""
    sheet = str(write(tmp_path, AK80))
    code, short, _ = run(capsys, "derive", sheet, "--json")
    assert code == 0
    code, long, _ = run(capsys, "derive", sheet, "--format", "json")
    assert code == 0 and short == long and "max_effort_limits" in json.loads(short)


def test_empty_or_folder_output_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Refuse --output '' and an existing folder with one line instead of ignoring or crashing."""
    sheet = str(write(tmp_path, AK80))
    code, _, err = run(capsys, "derive", sheet, "--output", "")
    assert code == 2 and "expected a file name" in err
    code, _, err = run(capsys, "derive", sheet, "-o", str(tmp_path))
    assert code == 2 and "is a folder" in err


@pytest.mark.parametrize("name", ["env.yaml", "env.txt", "env"])
def test_derive_refuses_an_output_suffix_it_cannot_write(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / name
    assert main(["derive", "tmotor-ak80-6", "-o", str(target)]) == 2
    assert "expected a file name ending in .toml, .json, .usda or .usd" in capsys.readouterr().err
    assert not target.exists()


def test_derive_writes_each_format_its_suffix_names(tmp_path: Path) -> None:
    for name, first in (("e.toml", "name ="), ("e.json", "{"), ("e.usda", "#usda 1.0")):
        assert main(["derive", "tmotor-ak80-6", "--format", "json", "-o", str(tmp_path / name)]) == 0
        assert (tmp_path / name).read_text().lstrip().startswith(first)


@pytest.mark.parametrize("format", ["text", "json"])
def test_an_efficiency_typed_as_a_tiny_percentage_draws_a_warning(
    format: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["derive", "tmotor-ak80-6", "--format", format, "--set", "gear.efficiency=0.9 %"]) == 0
    err = capsys.readouterr().err  # on stderr whatever stdout shows: it may be a file
    assert "gear.efficiency = 0.009 is unusually low: a percentage needs its sign" in err


def test_a_limit_below_float32s_range_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "tiny.toml"
    argv = ["derive", "tmotor-ak80-6", "--set", "motor.max_torque=1e-320", "-o", str(target)]
    assert main(argv) == 2
    assert "below float32's smallest normal number, 1.18e-38" in capsys.readouterr().err
    assert not target.exists()


def test_an_unknown_override_key_lists_the_valid_ones(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["derive", "tmotor-ak80-6", "--set", "motor.nope=1"]) == 2
    err = capsys.readouterr().err
    assert "unknown key 'nope' in [motor]; valid keys in [motor]: " in err and "torque_constant" in err


def test_a_read_only_output_needs_force(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The refusal names --force, so derive takes it as every command with -o does."""
    target = tmp_path / "env.toml"
    target.write_text("old", encoding="utf-8")
    target.chmod(0o444)
    assert main(["derive", "tmotor-ak80-6", "-o", str(target)]) == 2
    assert "read-only (pass --force to replace it)" in capsys.readouterr().err
    assert target.read_text(encoding="utf-8") == "old"
    assert main(["derive", "tmotor-ak80-6", "-o", str(target), "--force"]) == 0
    assert target.read_text(encoding="utf-8").startswith('name = "T-Motor AK80-6"')


def test_the_output_cannot_be_the_datasheet(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """derive SHEET -o SHEET replaced the datasheet with its envelope without a word."""
    sheet = write(tmp_path, AK80)
    assert main(["derive", str(sheet), "-o", str(sheet)]) == 2
    assert "is the datasheet itself: write the envelope to a new file" in capsys.readouterr().err
    assert sheet.read_text(encoding="utf-8") == AK80

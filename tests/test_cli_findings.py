"""What a new user broke in the CLI, datasheets and file handling, each pinned by a test.

Standard output that closes early or fills up, output suffixes, files read by guess, datasheet
inputs that look like unit slips, limits below float32's range, runs of no step, a rotary motor on a
prismatic joint, and USD joint paths with a typo.
"""

from __future__ import annotations

import errno
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main
from drive_envelope._src.datasheet.catalog import catalog_entries, load_catalog_datasheet
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.load import datasheet_from_mapping
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.files import read_mapping

CORPUS = Path(__file__).resolve().parent / "corpus" / "good"
ENVELOPE = CORPUS / "envelope.toml"  # max_effort 10, v_max 5, R 0.5, G 0.2
HAS_PXR = importlib.util.find_spec("pxr") is not None


def _failing_log(folder: Path) -> Path:
    """A log whose second sample asks 20 N*m at rest, twice the envelope's max_effort of 10."""
    log = folder / "log.csv"
    log.write_text(
        "time,velocity,effort\n0,0,1\n0.1,0,20\n" + "".join(f"{0.2 + i},1,2\n" for i in range(4000))
    )
    return log


class _Stream:
    """A stdout stand-in whose writes fail like a closed pipe or a full disk."""

    def __init__(self, error: OSError) -> None:
        self.error = error

    def write(self, text: str) -> int:
        raise self.error

    def flush(self) -> None:
        raise self.error

    def fileno(self) -> int:
        raise ValueError("no file descriptor")


def test_a_closed_pipe_keeps_the_failed_checks_status(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(sys, "stdout", _Stream(BrokenPipeError(errno.EPIPE, "Broken pipe")))
    assert main(["check", str(ENVELOPE), str(_failing_log(tmp_path))]) == 1


def test_a_closed_pipe_keeps_a_passing_checks_status(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "stdout", _Stream(BrokenPipeError(errno.EPIPE, "Broken pipe")))
    assert main(["check", str(ENVELOPE), str(CORPUS / "log.csv")]) == 0


def test_a_reader_that_leaves_early_does_not_hide_a_failed_check(tmp_path: Path) -> None:
    """The real thing: ``check ... | head -c 1`` with the pipe closed before the output is flushed."""
    command = [sys.executable, "-m", "drive_envelope", "check", str(ENVELOPE), str(_failing_log(tmp_path))]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdout is not None and process.stderr is not None
    process.stdout.close()  # the reader is gone long before Python has started
    stderr = process.stderr.read().decode()
    assert process.wait(timeout=120) == 1
    assert "Traceback" not in stderr and "Exception ignored" not in stderr


def test_a_full_standard_output_is_one_line_and_status_2(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "stdout", _Stream(OSError(errno.ENOSPC, "No space left on device")))
    assert main(["envelope", "show", str(ENVELOPE)]) == 2
    assert (
        capsys.readouterr().err
        == "drive-envelope: error: cannot write to standard output: No space left on device\n"
    )


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


def test_a_file_is_never_read_as_toml_by_guess(tmp_path: Path) -> None:
    sheet = tmp_path / "motor.txt"
    sheet.write_text('name = "x"\n')
    with pytest.raises(
        InputError, match=r"motor\.txt: expected a \.toml, \.json, \.yaml or \.yml file.*'\.txt'"
    ):
        read_mapping(sheet)


def _sheet(**motor: object) -> dict[str, object]:
    return {
        "name": "hand-typed",
        "motor": dict(motor),
        "gear": {"ratio": "10:1", "efficiency": "90 %"},
        "controller": {"max_current": "24 A", "max_voltage": "48 V"},
    }


def test_a_torque_constant_typed_without_its_unit_draws_a_warning() -> None:
    # 91 read as SI N*m/A with 100 rpm/V (10.47 (rad/s)/V): k_t * k_v = 952.9 where an ideal motor has 1
    sheet = datasheet_from_mapping(_sheet(torque_constant=91, speed_constant="100 rpm/V"), source="s.toml")
    (warning,) = derive(sheet).warnings
    assert warning.startswith("s.toml: motor.torque_constant * motor.speed_constant = 952.9 in SI units")


def test_constants_that_agree_draw_no_warning() -> None:
    # 91 mNm/A and 105 rpm/V: 0.091 * 10.9956 = 1.0006
    sheet = datasheet_from_mapping(_sheet(torque_constant="91 mNm/A", speed_constant="105 rpm/V"), source="s")
    assert derive(sheet).warnings == ()


def test_a_printed_gradient_that_disagrees_with_resistance_draws_a_warning() -> None:
    # R/k_t^2 = 0.571 / 0.0369^2 = 419.36 (rad/s)/(N*m); 15.8 rpm/mNm = 1654.57: 3.95x
    motor = {
        "torque_constant": "36.9 mNm/A",
        "speed_constant": "259 rpm/V",
        "terminal_resistance": "0.571 ohm",
        "speed_torque_gradient": "15.8 rpm/mNm",
    }
    warnings = derive(datasheet_from_mapping(_sheet(**motor), source="m.toml")).warnings
    assert len(warnings) == 1 and "(3.95x): check their units" in warnings[0]
    motor["speed_torque_gradient"] = "4 rpm/mNm"  # 418.88 (rad/s)/(N*m): agrees
    assert derive(datasheet_from_mapping(_sheet(**motor), source="m.toml")).warnings == ()


@pytest.mark.parametrize("format", ["text", "json"])
def test_an_efficiency_typed_as_a_tiny_percentage_draws_a_warning(
    format: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["derive", "tmotor-ak80-6", "--format", format, "--set", "gear.efficiency=0.9 %"]) == 0
    err = capsys.readouterr().err  # on stderr whatever stdout shows: it may be a file
    assert "gear.efficiency = 0.009 is unusually low: a percentage needs its sign" in err


def test_no_catalog_actuator_draws_a_warning() -> None:
    """Real vendor numbers are consistent: the warnings fire on slips, not on datasheets as printed."""
    for entry in catalog_entries():
        assert derive(load_catalog_datasheet(entry.key)).warnings == (), entry.key


def test_a_limit_below_float32s_range_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "tiny.toml"
    argv = ["derive", "tmotor-ak80-6", "--set", "motor.max_torque=1e-320", "-o", str(target)]
    assert main(argv) == 2
    assert "below float32's smallest normal number, 1.18e-38" in capsys.readouterr().err
    assert not target.exists()


def test_a_run_of_no_step_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run.csv"
    argv = ["simulate", str(CORPUS / "scenario.toml"), "-o", str(out), "--set", "simulation.dt=1"]
    assert main(argv) == 2  # the scenario's duration is 0.1 s
    assert "simulation.dt = 1 s is longer than simulation.duration = 0.1 s" in capsys.readouterr().err
    assert not out.exists()
    argv[-1] = "simulation.dt=0.15"  # round(0.1 / 0.15) = 1 step, but dt > duration all the same
    assert main(argv) == 2 and "is longer than simulation.duration" in capsys.readouterr().err


def test_a_duration_that_is_not_whole_steps_says_where_the_run_ends(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run.csv"
    argv = ["simulate", str(CORPUS / "scenario.toml"), "-o", str(out), "--set", "simulation.dt=0.03"]
    assert main(argv) == 0  # 0.1 s / 0.03 s = 3.33: 3 steps, to 0.09 s
    assert "simulating round(duration / dt) = 3 steps, to 0.09 s" in capsys.readouterr().err
    assert len(out.read_text().strip().splitlines()) == 1 + 4  # header, initial state, 3 steps


def test_a_rotary_motor_on_a_prismatic_joint_asks_for_a_screw() -> None:
    data = {"name": "x", "joint": "prismatic", "motor": {"max_torque": "1 N*m", "max_speed": "3000 rpm"}}
    with pytest.raises(InputError, match=r"a rotary motor on a prismatic joint needs \[screw\] lead"):
        datasheet_from_mapping(data, source="d.toml")


def test_an_unknown_override_key_lists_the_valid_ones(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["derive", "tmotor-ak80-6", "--set", "motor.nope=1"]) == 2
    err = capsys.readouterr().err
    assert "unknown key 'nope' in [motor]; valid keys in [motor]: " in err and "torque_constant" in err


@pytest.mark.skipif(not HAS_PXR, reason="needs usd-core")
def test_a_usd_joint_path_with_a_typo_names_the_nearest_joints() -> None:
    from pxr import Usd, UsdPhysics

    from drive_envelope._src.adapters.usd.authoring import resolve_joint
    from drive_envelope._src.adapters.usd.stage import register_schemas

    register_schemas()  # before the first stage, as every entry point does
    stage = Usd.Stage.CreateInMemory()
    UsdPhysics.RevoluteJoint.Define(stage, "/Robot/Arm/RevoluteJoint")
    UsdPhysics.PrismaticJoint.Define(stage, "/Robot/Rail/Slider")
    with pytest.raises(
        InputError, match=r"'/Robot/Arm/RevolutJoint': no such prim .*did you mean '/Robot/Arm/RevoluteJoint'"
    ):
        resolve_joint(stage, "/Robot/Arm/RevolutJoint")
    with pytest.raises(
        InputError, match=r"'/RevoluteJoint': no such prim .*did you mean '/Robot/Arm/RevoluteJoint'\?\)"
    ):
        resolve_joint(stage, "RevoluteJoint")  # a bare name is relative to the root
    with pytest.raises(
        InputError, match=r"'/Zzz': no such prim .*; it has 2 joint\(s\), e\.g\. '/Robot/Arm/RevoluteJoint'"
    ):
        resolve_joint(stage, "/Zzz")


# --- round 3: simulate's JSON as a log, notes on derived envelopes, plot warnings ------------------


def test_check_and_fit_read_simulates_json_trajectory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "run.json"
    assert main(["simulate", str(CORPUS / "scenario.toml"), "-o", str(run)]) == 0
    csv = tmp_path / "run.csv"
    assert main(["simulate", str(CORPUS / "scenario.toml"), "-o", str(csv)]) == 0
    capsys.readouterr()
    assert main(["check", str(ENVELOPE), str(run), "--json"]) in (0, 1)
    from_json = json.loads(capsys.readouterr().out)["joints"][0]
    assert main(["check", str(ENVELOPE), str(csv), "--json"]) in (0, 1)
    from_csv = json.loads(capsys.readouterr().out)["joints"][0]
    assert from_json["samples"] == from_csv["samples"] == 11
    assert from_json["effort"] == from_csv["effort"] and from_json["duration"] == from_csv["duration"]


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


@pytest.mark.skipif(importlib.util.find_spec("matplotlib") is None, reason="needs matplotlib")
def test_a_glyph_the_font_lacks_is_one_warning_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plot", "tmotor-ak80-6", "--title", "AK 日", "-o", str(tmp_path / "t.svg")]) == 0
    lines = capsys.readouterr().err.splitlines()
    (line,) = [line for line in lines if "Glyph" in line]  # once, without matplotlib's source line
    assert line.startswith("drive-envelope: warning: Glyph 26085 (") and "missing from font" in line


def test_load_envelope_of_a_catalog_name_points_to_the_resolver() -> None:
    from drive_envelope import load_envelope

    with pytest.raises(InputError, match=r"'tmotor-ak80-6': no such envelope file; .*resolve_envelope"):
        load_envelope("tmotor-ak80-6")

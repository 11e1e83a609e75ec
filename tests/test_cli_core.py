"""The CLI entry point and ``drive-envelope envelope show``."""

from __future__ import annotations

import errno
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from drive_envelope import PerformanceEnvelope, load_envelope, save_envelope
from drive_envelope._src.cli.main import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "envelopes" / "demo.toml"


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "drive_envelope", *args], capture_output=True, text=True)


def test_version_and_help() -> None:
    """Print the version and the help through python -m."""
    from drive_envelope import __version__

    assert _run("--version").stdout.strip() == f"drive-envelope {__version__}"
    result = _run("--help")
    assert result.returncode == 0
    assert "envelope" in result.stdout


def test_show_prints_table_and_corners(capsys: pytest.CaptureFixture[str]) -> None:
    """Show the parameters and the three corner points of the demo envelope."""
    assert main(["envelope", "show", str(EXAMPLE)]) == 0
    out = capsys.readouterr().out
    assert "max_actuator_velocity" in out and "37.6991" in out  # 360 rpm
    assert "stall" in out and "corner" in out and "no-load" in out


def test_show_an_unlimited_effort_stalls_at_inf(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """max_effort = inf without a speed line: the stall effort is inf (the table said 0)."""
    path = tmp_path / "e.toml"
    path.write_text('max_effort = "inf"\nmax_actuator_velocity = 3.0\n', encoding="utf-8")
    assert main(["envelope", "show", str(path)]) == 0
    out = capsys.readouterr().out
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines() if line}
    assert rows["stall"] == ["0", "inf"] and rows["no-load"] == ["3", "0"] and "both curves bind" not in out
    path.write_text('max_effort = "inf"\nmax_actuator_velocity = 3.0\nspeed_effort_gradient = 0.5\n')
    assert main(["envelope", "show", str(path)]) == 0
    rows = {line.split()[0]: line.split()[1:] for line in capsys.readouterr().out.splitlines() if line}
    assert rows["stall"] == ["0", "6"]  # the speed line reaches zero speed at 3 / 0.5


def test_show_json_round_trips(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Print JSON that reads back as the same envelope, inf included."""
    env = PerformanceEnvelope(max_effort=2.5, velocity_dependent_resistance=0.1, name="x")
    path = tmp_path / "e.toml"
    save_envelope(env, path)
    assert main(["envelope", "show", "--json", str(path)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["max_actuator_velocity"] == "inf"
    assert PerformanceEnvelope.from_dict(data) == env


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_save_load_round_trip(tmp_path: Path, suffix: str) -> None:
    """Write and read an envelope file without losing a bit."""
    env = PerformanceEnvelope(
        max_effort=1 / 3,
        max_actuator_velocity=math.pi,
        speed_effort_gradient=0.1,
        joint="prismatic",
        name='a "b"',
    )
    path = tmp_path / f"env{suffix}"
    save_envelope(env, path)
    assert load_envelope(path) == env
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temp file left


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("max_effort = [1", "malformed TOML"),
        (
            "max_effort = 1\nmax_velocity = 2\n",
            "unknown key 'max_velocity' (did you mean 'max_actuator_velocity'?)",
        ),
        ("max_effort = -2\n", "max_effort must be >= 0, got -2.0"),
        ('max_effort = "2 rpm"\n', "key 'max_effort'"),
        ('max_effort = 1\nmax_actuator_velocity = "3 Hz"\n', "angle unit"),
        ("joint = 'revolute'\n", "missing required key 'max_effort'"),
    ],
)
def test_bad_file_exits_2_with_one_line(tmp_path: Path, content: str, message: str) -> None:
    """Exit 2 with one line naming the file and the problem, no traceback."""
    path = tmp_path / "bad.toml"
    path.write_text(content)
    result = _run("envelope", "show", str(path))
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"drive-envelope: error: {path}")
    assert message in lines[0]


def test_missing_file_exits_2() -> None:
    """Name a missing file in a one-line error."""
    result = _run("envelope", "show", "nope.toml")
    assert result.returncode == 2
    assert result.stderr.strip() == "drive-envelope: error: nope.toml: no such file"


def test_atomic_write_keeps_mode_and_names_missing_folder(tmp_path: Path) -> None:
    """Give new files the umask mode, keep a replaced file's mode, and refuse a file as a folder."""
    import os
    import stat

    from drive_envelope import InputError
    from drive_envelope.io import atomic_write_text

    fresh = tmp_path / "new.txt"
    atomic_write_text(fresh, "a")
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o666 & ~mask
    fresh.chmod(0o640)
    atomic_write_text(fresh, "b")
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o640
    assert fresh.read_text() == "b"
    with pytest.raises(InputError, match=r"new\.txt' is a file, not a folder"):
        atomic_write_text(fresh / "x.txt", "c")


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["check", "--bogus"], "drive-envelope check: error: the following arguments are required"),
        (["fit", "x.csv", "--seed", "x"], "argument --seed: expected an integer >= 0, got 'x'"),
        (["nope"], "drive-envelope: error: argument COMMAND: invalid choice: 'nope'"),
        (  # was the top-level parser's: no suggestion, and `see drive-envelope --help`
            ["check", "e.toml", "log.csv", "--tolerence", "0.1"],
            "drive-envelope check: error: unrecognized arguments: --tolerence 0.1 (--tolerence: did you "
            "mean --tolerance?) (see drive-envelope check --help)",
        ),
        (
            ["mujoco", "show", "robot.xml", "--jsn"],
            "drive-envelope mujoco show: error: unrecognized arguments: --jsn (--jsn: did you mean --json?)",
        ),
        (["derive", "a", "b"], "drive-envelope derive: error: unrecognized arguments: b (see drive-envelope"),
        (  # argparse read it as --joint-column (replay's --joint picks a joint): no abbreviations
            ["check", "e.toml", "log.csv", "--joint", "elbow"],
            "drive-envelope check: error: unrecognized arguments: --joint elbow (--joint: did you mean "
            "--joint-column?)",
        ),
        (
            ["check", "e.toml", "log.csv", "--velocity-col", "v"],
            "unrecognized arguments: --velocity-col v (--velocity-col: did you mean --velocity-column?)",
        ),
    ],
)
def test_bad_flags_are_one_line_with_exit_2(
    argv: list[str], needle: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Print a bad flag as one line (no usage dump) pointing at --help, and return 2."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err and "--help)" in err


def test_integer_and_fraction_flag_types() -> None:
    """Read whole numbers (1e8 too) within bounds and fractions in [0, 1]; refuse the rest."""
    import argparse

    from drive_envelope._src.cli.common import fraction, integer_at_least

    count = integer_at_least(1, 10**9)
    assert count("12") == 12 and count("1e8") == 10**8 and count("+7") == 7
    for bad in ("0", "1.5", "x", "inf", "nan", "2e9", "1e400"):
        with pytest.raises(argparse.ArgumentTypeError, match=r"expected an integer in 1\.\.1000000000"):
            count(bad)
    assert integer_at_least(0)("123456789012345678901234567890") == 123456789012345678901234567890
    assert fraction("0") == 0.0 and fraction("1") == 1.0
    for bad in ("-0.1", "1.01", "nan", "x"):
        with pytest.raises(argparse.ArgumentTypeError, match=r"expected a fraction in \[0, 1\]"):
            fraction(bad)


class _Terminal:
    """A stream that says it is a terminal and records what is written."""

    def __init__(self, tty: bool) -> None:
        self.tty, self.text = tty, ""

    def isatty(self) -> bool:
        return self.tty

    def write(self, text: str) -> None:
        self.text += text

    def flush(self) -> None:
        pass


def test_progress_bar_draws_only_on_a_terminal_and_only_for_long_runs() -> None:
    """Draw nothing off a terminal or before the delay; on a terminal, one updating line ended by close."""
    from drive_envelope._src.cli.common import Progress

    piped = _Terminal(tty=False)
    bar = Progress("simulate", stream=piped, delay=0.0)  # type: ignore[arg-type]
    bar(5, 10)
    bar.close()
    assert piped.text == ""
    quick = _Terminal(tty=True)
    bar = Progress("simulate", stream=quick, delay=60.0)  # type: ignore[arg-type]
    bar(5, 10)
    bar.close()
    assert quick.text == ""  # a short run prints nothing
    tty = _Terminal(tty=True)
    bar = Progress("simulate", stream=tty, delay=0.0)  # type: ignore[arg-type]
    bar(5, 10)
    bar(6, 10)  # within 0.2 s of the last draw: skipped
    bar.close()
    assert tty.text.startswith("\rsimulate [###############...............]  50.0 % (5/10")
    assert tty.text.endswith("\n") and tty.text.count("\r") == 1


# standard output that closes early or fills up keeps the exit status (a new user's findings)

CORPUS = Path(__file__).resolve().parent / "corpus" / "good"
ENVELOPE = CORPUS / "envelope.toml"  # max_effort 10, v_max 5, R 0.5, G 0.2


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


def test_show_reads_a_datasheet_or_catalog_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """envelope show takes what plot and check take (a datasheet said "unknown key 'description'")."""
    assert main(["envelope", "show", "tmotor-ak80-6"]) == 0
    by_name = capsys.readouterr().out
    sheet = tmp_path / "ak80.toml"
    assert main(["catalog", "tmotor-ak80-6"]) == 0
    sheet.write_text(capsys.readouterr().out, encoding="utf-8")
    assert main(["envelope", "show", str(sheet)]) == 0
    assert capsys.readouterr().out == by_name
    assert by_name.startswith("T-Motor AK80-6 (revolute)") and "37.6991" in by_name


def test_a_scenario_for_an_envelope_and_back_is_named(capsys: pytest.CaptureFixture[str]) -> None:
    """Name the kind of file given (the messages were "unknown key 'drive'" / "unknown key 'max_effort'")."""
    root = Path(__file__).resolve().parents[1] / "examples"
    scenario, envelope_file = root / "scenarios" / "actuator_swing.toml", root / "envelopes" / "demo.toml"
    assert main(["check", str(scenario), str(scenario)]) == 2
    assert f"{scenario}: a scenario or stand file (its [drive] table), not an envelope file" in (
        capsys.readouterr().err
    )
    assert main(["simulate", str(envelope_file)]) == 2
    assert f"{envelope_file}: an envelope file (max_effort at the top level), not a scenario or stand" in (
        capsys.readouterr().err
    )

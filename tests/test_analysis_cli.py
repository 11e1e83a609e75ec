"""The `check` and `fit` commands: exit codes, JSON, envelope files, one-line errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import PerformanceEnvelope, load_envelope, save_envelope
from drive_envelope._src.cli.main import main

ENV = PerformanceEnvelope(
    max_effort=10.0,
    max_actuator_velocity=5.0,
    velocity_dependent_resistance=0.5,
    speed_effort_gradient=0.2,
    name="demo",
)


@pytest.fixture
def envelope_file(tmp_path: Path) -> Path:
    path = tmp_path / "env.toml"
    save_envelope(ENV, path)
    return path


def write_log(path: Path, rows: list[tuple[float, float, float]]) -> Path:
    lines = ["time,position,velocity,effort"] + [f"{t!r},0.0,{v!r},{e!r}" for t, v, e in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_check_passes_inside_and_prints_the_report(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Exit 0 and print per-joint margins for a log inside the envelope."""
    log = write_log(tmp_path / "log.csv", [(0.0, 0.0, 0.0), (0.1, 2.0, 9.0), (0.2, 4.0, 5.0)])
    assert main(["check", str(envelope_file), str(log)]) == 0
    out = capsys.readouterr().out
    assert "joint 'demo': 3 samples over 0.2 s, 0 outside" in out and "PASSED" in out


def test_check_fails_with_exit_1_and_json(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Exit 1 when violations exceed the tolerance; --json prints one object locating the worst."""
    log = write_log(
        tmp_path / "log.csv", [(0.0, 0.0, 0.0), (0.1, -3.0, 9.5), (0.2, 1.0, 1.0), (0.3, 1.0, 1.0)]
    )
    assert main(["check", str(envelope_file), str(log), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    joint = report["joints"][0]
    assert report["passed"] is False and joint["samples_outside"] == 1
    assert joint["effort"]["worst"]["time"] == 0.1 and joint["effort"]["worst"]["row"] == 2
    assert main(["check", str(envelope_file), str(log), "--tolerance", "0.25"]) == 0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("time,velocity\n0,1\n", "no column 'effort'"),
        ("time,velocity,effort\n0,1,2\n1,x,3\n", "row 2, column 'velocity'"),
        ("time,velocity,effort\n0,1,2\n1,nan,3\n", "row 2, column 'velocity'"),
        ("", "empty file"),
    ],
)
def test_check_malformed_log_exits_2_with_one_line(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str], text: str, message: str
) -> None:
    """Exit 2 with one 'drive-envelope: error:' line naming the row and column."""
    log = tmp_path / "bad.csv"
    log.write_text(text, encoding="utf-8")
    assert main(["check", str(envelope_file), str(log)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("drive-envelope: error:") and message in err and err.count("\n") == 1


def test_check_named_columns_and_joint_mapping(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Read renamed columns of a long-format log and apply a per-joint mapping file."""
    mapping = tmp_path / "joints.toml"
    mapping.write_text('[joints]\n"leg_*" = { max_effort = 2.0 }\n', encoding="utf-8")
    log = tmp_path / "robot.csv"
    log.write_text("stamp,name,qd,tau\n0,leg_l,0,1\n0,leg_r,0,3\n", encoding="utf-8")
    args = [
        "--time-column",
        "stamp",
        "--joint-column",
        "name",
        "--velocity-column",
        "qd",
        "--effort-column",
        "tau",
    ]
    assert main(["check", str(mapping), str(log), *args, "--json"]) == 1
    joints = {j["joint"]: j["samples_outside"] for j in json.loads(capsys.readouterr().out)["joints"]}
    assert joints == {"leg_l": 0, "leg_r": 1}
    assert main(["check", str(mapping), str(log), "--time-column", "time"]) == 2


@pytest.mark.plot
def test_check_writes_the_violation_plot(tmp_path: Path, envelope_file: Path) -> None:
    """Write the envelope plot with the violations highlighted."""
    log = write_log(tmp_path / "log.csv", [(0.0, 0.0, 0.0), (0.1, -3.0, 9.5), (0.2, 1.0, 1.0)])
    figure = tmp_path / "check.png"
    assert main(["check", str(envelope_file), str(log), "--plot", str(figure)]) == 1
    assert figure.stat().st_size > 0


def test_fit_json_and_output_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Print the four SI parameters with uncertainties and write an envelope file `envelope show` reads."""
    effort = np.linspace(0.0, ENV.stall_effort(), 300)
    velocity = ENV.velocity_at_effort(effort)
    log = write_log(
        tmp_path / "sweep.csv",
        [(0.01 * i, v, e) for i, (v, e) in enumerate(zip(velocity.tolist(), effort.tolist(), strict=True))],
    )
    out = tmp_path / "fitted.toml"
    assert (
        main(["fit", str(log), "--json", "--bootstrap", "10", "--output", str(out), "--name", "bench"]) == 0
    )
    data = json.loads(capsys.readouterr().out)
    for field in (
        "max_effort",
        "max_actuator_velocity",
        "velocity_dependent_resistance",
        "speed_effort_gradient",
    ):
        assert data[field] == pytest.approx(getattr(ENV, field), rel=1e-6)
        assert field in data["uncertainty"]
    assert load_envelope(out).name == "bench"
    assert main(["envelope", "show", str(out)]) == 0


def test_fit_from_curve_with_fixed_speed_limit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Fit a digitized curve given in rpm and mNm with --fix in vendor units."""
    points = tmp_path / "curve.csv"
    points.write_text(
        "speed [rpm],torque [mNm]\n0,800\n1000,780\n2000,760\n2800,400\n3000,0\n", encoding="utf-8"
    )
    assert (
        main(["fit", "--from-curve", str(points), "--fix", "max_actuator_velocity=3000 rpm", "--json"]) == 0
    )
    data = json.loads(capsys.readouterr().out)
    assert data["max_actuator_velocity"] == pytest.approx(3000 * 2 * math.pi / 60)
    assert data["status"]["max_actuator_velocity"] == "fixed"
    assert data["max_effort"] == pytest.approx(0.8) and data[
        "velocity_dependent_resistance"
    ] == pytest.approx(0.02 / (1000 * 2 * math.pi / 60))


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--fix", "max_torque=3"], "unknown parameter 'max_torque'"),
        (["--fix", "max_effort"], "expected NAME=VALUE"),
        (["--fix", "max_effort=3 rpm"], "--fix max_effort"),
        (["--outlier-quantile", "0.9"], "outlier-quantile"),
        (["--frontier-band", "0"], "--frontier-band: expected a fraction in (0, 1], got '0'"),
        (["--frontier-band", "1.5"], "--frontier-band: expected a fraction in (0, 1], got '1.5'"),
    ],
)
def test_fit_bad_arguments_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    """Exit 2 with one line naming the bad argument."""
    log = write_log(tmp_path / "sweep.csv", [(0.0, 1.0, 1.0), (0.1, 2.0, 1.0), (0.2, 3.0, 0.5)])
    assert main(["fit", str(log), *args]) == 2
    assert message in capsys.readouterr().err


def test_fit_report_names_the_samples_that_decided_each_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """List, in text and JSON, the samples on each line of a log whose interior dwarfs its frontier."""
    # ENV's corner: 10 - 0.5 v = (5 - v) / 0.2 -> v = 15 / 4.5; rows 2-11 accelerate on eq. 1,
    # rows 12-21 ride eq. 2, rows 22-101 lie well inside (60 % of the limit)
    corner = 15.0 / 4.5
    v1 = np.linspace(0.0, 0.9 * corner, 10)
    t2 = np.linspace(float(ENV.effort_limit(1.05 * corner)), 0.5, 10)
    inner = np.linspace(0.1, 4.5, 80)
    velocity = [*v1.tolist(), *ENV.velocity_at_effort(t2).tolist(), *inner.tolist()]
    effort = [*ENV.effort_limit(v1).tolist(), *t2.tolist(), *(0.6 * ENV.effort_limit(inner)).tolist()]
    log = write_log(
        tmp_path / "run.csv",
        [(0.0, 0.0, 0.0)]  # at rest: on no line
        + [(0.01 * (i + 1), v, e) for i, (v, e) in enumerate(zip(velocity, effort, strict=True))],
    )
    assert main(["fit", str(log), "--bootstrap", "0"]) == 0
    out = capsys.readouterr().out
    assert "lines, decided by the samples on them (within 1 % of the cap)" in out
    assert any(
        line.startswith("eq. 2 velocity  fitted") and line.endswith("12-21") for line in out.splitlines()
    )
    assert main(["fit", str(log), "--bootstrap", "0", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["lines"]["effort"]["samples"] == [[2, 11]] and data["lines"]["velocity"]["samples"] == [
        [12, 21]
    ]
    assert data["frontier"]["samples"] == 20  # the saturated rows, on the hull
    for field in (
        "max_effort",
        "max_actuator_velocity",
        "velocity_dependent_resistance",
        "speed_effort_gradient",
    ):
        assert data[field] == pytest.approx(getattr(ENV, field), rel=1e-9)


def test_fit_from_curve_writes_a_dc_motors_speed_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Write the no-load speed of a published DC motor curve into the envelope file (issue 18's C21)."""
    points = tmp_path / "c21.csv"
    points.write_text("speed [rpm],torque [oz-in]\n3780,0\n3360,38\n3117,60\n0,342\n", encoding="utf-8")
    out = tmp_path / "c21.toml"
    assert main(["fit", "--from-curve", str(points), "--json", "-o", str(out)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["velocity_dependent_resistance"] == 0.0
    assert data["status"]["max_actuator_velocity"] == "fitted"
    written = load_envelope(out)
    assert written.max_actuator_velocity == pytest.approx(3780 * 2 * math.pi / 60, rel=1e-4)
    assert written.max_effort == pytest.approx(342 * 0.45359237 / 16 * 9.80665 * 0.0254, rel=1e-9)


def test_check_reads_parquet(tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Check a Parquet log with the same columns as the simulate CSV."""
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    log = tmp_path / "log.parquet"
    pq.write_table(pa.table({"time": [0.0, 0.1], "velocity": [0.0, 6.0], "effort": [0.0, 1.0]}), log)
    assert main(["check", str(envelope_file), str(log), "--json"]) == 1
    velocity = json.loads(capsys.readouterr().out)["joints"][0]["velocity"]
    assert velocity["worst"]["excess"] == pytest.approx(1.2) and velocity["worst"]["row"] == 2


def test_check_reports_released_samples_in_text_and_json(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Count zero-effort samples past the no-load speed as released, apart from outside, in both formats."""
    # ENV: no-load speed 5 rad/s; rows 2-3 coast at 6 and 7 rad/s with zero effort, row 4 pushes at 6
    log = write_log(
        tmp_path / "log.csv", [(0.0, 0.0, 0.0), (0.1, 6.0, 0.0), (0.2, 7.0, 0.0), (0.3, 6.0, 0.5)]
    )
    assert main(["check", str(envelope_file), str(log), "--json"]) == 1
    joint = json.loads(capsys.readouterr().out)["joints"][0]
    assert (joint["samples_released"], joint["samples_outside"]) == (2, 1)
    assert joint["time_released"] == pytest.approx(0.2)
    assert main(["check", str(envelope_file), str(log)]) == 1
    out = capsys.readouterr().out
    assert "1 outside (25 %), 2 released -> FAIL" in out
    assert "released: 2 samples (0.2 s) above the speed line with zero effort" in out


def test_check_accepts_a_header_with_spaces(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Check 'time, velocity, effort' as written by hand or by 'a, b' formatting."""
    log = tmp_path / "log.csv"
    log.write_text("time, velocity, effort\n0.0, 1.0, 2.0\n0.1, 2.0, 3.0\n", encoding="utf-8")
    assert main(["check", str(envelope_file), str(log)]) == 0
    assert "2 samples over 0.1 s, 0 outside" in capsys.readouterr().out


CORPUS = Path(__file__).resolve().parent / "corpus" / "good"
ENVELOPE = CORPUS / "envelope.toml"  # max_effort 10, v_max 5, R 0.5, G 0.2


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

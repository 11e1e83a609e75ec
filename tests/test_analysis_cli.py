"""The `check` and `fit` commands: exit codes, JSON, envelope files, one-line errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from _bench_logs import run_cli
from _bench_logs import write_log as write_text_log
from drive_envelope import PerformanceEnvelope, load_envelope, save_envelope
from drive_envelope._src.cli.main import main
from drive_envelope.analysis import read_log
from drive_envelope.errors import InputError

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
        (["--fix", "max_effort=3", "--fix", "max_effort=4"], "--fix 'max_effort' given twice"),
        (  # float('1e400') was inf: a speed limit silently fixed at inf
            ["--fix", "max_actuator_velocity=1e400"],
            "--fix max_actuator_velocity: '1e400' is beyond the float range",
        ),
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


# bench logs of a new user: check and fit read header units, say when time goes back, warn when one
# sample decides a line

RPM = 2.0 * math.pi / 60.0  # rad/s per rev/min
UNITS_LOG = "time [s],velocity [rpm],effort [mNm]\n0,0,1000\n0.1,100,11000\n0.2,200,9000\n"
SI_LOG = f"time,velocity,effort\n0,0,1\n0.1,{100 * RPM!r},11\n0.2,{200 * RPM!r},9\n"


def one_line_error(code: int, err: str) -> str:
    assert code == 2 and err.startswith("drive-envelope: error:") and err.count("\n") == 1, err
    assert "Traceback" not in err
    return err


def test_fit_reads_header_units(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`fit` on a log in rpm and mNm gives the fit of the same log in SI, not 1000x the effort."""
    units = write_text_log(tmp_path / "units.csv", UNITS_LOG)
    si = write_text_log(tmp_path / "si.csv", SI_LOG)
    results = []
    for args in (
        [str(units)],
        [str(units), "--velocity-column", "velocity [rpm]", "--effort-column", "effort [mNm]"],
        [str(si)],
    ):
        code, out, _ = run_cli(["fit", *args, "--json", "--bootstrap", "0"], capsys)
        assert code == 0
        results.append(json.loads(out))
    for name in ("max_effort", "velocity_dependent_resistance"):
        assert results[0][name] == pytest.approx(results[2][name], rel=1e-12)
        assert results[1][name] == results[0][name]
    assert results[0]["max_effort"] < 12.0  # N*m: 11918 when the mNm were read as N*m


def test_check_reads_header_units(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`check` on a log in rpm and mNm reports what it reports for the same log in SI."""
    units = write_text_log(tmp_path / "units.csv", UNITS_LOG)
    si = write_text_log(tmp_path / "si.csv", SI_LOG)
    reports = []
    for log in (units, si):
        code, out, _ = run_cli(["check", str(bench_envelope_file), str(log), "--json"], capsys)
        reports.append((code, json.loads(out)["joints"][0]))
    (code_u, joint_u), (code_si, joint_si) = reports
    assert code_u == code_si == 0  # 11 N*m and 20.9 rad/s: inside 12 N*m and 40 rad/s
    assert joint_u["samples"] == 3 and joint_u["duration"] == pytest.approx(0.2)
    assert joint_u["effort"]["minimum"] == pytest.approx(joint_si["effort"]["minimum"], rel=1e-12)
    assert joint_u["effort"]["minimum"] == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("header", "fragment"),
    [
        ("time,velocity [N*m],effort", "column 'velocity [N*m]': unit 'N*m' is not an angular speed"),
        ("time,velocity [Hz],effort", "column 'velocity [Hz]': unit 'Hz' is not an angular speed"),
        ("time,velocity [blips],effort", "column 'velocity [blips]': unknown unit 'blips'"),
        ("time,velocity,effort [J]", "column 'effort [J]': unit 'J' is not a torque"),
        ("time [kg],velocity,effort", "column 'time [kg]': unit 'kg' is not a time"),
        (
            "time,velocity [mm/s],effort",
            "unit 'mm/s' is not an angular speed in rad/s (e.g. '3000 rpm'); "
            "it is the unit of a prismatic joint",
        ),
        ("time,velocity,velocity [rpm],effort", "column 'velocity' is ambiguous"),
    ],
)
def test_bad_header_units_are_one_line_errors(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str], header: str, fragment: str
) -> None:
    """A unit of the wrong dimension or an unknown one names the column and the unit, exit 2."""
    cells = ",".join(["1"] * len(header.split(",")))
    log = write_text_log(tmp_path / "bad.csv", f"{header}\n{cells}\n{cells}\n{cells}\n")
    commands = [["check", str(bench_envelope_file), str(log)], ["fit", str(log)]]
    for args in commands[:1] if header.startswith("time [") else commands:  # fit never reads the time
        err = one_line_error(*run_cli(args, capsys)[::2])
        assert fragment in err and str(log) in err


def test_prismatic_units_follow_the_joint_type(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """mm/s and N read for a prismatic fit and check; rpm with N (two joint types) is refused."""
    log = write_text_log(tmp_path / "lin.csv", "velocity [mm/s],effort [kN]\n0,0.1\n100,0.2\n200,0.15\n")
    code, out, _ = run_cli(["fit", str(log), "--joint", "prismatic", "--json", "--bootstrap", "0"], capsys)
    assert code == 0 and json.loads(out)["max_effort"] < 1000.0  # N, not kN read as N
    chunk = read_log(log)  # joint type from the units
    assert chunk.joint_type == "prismatic" and chunk.effort.tolist() == pytest.approx([100.0, 200.0, 150.0])
    env = tmp_path / "lin.toml"
    save_envelope(PerformanceEnvelope(max_effort=250.0, max_actuator_velocity=1.0, joint="prismatic"), env)
    assert run_cli(["check", str(env), str(log)], capsys)[0] == 0
    mixed = write_text_log(tmp_path / "mixed.csv", "velocity [rpm],effort [N]\n0,1\n1,2\n2,3\n")
    with pytest.raises(InputError, match="has the unit of a revolute joint but column 'effort \\[N\\]'"):
        read_log(mixed)


def test_curve_reader_keeps_reading_units_with_the_same_helper(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`fit --from-curve` reads `speed (rpm)` and refuses a torque unit on the speed column."""
    good = write_text_log(tmp_path / "curve.csv", "speed (rpm),torque (mNm)\n0,820\n2500,760\n5000,700\n")
    code, out, _ = run_cli(["fit", "--from-curve", str(good), "--json"], capsys)
    assert code == 0 and json.loads(out)["max_effort"] == pytest.approx(0.82)
    bad = write_text_log(tmp_path / "bad.csv", "speed [N*m],torque [mNm]\n0,820\n2500,760\n5000,700\n")
    err = one_line_error(*run_cli(["fit", "--from-curve", str(bad)], capsys)[::2])
    assert "column 'speed [N*m]': unit 'N*m' is not an angular speed" in err


def test_check_says_when_time_goes_back(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The user's log `0.2 / 0 / 0.1`: two episodes, 0.1 s (the jump back counts 0), row 2 named."""
    log = write_text_log(tmp_path / "unsorted.csv", "time,velocity,effort\n0.2,20,9\n0,0,1\n0.1,5,11\n")
    code, out, _ = run_cli(["check", str(bench_envelope_file), str(log)], capsys)
    assert code == 0
    assert "3 samples over 0.1 s in 2 episodes (time goes back 1 time(s), first at row 2)" in out
    code, out, _ = run_cli(["check", str(bench_envelope_file), str(log), "--json"], capsys)
    (joint,) = json.loads(out)["joints"]
    assert (joint["duration"], joint["time_resets"], joint["first_time_reset"]) == (pytest.approx(0.1), 1, 2)


def test_equal_times_are_one_episode(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Repeated time stamps are fine, and the span is last minus first."""
    log = write_text_log(tmp_path / "equal.csv", "time,velocity,effort\n0,0,1\n0,1,1\n0.1,2,2\n0.1,3,2\n")
    code, out, _ = run_cli(["check", str(bench_envelope_file), str(log)], capsys)
    assert code == 0 and "4 samples over 0.1 s," in out and "episodes" not in out


def test_fit_does_not_depend_on_time_order(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`fit` never reads the time, so a shuffled log fits as the sorted one does."""
    log = write_text_log(tmp_path / "unsorted.csv", "time,velocity,effort\n0.2,20,9\n0,0,1\n0.1,5,11\n")
    assert run_cli(["fit", str(log), "--bootstrap", "0"], capsys)[0] == 0


def _spike_log(path: Path) -> Path:
    """1e5 samples inside (9.2 N*m, 22.53 rad/s, R 0, G 2.44759), 2 % on the boundary, one spike."""
    rng = np.random.default_rng(0)
    cap, speed, gradient, n = 9.2, 22.53, 2.44759, 100_000
    v = rng.uniform(-speed, speed, n)
    e = rng.uniform(-cap, cap, n)
    outside = np.abs(v) > speed - gradient * np.abs(e)
    e[outside] = np.sign(e[outside]) * (speed - np.abs(v[outside])) / gradient * rng.uniform(0, 1, n)[outside]
    edge = rng.choice(n, n // 50, replace=False)
    x = rng.uniform(0.0, speed, edge.size)
    v[edge] = x * rng.choice([-1.0, 1.0], edge.size)
    e[edge] = np.where(x <= speed - gradient * cap, cap, (speed - x) / gradient) * np.sign(v[edge])
    v, e = np.append(v, 5.0), np.append(e, 50.0)
    rows = "".join(
        f"{t!r},{a!r},{b!r}\n"
        for t, a, b in zip((np.arange(n + 1) * 1e-3).tolist(), v.tolist(), e.tolist(), strict=True)
    )
    return write_text_log(path, "time,velocity,effort\n" + rows)


def test_fit_warns_when_a_spike_decides_a_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """One spike sets max_effort = 50 (unchanged); the report says so as a warning naming the row."""
    log = _spike_log(tmp_path / "spike.csv")
    code, out, _ = run_cli(["fit", str(log), "--bootstrap", "0", "--json"], capsys)
    assert code == 0
    result = json.loads(out)
    assert result["max_effort"] == 50.0  # the numbers are what they were
    warnings = [note for note in result["notes"] if note.startswith("warning: ")]
    assert len(warnings) == 1
    assert "eq. 1 (max_effort) rests on one sample, sample 100001" in warnings[0]
    assert "|effort| 50 N*m" in warnings[0] and "times the largest of all other samples" in warnings[0]
    assert "--outlier-quantile" in warnings[0]
    assert not any("no sample below" in note for note in result["notes"])  # ~half the log lies below
    assert any("no frontier sample below" in note for note in result["notes"])
    code, out, _ = run_cli(["fit", str(log), "--bootstrap", "0", "--outlier-quantile", "0.01"], capsys)
    assert code == 0 and "warning:" not in out
    assert (
        next(line for line in out.splitlines() if line.startswith("max_effort")).split()[1].startswith("9.2")
    )


def test_fit_text_prints_the_warning_as_a_warning_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """In text, the warning is its own `warning:` line, not a `note: warning:` one."""
    rows = [(0.0, 9.0), (1.0, 9.0), (2.0, 9.0), (3.0, 9.0), (4.0, 30.0), (5.0, 9.0), (6.0, 9.0)]
    log = write_text_log(tmp_path / "log.csv", "velocity,effort\n" + "".join(f"{v},{e}\n" for v, e in rows))
    code, out, _ = run_cli(["fit", str(log), "--bootstrap", "0"], capsys)
    assert code == 0
    warning = [line for line in out.splitlines() if line.startswith("warning: ")]
    assert len(warning) == 1
    assert (
        "eq. 1 (max_effort) rests on 2 samples, among them sample 5 (|velocity| 4 rad/s, |effort| 30 N*m)"
        in warning[0]
    )
    assert "3.33 times the largest of all other samples (9 N*m)" in warning[0]
    assert "note: warning" not in out


def test_fit_of_a_clean_sweep_and_of_a_curve_give_no_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Lines decided by many samples, and a datasheet curve's stall point, are not warned about."""
    speeds = np.linspace(0.0, 20.0, 41)
    efforts = np.minimum(10.0, (22.0 - speeds) / 0.5)
    log = write_text_log(
        tmp_path / "sweep.csv",
        "velocity,effort\n"
        + "".join(f"{v!r},{e!r}\n" for v, e in zip(speeds.tolist(), efforts.tolist(), strict=True)),
    )
    code, out, _ = run_cli(["fit", str(log), "--bootstrap", "0"], capsys)
    assert code == 0 and "warning" not in out
    curve_text = "speed [rpm],torque [oz-in]\n3780,0\n3360,38\n3117,60\n0,342\n"
    curve = write_text_log(tmp_path / "c21.csv", curve_text)
    code, out, _ = run_cli(["fit", "--from-curve", str(curve)], capsys)
    assert code == 0 and "warning" not in out


def test_a_row_with_too_many_fields_exits_2(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The user's log, through check and fit: one line naming the row."""
    log = write_text_log(tmp_path / "long.csv", "time,velocity,effort\n0,0,1\n0.1,5,11,7\n0.2,1,1\n")
    for args in (["check", str(bench_envelope_file), str(log)], ["fit", str(log)]):
        assert "row 2 (line 3): 4 fields" in one_line_error(*run_cli(args, capsys)[::2])


SCENARIOS = Path(__file__).resolve().parents[1] / "examples" / "scenarios"


def test_fit_output_cannot_be_its_log(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """fit RUN.json -o RUN.json (simulate's JSON trajectory) replaced the log with the envelope."""
    run = tmp_path / "run.json"
    assert main(["simulate", str(SCENARIOS / "velocity_saturation_tgs.toml"), "-o", str(run)]) == 0
    text = run.read_text(encoding="utf-8")
    assert main(["fit", str(run), "-o", str(run)]) == 2
    assert f"--output '{run}' is the log itself: write the envelope to a new file" in capsys.readouterr().err
    assert run.read_text(encoding="utf-8") == text

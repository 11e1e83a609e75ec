"""Bench-log findings of a new user (check, fit, plot -t): each is a regression test.

1. Units in column headers (``velocity [rpm]``) are converted to SI by the shared log reader.
2. Time that goes back (episodes) is counted and said; the jump back counts 0 s.
3. Fit notes count frontier samples; a line decided by one sample is a warning naming it.
4. ``plot -t`` draws a bench log without a position column.
5. CSV rows with too many fields and numbers beyond the float range are named precisely.
"""

from __future__ import annotations

import importlib.util
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import PerformanceEnvelope, save_envelope
from drive_envelope._src.analysis.log_units import column_scale, split_header
from drive_envelope._src.cli.main import main
from drive_envelope._src.scenario.trajectory import read_operating_log, read_trajectory
from drive_envelope.analysis import LogColumns, check_log, iter_log, read_log
from drive_envelope.errors import InputError

HAS_PYARROW = importlib.util.find_spec("pyarrow") is not None
ENGINES = [
    "python",
    pytest.param("pyarrow", marks=pytest.mark.skipif(not HAS_PYARROW, reason="needs pyarrow")),
]
RPM = 2.0 * math.pi / 60.0  # rad/s per rev/min

UNITS_LOG = "time [s],velocity [rpm],effort [mNm]\n0,0,1000\n0.1,100,11000\n0.2,200,9000\n"
SI_LOG = f"time,velocity,effort\n0,0,1\n0.1,{100 * RPM!r},11\n0.2,{200 * RPM!r},9\n"


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def envelope_file(tmp_path: Path) -> Path:
    path = tmp_path / "env.toml"
    save_envelope(PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=40.0, name="demo"), path)
    return path


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def one_line_error(code: int, err: str) -> str:
    assert code == 2 and err.startswith("drive-envelope: error:") and err.count("\n") == 1, err
    assert "Traceback" not in err
    return err


# -- 1. units in column headers ---------------------------------------------------------------------


@pytest.mark.parametrize("engine", ENGINES)
def test_header_units_are_converted_to_si(tmp_path: Path, engine: str) -> None:
    """`velocity [rpm]` and `effort [mNm]` are found by their names and read in rad/s and N*m."""
    chunk = read_log(write(tmp_path / "units.csv", UNITS_LOG), engine=engine)  # type: ignore[arg-type]
    np.testing.assert_allclose(chunk.velocity, [0.0, 100 * RPM, 200 * RPM], rtol=1e-15)
    np.testing.assert_allclose(chunk.effort, [1.0, 11.0, 9.0], rtol=1e-15)
    np.testing.assert_array_equal(chunk.time, [0.0, 0.1, 0.2])
    assert chunk.joint_type == "revolute"


@pytest.mark.parametrize("engine", ENGINES)
def test_header_units_degrees_milliseconds_and_parentheses(tmp_path: Path, engine: str) -> None:
    """deg/s, rpm in parentheses, ms and oz-in headers convert; the full header text selects too."""
    text = "time (ms),qd (deg/s),tau [oz-in]\n0,180,16\n500,360,32\n"
    path = write(tmp_path / "deg.csv", text)
    columns = LogColumns(velocity="qd", effort="tau [oz-in]")
    chunk = read_log(path, columns, engine=engine)  # type: ignore[arg-type]
    np.testing.assert_allclose(chunk.velocity, [math.pi, 2.0 * math.pi], rtol=1e-12)
    np.testing.assert_allclose(chunk.effort, [0.112984829, 0.225969658], rtol=1e-8)  # 1 ozf*in
    np.testing.assert_allclose(chunk.time, [0.0, 0.5], rtol=1e-15)


def test_position_units_share_the_one_implementation() -> None:
    """Position headers convert deg to rad and mm to m with the same helper the readers use."""
    assert split_header("position [deg]") == ("position", "deg")
    assert split_header("effort (N*m/(rad/s))") == ("effort", "N*m/(rad/s)")
    assert split_header("velocity [rpm] raw") == ("velocity [rpm] raw", "")
    assert column_scale("position", "deg", "revolute", "w")[0] == pytest.approx(math.pi / 180.0)
    assert column_scale("position", "mm", None, "w") == (pytest.approx(1e-3), "prismatic")
    assert column_scale("velocity", "rpm", None, "w") == (pytest.approx(RPM), "revolute")
    with pytest.raises(InputError, match=r"^w: unit 'N' is not an angle in rad"):
        column_scale("position", "N", "revolute", "w")


def test_parquet_header_units_are_converted(tmp_path: Path) -> None:
    """A Parquet log with unit headers reads as the CSV does."""
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    table = pa.table(
        {"time [s]": [0.0, 0.1, 0.2], "velocity [rpm]": [0.0, 100.0, 200.0], "effort [mNm]": [1e3, 11e3, 9e3]}
    )
    path = tmp_path / "units.parquet"
    pq.write_table(table, path, row_group_size=2)
    chunk = read_log(path)
    csv_chunk = read_log(write(tmp_path / "units.csv", UNITS_LOG))
    np.testing.assert_array_equal(chunk.velocity, csv_chunk.velocity)
    np.testing.assert_array_equal(chunk.effort, csv_chunk.effort)
    table_chunk = read_log({"velocity [deg/s]": [90.0, 180.0], "effort": [1.0, 2.0]})  # in memory too
    np.testing.assert_allclose(table_chunk.velocity, [math.pi / 2, math.pi])


def test_fit_reads_header_units(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`fit` on a log in rpm and mNm gives the fit of the same log in SI, not 1000x the effort."""
    units = write(tmp_path / "units.csv", UNITS_LOG)
    si = write(tmp_path / "si.csv", SI_LOG)
    results = []
    for args in (
        [str(units)],
        [str(units), "--velocity-column", "velocity [rpm]", "--effort-column", "effort [mNm]"],
        [str(si)],
    ):
        code, out, _ = run(["fit", *args, "--json", "--bootstrap", "0"], capsys)
        assert code == 0
        results.append(json.loads(out))
    for name in ("max_effort", "velocity_dependent_resistance"):
        assert results[0][name] == pytest.approx(results[2][name], rel=1e-12)
        assert results[1][name] == results[0][name]
    assert results[0]["max_effort"] < 12.0  # N*m: 11918 when the mNm were read as N*m


def test_check_reads_header_units(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`check` on a log in rpm and mNm reports what it reports for the same log in SI."""
    units = write(tmp_path / "units.csv", UNITS_LOG)
    si = write(tmp_path / "si.csv", SI_LOG)
    reports = []
    for log in (units, si):
        code, out, _ = run(["check", str(envelope_file), str(log), "--json"], capsys)
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
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str], header: str, fragment: str
) -> None:
    """A unit of the wrong dimension or an unknown one names the column and the unit, exit 2."""
    cells = ",".join(["1"] * len(header.split(",")))
    log = write(tmp_path / "bad.csv", f"{header}\n{cells}\n{cells}\n{cells}\n")
    commands = [["check", str(envelope_file), str(log)], ["fit", str(log)]]
    for args in commands[:1] if header.startswith("time [") else commands:  # fit never reads the time
        err = one_line_error(*run(args, capsys)[::2])
        assert fragment in err and str(log) in err


def test_prismatic_units_follow_the_joint_type(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """mm/s and N read for a prismatic fit and check; rpm with N (two joint types) is refused."""
    log = write(tmp_path / "lin.csv", "velocity [mm/s],effort [kN]\n0,0.1\n100,0.2\n200,0.15\n")
    code, out, _ = run(["fit", str(log), "--joint", "prismatic", "--json", "--bootstrap", "0"], capsys)
    assert code == 0 and json.loads(out)["max_effort"] < 1000.0  # N, not kN read as N
    chunk = read_log(log)  # joint type from the units
    assert chunk.joint_type == "prismatic" and chunk.effort.tolist() == pytest.approx([100.0, 200.0, 150.0])
    env = tmp_path / "lin.toml"
    save_envelope(PerformanceEnvelope(max_effort=250.0, max_actuator_velocity=1.0, joint="prismatic"), env)
    assert run(["check", str(env), str(log)], capsys)[0] == 0
    mixed = write(tmp_path / "mixed.csv", "velocity [rpm],effort [N]\n0,1\n1,2\n2,3\n")
    with pytest.raises(InputError, match="has the unit of a revolute joint but column 'effort \\[N\\]'"):
        read_log(mixed)


def test_curve_reader_keeps_reading_units_with_the_same_helper(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`fit --from-curve` reads `speed (rpm)` and refuses a torque unit on the speed column."""
    good = write(tmp_path / "curve.csv", "speed (rpm),torque (mNm)\n0,820\n2500,760\n5000,700\n")
    code, out, _ = run(["fit", "--from-curve", str(good), "--json"], capsys)
    assert code == 0 and json.loads(out)["max_effort"] == pytest.approx(0.82)
    bad = write(tmp_path / "bad.csv", "speed [N*m],torque [mNm]\n0,820\n2500,760\n5000,700\n")
    err = one_line_error(*run(["fit", "--from-curve", str(bad)], capsys)[::2])
    assert "column 'speed [N*m]': unit 'N*m' is not an angular speed" in err


# -- 2. time that goes back: episodes, counted and said ------------------------------------------


def test_check_says_when_time_goes_back(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The user's log `0.2 / 0 / 0.1`: two episodes, 0.1 s (the jump back counts 0), row 2 named."""
    log = write(tmp_path / "unsorted.csv", "time,velocity,effort\n0.2,20,9\n0,0,1\n0.1,5,11\n")
    code, out, _ = run(["check", str(envelope_file), str(log)], capsys)
    assert code == 0
    assert "3 samples over 0.1 s in 2 episodes (time goes back 1 time(s), first at row 2)" in out
    code, out, _ = run(["check", str(envelope_file), str(log), "--json"], capsys)
    (joint,) = json.loads(out)["joints"]
    assert (joint["duration"], joint["time_resets"], joint["first_time_reset"]) == (pytest.approx(0.1), 1, 2)


def test_equal_times_are_one_episode(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Repeated time stamps are fine, and the span is last minus first."""
    log = write(tmp_path / "equal.csv", "time,velocity,effort\n0,0,1\n0,1,1\n0.1,2,2\n0.1,3,2\n")
    code, out, _ = run(["check", str(envelope_file), str(log)], capsys)
    assert code == 0 and "4 samples over 0.1 s," in out and "episodes" not in out


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("chunk_rows", [1, 2, 3, 100])
def test_episodes_are_counted_across_chunk_boundaries(
    tmp_path: Path, envelope_file: Path, engine: str, chunk_rows: int
) -> None:
    """Three episodes of 0..3 s, 0..1 s, 0..2 s: 6 s in all, resets at rows 5 and 7, whatever the chunks."""
    times = [0, 1, 2, 3, 0, 1, 0, 1, 2]
    log = write(tmp_path / "log.csv", "time,velocity,effort\n" + "".join(f"{t},0,0\n" for t in times))
    (joint,) = check_log(envelope_file, log, chunk_rows=chunk_rows, engine=engine).joints
    assert (joint.duration, joint.time_resets, joint.first_time_reset) == (6.0, 2, 5)


@pytest.mark.parametrize("chunk_rows", [1, 2, 4, 100])
def test_episodes_are_per_joint_in_long_format_logs(
    tmp_path: Path, envelope_file: Path, chunk_rows: int
) -> None:
    """Joints that follow one another each start at 0: no episode; a drop within joint b is one."""
    rows = "a,0,1,1\na,1,1,1\nb,0,1,1\na,2,1,1\nb,1,1,1\nb,0.5,1,1\n"
    log = write(tmp_path / "long.csv", "joint,time,velocity,effort\n" + rows)
    a, b = check_log(envelope_file, log, chunk_rows=chunk_rows).joints
    assert (a.duration, a.time_resets) == (2.0, 0)
    assert (b.duration, b.time_resets, b.first_time_reset) == (1.0, 1, 6)


def test_fit_does_not_depend_on_time_order(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`fit` never reads the time, so a shuffled log fits as the sorted one does."""
    log = write(tmp_path / "unsorted.csv", "time,velocity,effort\n0.2,20,9\n0,0,1\n0.1,5,11\n")
    assert run(["fit", str(log), "--bootstrap", "0"], capsys)[0] == 0


# -- 3. fit notes and the one-sample warning -------------------------------------------------------


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
    return write(path, "time,velocity,effort\n" + rows)


def test_fit_warns_when_a_spike_decides_a_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """One spike sets max_effort = 50 (unchanged); the report says so as a warning naming the row."""
    log = _spike_log(tmp_path / "spike.csv")
    code, out, _ = run(["fit", str(log), "--bootstrap", "0", "--json"], capsys)
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
    code, out, _ = run(["fit", str(log), "--bootstrap", "0", "--outlier-quantile", "0.01"], capsys)
    assert code == 0 and "warning:" not in out
    assert (
        next(line for line in out.splitlines() if line.startswith("max_effort")).split()[1].startswith("9.2")
    )


def test_fit_text_prints_the_warning_as_a_warning_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """In text, the warning is its own `warning:` line, not a `note: warning:` one."""
    rows = [(0.0, 9.0), (1.0, 9.0), (2.0, 9.0), (3.0, 9.0), (4.0, 30.0), (5.0, 9.0), (6.0, 9.0)]
    log = write(tmp_path / "log.csv", "velocity,effort\n" + "".join(f"{v},{e}\n" for v, e in rows))
    code, out, _ = run(["fit", str(log), "--bootstrap", "0"], capsys)
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
    log = write(
        tmp_path / "sweep.csv",
        "velocity,effort\n"
        + "".join(f"{v!r},{e!r}\n" for v, e in zip(speeds.tolist(), efforts.tolist(), strict=True)),
    )
    code, out, _ = run(["fit", str(log), "--bootstrap", "0"], capsys)
    assert code == 0 and "warning" not in out
    curve = write(tmp_path / "c21.csv", "speed [rpm],torque [oz-in]\n3780,0\n3360,38\n3117,60\n0,342\n")
    code, out, _ = run(["fit", "--from-curve", str(curve)], capsys)
    assert code == 0 and "warning" not in out


# -- 4. plot -t of a bench log without position ---------------------------------------------------


def test_plot_draws_a_bench_log_without_position(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A log `check` reads (`time,velocity,effort`) is plotted; `velocity,effort` alone too."""
    pytest.importorskip("matplotlib")
    log = write(tmp_path / "bench.csv", "time,velocity,effort\n0,0,1\n0.1,5,11\n0.2,20,9\n")
    assert run(["check", str(envelope_file), str(log)], capsys)[0] == 0
    figure = tmp_path / "bench.png"
    code, _, err = run(["plot", str(envelope_file), "-t", str(log), "-o", str(figure)], capsys)
    assert code == 0 and figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", err
    bare = write(tmp_path / "bare.csv", "velocity,effort\n0,1\n5,11\n")
    assert (
        run(["plot", str(envelope_file), "-t", str(bare), "-o", str(tmp_path / "bare.png")], capsys)[0] == 0
    )


def test_operating_log_reader_keeps_the_trajectory_reader_strict(tmp_path: Path) -> None:
    """The plot's reader needs velocity and effort only; `read_trajectory` still needs position."""
    log = write(tmp_path / "bench.csv", "time,velocity,effort\n0,0,1\n0.1,5,11\n")
    points = read_operating_log(log)
    assert points.velocity.tolist() == [0.0, 5.0] and points.effort.tolist() == [1.0, 11.0]
    assert points.time is not None and points.time.tolist() == [0.0, 0.1] and points.name == "bench"
    assert read_operating_log(write(tmp_path / "bare.csv", "velocity,effort\n1,2\n")).time is None
    with pytest.raises(
        InputError, match="missing column\\(s\\) position; expected header time,position,velocity,effort"
    ):
        read_trajectory(log)
    with pytest.raises(InputError, match="missing column\\(s\\) effort"):
        read_operating_log(write(tmp_path / "no_effort.csv", "time,velocity\n0,1\n"))
    data = {"engine": "bench", "name": "swing", "velocity": [1.0, 2.0], "effort": [3.0, 4.0]}
    json_log = write(tmp_path / "bench.json", json.dumps(data))
    assert read_operating_log(json_log).name == "swing" and read_operating_log(json_log).time is None


# -- 5. CSV parse errors name the row -------------------------------------------------------------


@pytest.mark.parametrize("engine", ENGINES)
def test_a_row_with_too_many_fields_names_row_and_line(tmp_path: Path, engine: str) -> None:
    """`0.1,5,11,7` in a 3-column log: both readers name the data row and the line of the file."""
    log = write(tmp_path / "long.csv", "time,velocity,effort\n0,0,1\n0.1,5,11,7\n0.2,1,1\n")
    with pytest.raises(
        InputError, match=r"row 2 \(line 3\): 4 fields, the header has 3 \(time, velocity, effort\)"
    ):
        read_log(log, engine=engine)  # type: ignore[arg-type]
    shifted = write(tmp_path / "shifted.csv", "# bench\ntime,velocity,effort\n0,0,1\n\n0.1,5\n")
    with pytest.raises(InputError, match=r"row 2 \(line 5\): 2 fields, the header has 3"):
        read_log(shifted, engine=engine)  # type: ignore[arg-type]


def test_a_row_with_too_many_fields_exits_2(
    tmp_path: Path, envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The user's log, through check and fit: one line naming the row."""
    log = write(tmp_path / "long.csv", "time,velocity,effort\n0,0,1\n0.1,5,11,7\n0.2,1,1\n")
    for args in (["check", str(envelope_file), str(log)], ["fit", str(log)]):
        assert "row 2 (line 3): 4 fields" in one_line_error(*run(args, capsys)[::2])


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("chunk_rows", [1, 1000])
def test_a_number_beyond_the_float_range_is_named_as_written(
    tmp_path: Path, engine: str, chunk_rows: int
) -> None:
    """`1e400` is reported with its text (not only as inf); a written `inf` stays `got inf`."""
    log = write(tmp_path / "big.csv", "time,velocity,effort\n0,0,1\n0.1,-1e400,11\n")
    with pytest.raises(InputError, match=r"row 2, column 'velocity': got -inf \(the cell reads '-1e400'"):
        list(iter_log(log, chunk_rows=chunk_rows, engine=engine))  # type: ignore[arg-type]
    written = write(tmp_path / "inf.csv", "time,velocity,effort\n0,0,1\n0.1,inf,11\n")
    with pytest.raises(InputError, match=r"row 2, column 'velocity': got inf; expected a finite number"):
        read_log(written, engine=engine)  # type: ignore[arg-type]


# -- identify's bench logs read header units with the same code ------------------------------------


def test_bench_logs_read_header_units(tmp_path: Path) -> None:
    """``time [ms]``, ``position [deg]``, ``target_position (deg)``: SI in the BenchLog, like check."""
    from drive_envelope._src.identify.logs import read_bench_log

    si = write(tmp_path / "si.csv", "time,position,target_position\n0,0,0.5\n0.01,0.1,0.5\n0.02,0.2,0.5\n")
    degrees = [0.0, 0.1 * 180 / math.pi, 0.2 * 180 / math.pi]
    rows = "".join(f"{10 * i},{d!r},{0.5 * 180 / math.pi!r}\n" for i, d in enumerate(degrees))
    units = write(tmp_path / "units.csv", "time [ms],position [deg],target_position (deg)\n" + rows)
    a, b = read_bench_log(si), read_bench_log(units)
    for column in ("time", "position", "target_position"):
        np.testing.assert_allclose(getattr(b, column), getattr(a, column), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    ("header", "message"),
    [
        ("time,position [N*m],target_position", "column 'position [N*m]': unit 'N*m'"),
        ("time,position [deg],target_position [mm]", "the header units are of two joint types"),
        ("time,position,target_position,torque_enable [V]", "expected no unit (0 or 1 per sample)"),
    ],
)
def test_bench_log_unit_errors_are_one_line(tmp_path: Path, header: str, message: str) -> None:
    from drive_envelope._src.identify.logs import read_bench_log

    fields = header.count(",") + 1
    log = write(
        tmp_path / "bad.csv", header + "\n" + "".join(",".join(["1"] * fields) + "\n" for _ in range(3))
    )
    with pytest.raises(InputError, match=re.escape(message)) as caught:
        read_bench_log(log)
    assert "\n" not in str(caught.value)

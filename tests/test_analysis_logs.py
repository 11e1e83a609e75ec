"""Reading logs for the analysis: CSV (pyarrow and standard library), Parquet, tables, bad input."""

from __future__ import annotations

import gzip
import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest

from _bench_logs import write_log
from drive_envelope._src.analysis.log_model import log_plan
from drive_envelope._src.analysis.log_units import column_scale, split_header
from drive_envelope._src.cli.main import main
from drive_envelope.analysis import LogColumns, check_log, iter_log, read_log
from drive_envelope.errors import InputError

HAS_PYARROW = importlib.util.find_spec("pyarrow") is not None
ENGINES = [
    "python",
    pytest.param("pyarrow", marks=pytest.mark.skipif(not HAS_PYARROW, reason="needs pyarrow")),
]

SIMULATE_CSV = "time,position,velocity,effort\n0.0,0.0,0.0,0.0\n0.01,0.001,0.5,2.0\n0.02,0.004,-1.5,-3.25\n"


def write(tmp_path: Path, text: str, name: str = "log.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("engine", ENGINES)
def test_reads_the_simulate_csv_as_is(tmp_path: Path, engine: str) -> None:
    """Read the CSV of `drive-envelope simulate` with the default columns."""
    chunk = read_log(write(tmp_path, SIMULATE_CSV), engine=engine)  # type: ignore[arg-type]
    np.testing.assert_array_equal(chunk.velocity, [0.0, 0.5, -1.5])
    np.testing.assert_array_equal(chunk.effort, [0.0, 2.0, -3.25])
    np.testing.assert_array_equal(chunk.time, [0.0, 0.01, 0.02])
    assert chunk.joint is None


@pytest.mark.parametrize("engine", ENGINES)
def test_skips_comment_lines_and_blank_rows(tmp_path: Path, engine: str) -> None:
    """Skip leading '#' comment lines and blank lines."""
    text = "# engine: reference\n#\ntime,velocity,effort\n0,1,2\n\n1,3,4\n"
    chunk = read_log(write(tmp_path, text), engine=engine)  # type: ignore[arg-type]
    np.testing.assert_array_equal(chunk.velocity, [1.0, 3.0])


@pytest.mark.parametrize("engine", ENGINES)
def test_chunks_keep_joint_codes_stable(tmp_path: Path, engine: str) -> None:
    """Give a joint the same code in every chunk of a long-format log."""
    rows = "".join(f"{i},{'ab'[i % 2] if i < 4 else 'c'},{i},{-i}\n" for i in range(7))
    path = write(tmp_path, "time,joint,velocity,effort\n" + rows)
    chunks = list(iter_log(path, chunk_rows=2, engine=engine))  # type: ignore[arg-type]
    assert [c.first_row for c in chunks] == [1, 3, 5, 7]
    codes = np.concatenate([c.joint for c in chunks if c.joint is not None])
    names = chunks[-1].names
    assert [names[k] for k in codes] == ["a", "b", "a", "b", "c", "c", "c"]


def test_reads_gzip_and_tsv(tmp_path: Path) -> None:
    """Read gzip-compressed and tab-separated logs."""
    path = tmp_path / "log.tsv.gz"
    with gzip.open(path, "wt", encoding="utf-8") as handle:
        handle.write("velocity\teffort\n1\t2\n3\t4\n")
    for engine in ("python", "auto"):
        chunk = read_log(path, engine=engine)  # type: ignore[arg-type]
        np.testing.assert_array_equal(chunk.effort, [2.0, 4.0])


def test_reads_tables_of_arrays() -> None:
    """Accept a mapping of NumPy arrays with a joint column of strings."""
    table = {"velocity": np.array([1.0, 2.0]), "effort": [3, 4], "joint": np.array(["x", "y"])}
    chunk = read_log(table)
    assert chunk.names == ("x", "y")
    np.testing.assert_array_equal(chunk.joint, [0, 1])


def test_reads_parquet_with_custom_columns(tmp_path: Path) -> None:
    """Read a Parquet log with renamed columns and a dictionary joint column."""
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    table = pa.table(
        {
            "t": [0.0, 0.1, 0.2],
            "qd": [1.0, 2.0, 3.0],
            "tau": [4, 5, 6],
            "name": pa.array(["a", "b", "a"]).dictionary_encode(),
        }
    )
    path = tmp_path / "log.parquet"
    pq.write_table(table, path)
    columns = LogColumns(velocity="qd", effort="tau", time="t", joint="name")
    chunk = read_log(path, columns)
    np.testing.assert_array_equal(chunk.effort, [4.0, 5.0, 6.0])
    assert [chunk.names[k] for k in chunk.joint] == ["a", "b", "a"]  # type: ignore[union-attr]


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("time,velocity\n0,1\n", "no column 'effort'"),
        ("time,velocity,effort\n0,1,2\n1,abc,3\n", "row 2, column 'velocity': got 'abc'"),
        ("time,velocity,effort\n0,1,2\n1,2,3\n2,3,\n", "row 3, column 'effort': got an empty cell"),
        ("time,velocity,effort\n0,1,2\n1,nan,3\n", "row 2, column 'velocity': got an empty cell or NaN"),
        ("time,velocity,effort\n0,1,2\n1,inf,3\n", "row 2, column 'velocity': got inf"),
        ("", "empty file"),
        ("# only a comment\n", "empty file"),
        ("time,velocity,effort\n", "no data rows"),
    ],
)
def test_malformed_logs_name_the_row_and_column(tmp_path: Path, engine: str, text: str, message: str) -> None:
    """Raise one InputError naming the file, row and column of a malformed log."""
    path = write(tmp_path, text)
    with pytest.raises(InputError, match=message) as info:
        read_log(path, engine=engine)  # type: ignore[arg-type]
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_reports_the_earliest_bad_row_across_columns(tmp_path: Path) -> None:
    """Name the earliest bad row even when a later column is the one that fails."""
    path = write(tmp_path, "velocity,effort\n1,2\n2,\n,3\n")
    for engine in ("python", "auto"):
        with pytest.raises(InputError, match="row 2, column 'effort'"):
            read_log(path, engine=engine)  # type: ignore[arg-type]


def test_ragged_row_is_named(tmp_path: Path) -> None:
    """Report a row with too few fields by its number."""
    path = write(tmp_path, "time,velocity,effort\n0,1,2\n1,2\n")
    with pytest.raises(InputError, match="row 2"):
        read_log(path, engine="python")
    with pytest.raises(InputError, match=r"row 2|cannot read as CSV"):
        read_log(path)


def test_explicit_time_column_must_exist(tmp_path: Path) -> None:
    """Require a time column the user named, but not the default one."""
    path = write(tmp_path, "velocity,effort\n1,2\n")
    assert read_log(path).time is None
    with pytest.raises(InputError, match=r"no column 'stamp'.*--time-column"):
        read_log(path, LogColumns(time="stamp", require_time=True))


def test_missing_file_is_an_input_error(tmp_path: Path) -> None:
    """Report a missing log file in one line."""
    with pytest.raises(InputError, match="no such log file"):
        read_log(tmp_path / "absent.csv")


def test_reads_a_pyarrow_table_and_names_a_null_row() -> None:
    """Accept a pyarrow Table in memory and name the row of a null cell."""
    pa = pytest.importorskip("pyarrow")
    table = pa.table({"velocity": [1.0, 2.0, 3.0], "effort": [4.0, 5.0, 6.0]})
    np.testing.assert_array_equal(read_log(table).velocity, [1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="row 2, column 'effort'"):
        read_log(pa.table({"velocity": [1.0, 2.0], "effort": [4.0, None]}))


def test_parquet_with_text_column_is_refused(tmp_path: Path) -> None:
    """Refuse a Parquet column of strings where numbers are expected, naming it."""
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / "log.parquet"
    pq.write_table(pa.table({"velocity": ["fast"], "effort": [1.0]}), path)
    with pytest.raises(InputError, match="column 'velocity' has type string"):
        read_log(path)


@pytest.mark.parametrize("engine", ENGINES)
def test_spaces_around_column_names_are_ignored(tmp_path: Path, engine: str) -> None:
    """Read 'time, velocity, effort' (spaces after the commas) as the plain header."""
    path = write(tmp_path, "time, velocity , effort\n0, 1.5, 2\n0.1, -3 ,4\n")
    chunk = read_log(path, engine=engine)  # type: ignore[arg-type]
    np.testing.assert_array_equal(chunk.velocity, [1.5, -3.0])
    np.testing.assert_array_equal(chunk.time, [0.0, 0.1])


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(
    ("header", "message"),
    [
        (
            "time,velocity,velocity,effort",
            "column 'velocity' is ambiguous: the header has 'velocity' (column 2)",
        ),
        ("time,Velocity,velocity,effort", "column 'velocity' is ambiguous"),
        ("time, velocity,velocity ,effort", "column 'velocity' is ambiguous"),
        ("time,time,velocity,effort", "column 'time' is ambiguous"),
    ],
)
def test_a_column_named_twice_is_refused(tmp_path: Path, engine: str, header: str, message: str) -> None:
    """Refuse duplicate or case-ambiguous names of a column that is read (never pick the first)."""
    path = write(tmp_path, header + "\n0,1,100,1\n")
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        read_log(path, engine=engine)  # type: ignore[arg-type]


@pytest.mark.parametrize("engine", ENGINES)
def test_a_repeated_column_that_is_not_read_is_harmless(tmp_path: Path, engine: str) -> None:
    """Read a log whose unused columns repeat a name (bench loggers do that)."""
    path = write(tmp_path, "time,note,velocity,note,effort\n0,a,1,b,2\n")
    assert read_log(path, engine=engine).effort.tolist() == [2.0]  # type: ignore[arg-type]


def test_one_column_in_two_roles_is_refused(tmp_path: Path) -> None:
    """Refuse --velocity-column effort; let an explicit role take a default-named column."""
    path = write(tmp_path, SIMULATE_CSV)
    with pytest.raises(
        InputError, match="column 'effort' is named by both --velocity-column and --effort-column"
    ):
        read_log(path, LogColumns(velocity="effort"))
    chunk = read_log(path, LogColumns(velocity="time"))  # 'time' is velocity here, so no time column
    assert chunk.time is None and chunk.velocity.tolist() == [0.0, 0.01, 0.02]
    with pytest.raises(InputError, match="named by both --velocity-column and --time-column"):
        read_log(path, LogColumns(velocity="time", time="time", require_time=True))


def test_table_with_a_repeated_name_is_refused() -> None:
    """Refuse a DataFrame with two 'velocity' columns, as a CSV header."""
    pd = pytest.importorskip("pandas")
    frame = pd.DataFrame([[1.0, 2.0, 3.0]], columns=["velocity", "velocity", "effort"])
    with pytest.raises(InputError, match="column 'velocity' is ambiguous"):
        read_log(frame)


@pytest.mark.parametrize("engine", ENGINES)
def test_truncated_gzip_is_one_line(tmp_path: Path, engine: str) -> None:
    """Report a .gz cut short as unreadable, naming the file."""
    data = gzip.compress(("time,velocity,effort\n" + "0.5,1.0,2.0\n" * 20000).encode())
    path = tmp_path / "log.csv.gz"
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"log\.csv\.gz: cannot read") as info:
        read_log(path, engine=engine)  # type: ignore[arg-type]
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_header_field_over_the_csv_limit_is_one_line(tmp_path: Path, engine: str) -> None:
    """Refuse a header field over 131072 characters, naming the line; a long line is refused too."""
    path = write(tmp_path, "time,velocity,effort," + "x" * 140_000 + "\n0,1,2,3\n")
    with pytest.raises(InputError, match=r"line 1 \(the header\): field larger than field limit"):
        read_log(path, engine=engine)  # type: ignore[arg-type]
    path = write(tmp_path, "velocity,effort" + ",x" * 600_000 + "\n1,2\n")
    with pytest.raises(InputError, match="line 1 is longer than 1048576 characters"):
        read_log(path, engine=engine)  # type: ignore[arg-type]


def test_a_folder_is_not_a_log(tmp_path: Path) -> None:
    """Say a folder is a folder, not that it is missing."""
    with pytest.raises(InputError, match="is a folder"):
        read_log(tmp_path)


@pytest.mark.parametrize("engine", ENGINES)
def test_joint_names_are_read_without_outer_spaces(tmp_path: Path, engine: str) -> None:
    """Give ' hip' and 'hip' one code (the spaces came from 'a, b' formatting)."""
    path = write(tmp_path, "joint,velocity,effort\nhip,1,2\n hip ,3,4\nknee,5,6\n")
    chunk = read_log(path, engine=engine)  # type: ignore[arg-type]
    assert chunk.names == ("hip", "knee") and chunk.joint is not None
    assert chunk.joint.tolist() == [0, 0, 1]


# columns found up to case (a new user's findings): 'Velocity [RPM]', 'Time,Position,Velocity,Effort'


@pytest.mark.parametrize(
    "header",
    [
        "time,position,Velocity [RPM],effort",
        "Time,Position,Velocity [rpm],Effort",
        "TIME, VELOCITY [Rpm], EFFORT",
    ],
)
def test_columns_are_found_up_to_case_and_rpm_is_read(tmp_path: Path, header: str) -> None:
    """Find 'velocity' in 'Velocity [RPM]' and read the unit as rpm (the units parser's vendor spelling)."""
    ak = write(tmp_path, 'max_effort = "12 N*m"\nmax_actuator_velocity = "300 rpm"\n', "ak.toml")
    row = ["0.1", "100", "2"] if header.count(",") == 2 else ["0.1", "0", "100", "2"]
    log = write(tmp_path, header + "\n" + ",".join(row) + "\n", "c1.csv")
    (joint,) = check_log(ak, log).joints
    assert joint.samples == 1 and joint.velocity is not None
    assert joint.velocity.minimum == pytest.approx(200 * 2 * 3.141592653589793 / 60)  # 300 - 100 rpm


def test_plain_capitalised_header_checks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Check 'Time,Position,Velocity,Effort' (was: exit 2, no column 'velocity')."""
    ak = write(tmp_path, 'max_effort = "12 N*m"\n', "ak.toml")
    log = write(tmp_path, "Time,Position,Velocity,Effort\n0,0,1,1\n0.1,0,1,13\n", "c2.csv")
    assert main(["check", str(ak), str(log), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["joints"][0]["samples_outside"] == 1 and report["joints"][0]["duration"] == 0.1


def test_two_columns_up_to_case_stay_ambiguous_and_joint_column_too() -> None:
    """Refuse 'Velocity,velocity' as today; find a 'Joint' column by its whole header."""
    with pytest.raises(InputError, match="column 'velocity' is ambiguous"):
        log_plan(["time", "Velocity", "velocity", "effort"], LogColumns(), "log.csv")
    with pytest.raises(InputError, match="column 'velocity' is ambiguous"):
        log_plan(["velocity", "VELOCITY [rpm]", "effort"], LogColumns(), "log.csv")
    plan = log_plan(["Joint", "Velocity", "Effort"], LogColumns(), "log.csv")
    assert "joint" in plan and plan.position == {"joint": 0, "velocity": 1, "effort": 2}
    assert log_plan(["qd", "tau"], LogColumns(velocity="QD", effort="Tau"), "x").position == {
        "velocity": 0,
        "effort": 1,
    }


# bench logs of a new user: units in column headers, time that goes back (episodes), CSV rows named precisely

RPM = 2.0 * math.pi / 60.0  # rad/s per rev/min
UNITS_LOG = "time [s],velocity [rpm],effort [mNm]\n0,0,1000\n0.1,100,11000\n0.2,200,9000\n"


@pytest.mark.parametrize("engine", ENGINES)
def test_header_units_are_converted_to_si(tmp_path: Path, engine: str) -> None:
    """`velocity [rpm]` and `effort [mNm]` are found by their names and read in rad/s and N*m."""
    chunk = read_log(write_log(tmp_path / "units.csv", UNITS_LOG), engine=engine)  # type: ignore[arg-type]
    np.testing.assert_allclose(chunk.velocity, [0.0, 100 * RPM, 200 * RPM], rtol=1e-15)
    np.testing.assert_allclose(chunk.effort, [1.0, 11.0, 9.0], rtol=1e-15)
    np.testing.assert_array_equal(chunk.time, [0.0, 0.1, 0.2])
    assert chunk.joint_type == "revolute"


@pytest.mark.parametrize("engine", ENGINES)
def test_header_units_degrees_milliseconds_and_parentheses(tmp_path: Path, engine: str) -> None:
    """deg/s, rpm in parentheses, ms and oz-in headers convert; the full header text selects too."""
    text = "time (ms),qd (deg/s),tau [oz-in]\n0,180,16\n500,360,32\n"
    path = write_log(tmp_path / "deg.csv", text)
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
    csv_chunk = read_log(write_log(tmp_path / "units.csv", UNITS_LOG))
    np.testing.assert_array_equal(chunk.velocity, csv_chunk.velocity)
    np.testing.assert_array_equal(chunk.effort, csv_chunk.effort)
    table_chunk = read_log({"velocity [deg/s]": [90.0, 180.0], "effort": [1.0, 2.0]})  # in memory too
    np.testing.assert_allclose(table_chunk.velocity, [math.pi / 2, math.pi])


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("chunk_rows", [1, 2, 3, 100])
def test_episodes_are_counted_across_chunk_boundaries(
    tmp_path: Path, bench_envelope_file: Path, engine: str, chunk_rows: int
) -> None:
    """Three episodes of 0..3 s, 0..1 s, 0..2 s: 6 s in all, resets at rows 5 and 7, whatever the chunks."""
    times = [0, 1, 2, 3, 0, 1, 0, 1, 2]
    log = write_log(tmp_path / "log.csv", "time,velocity,effort\n" + "".join(f"{t},0,0\n" for t in times))
    (joint,) = check_log(bench_envelope_file, log, chunk_rows=chunk_rows, engine=engine).joints
    assert (joint.duration, joint.time_resets, joint.first_time_reset) == (6.0, 2, 5)


@pytest.mark.parametrize("chunk_rows", [1, 2, 4, 100])
def test_episodes_are_per_joint_in_long_format_logs(
    tmp_path: Path, bench_envelope_file: Path, chunk_rows: int
) -> None:
    """Joints that follow one another each start at 0: no episode; a drop within joint b is one."""
    rows = "a,0,1,1\na,1,1,1\nb,0,1,1\na,2,1,1\nb,1,1,1\nb,0.5,1,1\n"
    log = write_log(tmp_path / "long.csv", "joint,time,velocity,effort\n" + rows)
    a, b = check_log(bench_envelope_file, log, chunk_rows=chunk_rows).joints
    assert (a.duration, a.time_resets) == (2.0, 0)
    assert (b.duration, b.time_resets, b.first_time_reset) == (1.0, 1, 6)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_row_with_too_many_fields_names_row_and_line(tmp_path: Path, engine: str) -> None:
    """`0.1,5,11,7` in a 3-column log: both readers name the data row and the line of the file."""
    log = write_log(tmp_path / "long.csv", "time,velocity,effort\n0,0,1\n0.1,5,11,7\n0.2,1,1\n")
    with pytest.raises(
        InputError, match=r"row 2 \(line 3\): 4 fields, the header has 3 \(time, velocity, effort\)"
    ):
        read_log(log, engine=engine)  # type: ignore[arg-type]
    shifted = write_log(tmp_path / "shifted.csv", "# bench\ntime,velocity,effort\n0,0,1\n\n0.1,5\n")
    with pytest.raises(InputError, match=r"row 2 \(line 5\): 2 fields, the header has 3"):
        read_log(shifted, engine=engine)  # type: ignore[arg-type]


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("chunk_rows", [1, 1000])
def test_a_number_beyond_the_float_range_is_named_as_written(
    tmp_path: Path, engine: str, chunk_rows: int
) -> None:
    """`1e400` is reported with its text (not only as inf); a written `inf` stays `got inf`."""
    log = write_log(tmp_path / "big.csv", "time,velocity,effort\n0,0,1\n0.1,-1e400,11\n")
    with pytest.raises(InputError, match=r"row 2, column 'velocity': got -inf \(the cell reads '-1e400'"):
        list(iter_log(log, chunk_rows=chunk_rows, engine=engine))  # type: ignore[arg-type]
    written = write_log(tmp_path / "inf.csv", "time,velocity,effort\n0,0,1\n0.1,inf,11\n")
    with pytest.raises(InputError, match=r"row 2, column 'velocity': got inf; expected a finite number"):
        read_log(written, engine=engine)  # type: ignore[arg-type]

"""Trajectory files: CSV/JSON writers (atomic), readers and their errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import InputError
from drive_envelope._src.analysis.logs import read_log
from drive_envelope._src.scenario.trajectory import (
    Trajectory,
    read_operating_log,
    read_trajectory,
    save_trajectory,
    trajectory_to_csv,
    trajectory_to_json,
)


def sample() -> Trajectory:
    return Trajectory(
        time=np.array([0.0, 0.1, 0.2]),
        position=np.array([0.0, 0.01, 0.035]),
        velocity=np.array([0.0, 0.1, 0.25]),
        effort=np.array([0.0, 1.0 / 3.0, -2.5]),
        joint="prismatic",
        engine="reference",
        name="demo",
        metadata={"solver": "tgs"},
    )


def test_csv_has_the_specified_header_and_round_trips_exactly(tmp_path: Path) -> None:
    """CSV starts with time,position,velocity,effort; floats round-trip bit for bit."""
    path = tmp_path / "out.csv"
    save_trajectory(sample(), path)
    assert path.read_text().splitlines()[0] == "time,position,velocity,effort"
    back = read_trajectory(path, joint="prismatic")
    for column in ("time", "position", "velocity", "effort"):
        np.testing.assert_array_equal(getattr(back, column), getattr(sample(), column))
    assert back.units["effort"] == "N"


def test_json_keeps_metadata_and_units(tmp_path: Path) -> None:
    """JSON output holds the columns plus engine, joint, units and metadata."""
    path = tmp_path / "out.json"
    save_trajectory(sample(), path)
    data = json.loads(path.read_text())
    assert data["engine"] == "reference" and data["joint"] == "prismatic"
    assert data["units"]["velocity"] == "m/s"
    assert data["metadata"] == {"solver": "tgs"}
    back = read_trajectory(path)
    np.testing.assert_array_equal(back.effort, sample().effort)
    assert back.joint == "prismatic"


def test_format_argument_overrides_the_suffix(tmp_path: Path) -> None:
    """format='json' writes JSON even to a .csv name."""
    path = tmp_path / "out.csv"
    save_trajectory(sample(), path, format="json")
    assert json.loads(path.read_text())["name"] == "demo"


def test_empty_effort_cell_reads_as_zero(tmp_path: Path) -> None:
    """Row 0 with an empty effort cell (another engine's convention) reads as 0.0."""
    path = tmp_path / "x.csv"
    path.write_text("time,position,velocity,effort\n0,0,0,\n0.1,0.01,0.1,2.0\n")
    assert read_trajectory(path).effort.tolist() == [0.0, 2.0]


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("time,position,velocity\n0,0,0\n", "missing column(s) effort"),
        ("time,position,velocity,effort\n0,0,abc,0\n", "line 2, column 'velocity'"),
        ("time,position,velocity,effort\n", "no data rows"),
    ],
)
def test_bad_csv_files_are_reported_in_one_line(tmp_path: Path, text: str, needle: str) -> None:
    """A missing column, a non-number or an empty file gives one InputError line."""
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        read_trajectory(path)


def test_unequal_columns_are_refused() -> None:
    """Columns of different lengths raise InputError."""
    with pytest.raises(InputError, match="different lengths"):
        Trajectory(time=np.zeros(3), position=np.zeros(2), velocity=np.zeros(3), effort=np.zeros(3))


def test_failed_write_leaves_no_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A writer that fails midway leaves neither the target nor a temporary file."""
    import drive_envelope._src.scenario.trajectory as module

    def boom(trajectory: Trajectory, handle: object) -> None:
        handle.write("time,position\n0.0,")  # type: ignore[attr-defined]
        raise RuntimeError("disk full")

    monkeypatch.setattr(module, "write_trajectory_csv", boom)
    with pytest.raises(RuntimeError):
        module.save_trajectory(sample(), tmp_path / "out.csv")
    assert list(tmp_path.iterdir()) == []


def test_csv_text_has_one_row_per_sample() -> None:
    """trajectory_to_csv writes a header plus one row per sample."""
    assert len(trajectory_to_csv(sample()).splitlines()) == 4


def long_sample(rows: int = 70_001) -> Trajectory:
    rng = np.random.default_rng(5)
    return Trajectory(
        time=np.arange(rows) * 1e-3,
        position=rng.normal(size=rows),
        velocity=rng.normal(size=rows) * 1e-300,  # subnormal-adjacent values round-trip too
        effort=rng.normal(size=rows) * 1e300,
        engine="reference",
        name="long",
        metadata={"dt": 1e-3},
    )


@pytest.mark.parametrize("suffix", [".csv", ".json", ".parquet"])
def test_files_written_in_blocks_round_trip_exactly(tmp_path: Path, suffix: str) -> None:
    """Write more rows than one block in each format and read back every float bit for bit."""
    if suffix == ".parquet":
        pytest.importorskip("pyarrow")
    path = tmp_path / f"out{suffix}"
    save_trajectory(long_sample(), path)
    back = read_trajectory(path)
    for column in ("time", "position", "velocity", "effort"):
        np.testing.assert_array_equal(getattr(back, column), getattr(long_sample(), column))
    if suffix != ".csv":
        assert back.engine == "reference" and back.metadata == {"dt": 1e-3}
    assert [p.name for p in tmp_path.iterdir()] == [path.name]


def test_json_text_is_strict_json_with_the_header_first() -> None:
    """Write JSON that the standard library reads back with the same keys and values."""
    data = json.loads(trajectory_to_json(sample()))
    assert list(data) == [
        "engine",
        "name",
        "joint",
        "units",
        "metadata",
        "time",
        "position",
        "velocity",
        "effort",
    ]
    assert data["effort"] == [0.0, 1.0 / 3.0, -2.5]


def test_parquet_written_elsewhere_reads_as_a_revolute_trajectory(tmp_path: Path) -> None:
    """Read a Parquet file with the four columns and no drive-envelope metadata."""
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / "bench.parquet"
    pq.write_table(
        pa.table({"time": [0.0, 0.1], "position": [0, 1], "velocity": [0.5, 1.5], "effort": [0.0, 2.0]}), path
    )
    back = read_trajectory(path)
    assert back.joint == "revolute" and back.name == "bench" and back.position.tolist() == [0.0, 1.0]
    pq.write_table(pa.table({"time": [0.0], "velocity": [0.5], "effort": [0.0]}), path)
    with pytest.raises(InputError, match="missing column"):
        read_trajectory(path)


def test_unknown_output_suffix_is_refused(tmp_path: Path) -> None:
    """Refuse writing CSV text into a name whose suffix says another format."""
    with pytest.raises(InputError, match=r"unknown suffix '\.xlsx'"):
        save_trajectory(sample(), tmp_path / "out.xlsx")
    save_trajectory(sample(), tmp_path / "out.xlsx", format="csv")  # named explicitly: fine
    assert (tmp_path / "out.xlsx").read_text().startswith("time,")


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        (
            "time,position,velocity,effort\n0,0,nan,0\n",
            "line 2, column 'velocity': got 'nan'; expected a finite",
        ),
        ("time,position,velocity,effort\n0,0,0,-inf\n", "line 2, column 'effort': got '-inf'"),
        ("time,position,velocity,velocity,effort\n0,0,0,1,0\n", "column 'velocity' appears 2 times"),
    ],
)
def test_non_finite_cells_and_repeated_columns_are_refused(tmp_path: Path, text: str, needle: str) -> None:
    """Refuse NaN, inf and a repeated column: a plot would drop or mix them without a word."""
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=needle):
        read_trajectory(path)


def test_header_spaces_are_accepted_and_non_finite_arrays_refused(tmp_path: Path) -> None:
    """Read 'time, position, velocity, effort'; refuse a Trajectory holding NaN."""
    path = tmp_path / "spaced.csv"
    path.write_text("time, position, velocity, effort\n0, 0, 1.5, 2\n")
    assert read_trajectory(path).velocity.tolist() == [1.5]
    with pytest.raises(InputError, match=r"column 'velocity', row 1 is nan"):
        Trajectory(time=np.zeros(2), position=np.zeros(2), velocity=[0.0, np.nan], effort=np.zeros(2))


def _write_log(path: Path, text: str) -> Path:
    """Write a bench log as a new user types it."""
    path.write_text(text, encoding="utf-8")
    return path


def test_operating_log_reader_keeps_the_trajectory_reader_strict(tmp_path: Path) -> None:
    """plot -t reads a CSV log with check's reader (velocity, effort); read_trajectory needs position."""
    log = _write_log(tmp_path / "bench.csv", "time,velocity,effort\n0,0,1\n0.1,5,11\n")
    points = read_log(log)  # what plot -t reads a CSV log with (issue 29: one log reader)
    assert points.velocity.tolist() == [0.0, 5.0] and points.effort.tolist() == [1.0, 11.0]
    assert points.time is not None and points.time.tolist() == [0.0, 0.1]
    assert read_log(_write_log(tmp_path / "bare.csv", "velocity,effort\n1,2\n")).time is None
    with pytest.raises(
        InputError, match="missing column\\(s\\) position; expected header time,position,velocity,effort"
    ):
        read_trajectory(log)
    with pytest.raises(InputError, match="no column 'effort'"):
        read_log(_write_log(tmp_path / "no_effort.csv", "time,velocity\n0,1\n"))
    with pytest.raises(
        InputError, match="expected a JSON or Parquet trajectory; CSV logs go through read_log"
    ):
        read_operating_log(log)
    data = {"engine": "bench", "name": "swing", "velocity": [1.0, 2.0], "effort": [3.0, 4.0]}
    json_log = _write_log(tmp_path / "bench.json", json.dumps(data))
    assert read_operating_log(json_log).name == "swing" and read_operating_log(json_log).time is None

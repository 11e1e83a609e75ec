"""Reading logs of (velocity, effort) samples in bounded-memory chunks.

Sources: CSV files (``.csv``, ``.tsv``, ``.txt``, each optionally ``.gz``), Parquet files
(``.parquet``, ``.pq``), ROS 2 bags (a rosbag2 folder or its ``.mcap`` / ``.db3``, :mod:`.log_bag`;
``LogColumns.bag`` picks the topics), or an in-memory table: a mapping of column name to array, a pandas
DataFrame or a pyarrow Table. CSV goes through pyarrow's streaming reader when pyarrow is installed
and through the standard library's ``csv`` module otherwise; Parquet needs pyarrow. Leading lines
starting with ``#`` (metadata comments) and blank lines are skipped; spaces around column names are
ignored. A column name given twice (or twice up to case), or one column named for two roles, is an
error: a check must never read one of two ``velocity`` columns and ignore the other.

A column header may give the column's unit after its name, ``velocity [rpm]`` or ``effort (mNm)``
(:mod:`.log_units`): the column is found by its name or its whole header, and its values are
converted to SI; a unit unknown or of the wrong dimension is an error naming the column. Time must
never decrease within a joint (equal consecutive times are fine).

Rows are numbered from 1 = the first data row after the header; every error names the source, the
row and the column. Numbers in the chunks are SI: velocity [rad/s or m/s], effort [N*m or N], time [s].
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Literal

import numpy as np

from drive_envelope._src.analysis.log_arrow import iter_parquet, iter_table
from drive_envelope._src.analysis.log_bag import bag_table, is_bag, read_bag
from drive_envelope._src.analysis.log_csv import iter_csv_arrow, iter_csv_python
from drive_envelope._src.analysis.log_model import LogChunk, LogColumns
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import input_file

DEFAULT_CHUNK_ROWS = 1 << 19
"""Rows per chunk: about 16 MiB of float64 columns, so memory stays bounded for any file size."""

ReadEngine = Literal["auto", "pyarrow", "python"]

_PARQUET_SUFFIXES = (".parquet", ".pq")


def source_label(source: object) -> str:
    """Name of a log source for messages: the path, or ``<table>`` for in-memory data."""
    if isinstance(source, (str, os.PathLike)):
        return str(source)
    return "<table>"


def iter_log(
    source: Any,
    columns: LogColumns | None = None,
    *,
    chunk_rows: int = DEFAULT_CHUNK_ROWS,
    engine: ReadEngine = "auto",
) -> Iterator[LogChunk]:
    """Yield a log as validated chunks of at most ``chunk_rows`` rows.

    Args:
        source: A CSV or Parquet path, or an in-memory table (mapping of column -> array, pandas
            DataFrame, pyarrow Table).
        columns: Column names; the defaults match ``drive-envelope simulate``'s CSV.
        chunk_rows: Rows per chunk (memory bound), ``>= 1``.
        engine: CSV reader: ``"pyarrow"``, ``"python"`` (standard library) or ``"auto"`` (pyarrow
            when installed).

    Raises:
        InputError: missing file or column, a column named twice or used twice, a damaged file,
            non-numeric/empty/NaN/infinite cell (naming the row and column), a row with more or
            fewer fields than the header, a unit in a header that is unknown or of the wrong
            dimension, a time below the one before it (of the same joint), an empty log, or Parquet
            without pyarrow.
    """
    columns = columns or LogColumns()
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1:
        raise InputError(f"chunk_rows must be an integer >= 1, got {chunk_rows!r}")
    if engine not in ("auto", "pyarrow", "python"):
        raise InputError(f"engine: expected 'auto', 'pyarrow' or 'python', got {engine!r}")
    label = source_label(source)
    if isinstance(source, (str, os.PathLike)) and is_bag(source):  # a ROS 2 bag: one long table
        chunks = iter_table(bag_table(read_bag(source, columns.bag)), columns, chunk_rows, label)
    elif isinstance(source, (str, os.PathLike)):
        path = input_file(source, label, max_bytes=None, what="log file")  # read in chunks: no size cap
        if path.suffix.lower() in _PARQUET_SUFFIXES:
            chunks = iter_parquet(path, columns, chunk_rows, label)
        elif path.suffix.lower() == ".json":  # simulate's JSON trajectory (SI, standard column names)
            chunks = iter_table(_json_trajectory(path), columns, chunk_rows, label)
        elif _use_pyarrow(engine):
            chunks = iter_csv_arrow(path, columns, chunk_rows, label)
        else:
            chunks = iter_csv_python(path, columns, chunk_rows, label)
    else:
        chunks = iter_table(source, columns, chunk_rows, label)
    empty = True
    for chunk in chunks:
        if len(chunk):
            empty = False
            yield chunk
    if empty:
        raise InputError(f"{label}: the log has no data rows (expected a header line and rows of numbers)")


def _json_trajectory(path: Path) -> dict[str, Any]:
    """The ``time``, ``velocity`` and ``effort`` columns of a JSON trajectory (``simulate -o run.json``)."""
    from drive_envelope._src.scenario.trajectory import read_operating_log

    run = read_operating_log(path)
    table: dict[str, Any] = {"velocity": run.velocity, "effort": run.effort}
    if run.time is not None:
        table["time"] = run.time
    return table


def read_log(source: Any, columns: LogColumns | None = None, *, engine: ReadEngine = "auto") -> LogChunk:
    """Read a whole log into one chunk (for fitting, where all samples are needed at once)."""
    parts = list(iter_log(source, columns, engine=engine))
    last = parts[-1]

    def join(name: str) -> Any:
        arrays = [getattr(part, name) for part in parts]
        return None if arrays[0] is None else np.concatenate(arrays)

    return LogChunk(
        velocity=join("velocity"),
        effort=join("effort"),
        time=join("time"),
        joint=join("joint"),
        names=last.names,
        first_row=1,
        joint_type=last.joint_type,
    )


def _use_pyarrow(engine: ReadEngine) -> bool:
    # pyarrow's CSV engine stays, inside this one reader, because it measures ~12x faster on big logs:
    # 1e6 rows (62 MiB, simulate's columns), check_log 0.33 s with pyarrow vs 4.20 s with the csv
    # module (2-core machine; `benchmarks/bench_check.py --rows 1000000`, check-csv-python; issue 29).
    # The csv-module engine stays for installs without pyarrow (it is an optional extra).
    if engine == "python":
        return False
    try:
        import pyarrow.csv  # noqa: F401
    except ImportError:
        if engine == "pyarrow":
            raise InputError(
                "engine 'pyarrow' needs pyarrow (pip install 'drive-envelope[parquet]')"
            ) from None
        return False
    return True

"""Reading logs of (velocity, effort) samples in bounded-memory chunks.

Sources: CSV files (``.csv``, ``.tsv``, ``.txt``, each optionally ``.gz``), Parquet files
(``.parquet``, ``.pq``), or an in-memory table: a mapping of column name to array, a pandas
DataFrame or a pyarrow Table. CSV goes through pyarrow's streaming reader when pyarrow is installed
and through the standard library's ``csv`` module otherwise; Parquet needs pyarrow. Leading lines
starting with ``#`` (metadata comments) and blank lines are skipped.

Rows are numbered from 1 = the first data row after the header; every error names the source, the
row and the column. Numbers are SI: velocity [rad/s or m/s], effort [N*m or N], time [s].
"""

from __future__ import annotations

import contextlib
import csv
import gzip
import io
import itertools
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError

__all__ = [
    "DEFAULT_CHUNK_ROWS",
    "LogChunk",
    "LogColumns",
    "ReadEngine",
    "iter_log",
    "read_log",
    "source_label",
]

DEFAULT_CHUNK_ROWS = 1 << 19
"""Rows per chunk: about 16 MiB of float64 columns, so memory stays bounded for any file size."""

ReadEngine = Literal["auto", "pyarrow", "python"]
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

_PARQUET_SUFFIXES = (".parquet", ".pq")


@dataclass(frozen=True, kw_only=True, slots=True)
class LogColumns:
    """Which columns of a log hold what; the defaults are those of ``drive-envelope simulate``."""

    velocity: str = "velocity"
    """Joint velocity column [rad/s or m/s]."""
    effort: str = "effort"
    """Total actuator effort column [N*m or N]."""
    time: str | None = "time"
    """Time column [s], used when present (``None``: never); it locates violations in time."""
    joint: str | None = "joint"
    """Joint-name column of a long-format log with several joints, used when present."""
    require_time: bool = False
    """Raise when the time column is absent (set when the user named it explicitly)."""
    require_joint: bool = False
    """Raise when the joint column is absent (set when the user named it explicitly)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class LogChunk:
    """A block of consecutive log rows, converted to float64 SI arrays and validated finite."""

    velocity: FloatArray
    """Joint velocity [rad/s or m/s], shape ``(n,)``."""
    effort: FloatArray
    """Total actuator effort [N*m or N], shape ``(n,)``."""
    time: FloatArray | None
    """Time [s], shape ``(n,)``, or None when the log has no time column."""
    joint: IntArray | None
    """Joint code per row (an index into ``names``), or None for a single-joint log."""
    names: tuple[str, ...]
    """Joint names seen so far in the whole log; codes are stable across chunks."""
    first_row: int
    """Row number of the first row (1 = the first data row of the source)."""

    def __len__(self) -> int:
        return int(self.velocity.shape[0])


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
        InputError: missing file or column, non-numeric/empty/NaN/infinite cell (naming the row and
            column), an empty log, or Parquet without pyarrow.
    """
    columns = columns or LogColumns()
    if chunk_rows < 1:
        raise InputError(f"chunk_rows must be >= 1, got {chunk_rows!r}")
    label = source_label(source)
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if not path.is_file():
            raise InputError(f"{label}: no such file")
        if _is_parquet(path):
            chunks = _iter_parquet(path, columns, chunk_rows, label)
        elif _use_pyarrow(engine):
            chunks = _iter_csv_arrow(path, columns, chunk_rows, label)
        else:
            chunks = _iter_csv_python(path, columns, chunk_rows, label)
    else:
        chunks = _iter_table(source, columns, chunk_rows, label)
    empty = True
    for chunk in chunks:
        if len(chunk):
            empty = False
            yield chunk
    if empty:
        raise InputError(f"{label}: the log has no data rows (expected a header line and rows of numbers)")


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
    )


# -- shared helpers -------------------------------------------------------------------------------


class _Plan:
    """The columns to read, resolved against a header: ``numeric`` (velocity, effort[, time])."""

    def __init__(self, available: Sequence[str], columns: LogColumns, label: str) -> None:
        present = set(available)

        def need(name: str, flag: str) -> str:
            if name not in present:
                raise InputError(
                    f"{label}: no column {name!r} (columns: {', '.join(available) or 'none'}); "
                    f"name it with {flag}"
                )
            return name

        self.velocity = need(columns.velocity, "--velocity-column")
        self.effort = need(columns.effort, "--effort-column")
        self.time = _optional(columns.time, columns.require_time, present, "--time-column", need)
        self.joint = _optional(columns.joint, columns.require_joint, present, "--joint-column", need)
        self.numeric = [self.velocity, self.effort] + ([self.time] if self.time else [])
        self.wanted = self.numeric + ([self.joint] if self.joint else [])


def _optional(name: str | None, required: bool, present: set[str], flag: str, need: Any) -> str | None:
    if name is None:
        return None
    if name in present:
        return name
    return need(name, flag) if required else None


class _JointCodes:
    """Stable integer codes for joint names across chunks."""

    def __init__(self) -> None:
        self.codes: dict[str, int] = {}

    def encode(self, names: Sequence[str], indices: npt.NDArray[Any]) -> IntArray:
        """Codes for ``names[indices]`` (a dictionary-encoded column)."""
        lookup = np.array(
            [self.codes.setdefault(str(name), len(self.codes)) for name in names], dtype=np.intp
        )
        return lookup[np.asarray(indices, dtype=np.intp)] if lookup.size else np.zeros(0, dtype=np.intp)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.codes)


def _first_nonfinite(values: FloatArray) -> int | None:
    """Index of the first NaN (empty cells read as NaN) or inf, or None."""
    with np.errstate(over="ignore", invalid="ignore"):
        total = float(np.sum(values))
    if math.isfinite(total):  # one pass, no temporary: a NaN or inf anywhere makes the sum non-finite
        return None
    bad = np.flatnonzero(~np.isfinite(values))
    return int(bad[0]) if bad.size else None


def _check_finite(arrays: dict[str, FloatArray], label: str, first_row: int) -> None:
    """Refuse NaN and inf cells, naming the earliest bad row (and its column)."""
    found = [
        (index, name) for name, values in arrays.items() if (index := _first_nonfinite(values)) is not None
    ]
    if found:
        index, name = min(found)
        value = float(arrays[name][index])
        what = "an empty cell or NaN" if math.isnan(value) else repr(value)
        raise InputError(
            f"{label}: row {first_row + index}, column {name!r}: got {what}; expected a finite number"
        )


def _make_chunk(
    plan: _Plan,
    arrays: dict[str, FloatArray],
    joint: IntArray | None,
    codes: _JointCodes,
    first_row: int,
    label: str,
) -> LogChunk:
    _check_finite({name: arrays[name] for name in plan.numeric}, label, first_row)
    return LogChunk(
        velocity=arrays[plan.velocity],
        effort=arrays[plan.effort],
        time=arrays[plan.time] if plan.time else None,
        joint=joint,
        names=codes.names,
        first_row=first_row,
    )


def _is_parquet(path: Path) -> bool:
    return path.suffix.lower() in _PARQUET_SUFFIXES


def _use_pyarrow(engine: ReadEngine) -> bool:
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


# -- CSV ------------------------------------------------------------------------------------------


def _open_text(path: Path) -> io.TextIOBase:
    if path.suffix.lower() == ".gz":
        return io.TextIOWrapper(gzip.open(path, "rb"), encoding="utf-8-sig", newline="")
    return open(path, encoding="utf-8-sig", newline="")  # the caller closes it (with-block); -sig: skip a BOM


def _csv_header(path: Path, label: str) -> tuple[int, list[str], str]:
    """Return (lines before the header, header names, delimiter); comments and blanks are skipped."""
    skip = 0
    try:
        with _open_text(path) as handle:
            for line in handle:
                stripped = line.strip()
                if stripped and not stripped.startswith("#"):
                    delimiter = max((",", ";", "\t"), key=stripped.count)
                    header = [name.strip() for name in next(csv.reader([stripped], delimiter=delimiter))]
                    return skip, header, delimiter
                skip += 1
    except (OSError, UnicodeDecodeError, EOFError) as exc:
        raise InputError(f"{label}: cannot read: {exc}") from None
    raise InputError(f"{label}: empty file (expected a header line naming the columns, then rows of numbers)")


def _iter_csv_arrow(path: Path, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    import pyarrow as pa
    import pyarrow.csv as pacsv

    skip, header, delimiter = _csv_header(path, label)
    plan = _Plan(header, columns, label)
    types: dict[str, Any] = {name: pa.float64() for name in plan.numeric}
    if plan.joint:
        types[plan.joint] = pa.dictionary(pa.int32(), pa.string())
    # pyarrow reads about 35 blocks ahead of the consumer: 1 MiB blocks bound that to ~35 MiB
    # whatever the file size (larger blocks parse no faster); batches are cut to chunk_rows below
    block = 1 << 20
    codes = _JointCodes()
    row = 1
    try:
        reader = pacsv.open_csv(
            path,
            read_options=pacsv.ReadOptions(skip_rows=skip, block_size=block),
            parse_options=pacsv.ParseOptions(delimiter=delimiter),
            convert_options=pacsv.ConvertOptions(include_columns=plan.wanted, column_types=types),
        )
        for block_batch in reader:
            for start in range(0, block_batch.num_rows, chunk_rows):  # blocks are sized in bytes: cut to rows
                batch = block_batch.slice(start, chunk_rows)
                arrays = {name: batch.column(name).to_numpy(zero_copy_only=False) for name in plan.numeric}
                joint = (
                    _arrow_joint(batch.column(plan.joint), codes, label, plan.joint, row)
                    if plan.joint
                    else None
                )
                yield _make_chunk(plan, arrays, joint, codes, row, label)
                row += batch.num_rows
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
        # pyarrow's message has no reliable row number: rescan with the standard library for one
        for _ in _iter_csv_python(path, columns, chunk_rows, label):
            pass
        raise InputError(f"{label}: cannot read as CSV: {' '.join(str(exc).split())}") from None


def _iter_csv_python(path: Path, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    skip, header, delimiter = _csv_header(path, label)
    plan = _Plan(header, columns, label)
    index = {name: header.index(name) for name in plan.wanted}
    width = max(index.values()) + 1
    codes = _JointCodes()
    row = 1
    with _open_text(path) as handle:
        for _ in range(skip + 1):
            handle.readline()
        reader = csv.reader(handle, delimiter=delimiter)
        while True:
            try:
                block = [fields for fields in itertools.islice(reader, chunk_rows) if fields]
            except (csv.Error, UnicodeDecodeError, OSError, EOFError) as exc:
                raise InputError(
                    f"{label}: cannot read near row {row}: {' '.join(str(exc).split())}"
                ) from None
            if not block:
                return
            for offset, fields in enumerate(block):
                if len(fields) < width:
                    raise InputError(
                        f"{label}: row {row + offset}: {len(fields)} fields, the header has {len(header)} "
                        f"({', '.join(header)})"
                    )
            arrays = _parse_block(block, index, plan, label, row)
            joint = None
            if plan.joint:
                names, inverse = np.unique(
                    [fields[index[plan.joint]].strip() for fields in block], return_inverse=True
                )
                joint = codes.encode(list(names), inverse)
            yield _make_chunk(plan, arrays, joint, codes, row, label)
            row += len(block)


def _parse_floats(block: list[list[str]], column: int) -> tuple[FloatArray, tuple[int, str] | None]:
    """Column ``column`` of ``block`` as floats, and (offset, cell) of the first unreadable cell."""
    cells = [fields[column] for fields in block]
    try:
        return np.array(cells, dtype=np.float64), None
    except ValueError:
        for offset, cell in enumerate(cells):
            try:
                float(cell)
            except ValueError:
                return np.zeros(0), (offset, cell)
        raise


def _parse_block(
    block: list[list[str]], index: dict[str, int], plan: _Plan, label: str, first_row: int
) -> dict[str, FloatArray]:
    """The numeric columns of a block of CSV rows; an unreadable cell raises, naming the earliest."""
    arrays: dict[str, FloatArray] = {}
    bad: list[tuple[int, str, str]] = []
    for name in plan.numeric:
        arrays[name], problem = _parse_floats(block, index[name])
        if problem is not None:
            bad.append((problem[0], name, problem[1]))
    if bad:
        offset, name, cell = min(bad)
        what = "an empty cell" if not cell.strip() else repr(cell)
        raise InputError(f"{label}: row {first_row + offset}, column {name!r}: got {what}; expected a number")
    return arrays


# -- Parquet and pyarrow tables -------------------------------------------------------------------


def _arrow_numeric(column: Any, name: str, label: str) -> FloatArray:
    import pyarrow as pa

    kind = column.type
    if isinstance(column, pa.ChunkedArray):
        column = column.combine_chunks()
    if not (pa.types.is_floating(kind) or pa.types.is_integer(kind) or pa.types.is_decimal(kind)):
        raise InputError(f"{label}: column {name!r} has type {kind}; expected numbers")
    if pa.types.is_decimal(kind):
        column = column.cast(pa.float64())
    return np.asarray(column.to_numpy(zero_copy_only=False), dtype=np.float64)


def _arrow_joint(column: Any, codes: _JointCodes, label: str, name: str, first_row: int) -> IntArray:
    import pyarrow as pa

    if isinstance(column, pa.ChunkedArray):
        column = column.combine_chunks()
    if column.null_count:
        bad = int(np.flatnonzero(column.is_null().to_numpy(zero_copy_only=False))[0])
        raise InputError(f"{label}: row {first_row + bad}, column {name!r}: empty joint name")
    if not pa.types.is_dictionary(column.type):
        column = column.dictionary_encode()
    names = [str(value) for value in column.dictionary.to_pylist()]
    return codes.encode(names, column.indices.to_numpy(zero_copy_only=False))


def _iter_parquet(path: Path, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise InputError(
            f"{label}: Parquet logs need pyarrow (pip install 'drive-envelope[parquet]')"
        ) from None
    try:
        # pre-buffering keeps every row group read so far in memory: off, to stream in bounded memory
        handle = pq.ParquetFile(path, pre_buffer=False, buffer_size=1 << 22)
    except (pa.ArrowException, OSError) as exc:
        raise InputError(f"{label}: cannot read as Parquet: {' '.join(str(exc).split())}") from None
    with contextlib.closing(handle):
        plan = _Plan(handle.schema_arrow.names, columns, label)
        codes = _JointCodes()
        row = 1
        for batch in handle.iter_batches(batch_size=chunk_rows, columns=plan.wanted):
            arrays = {name: _arrow_numeric(batch.column(name), name, label) for name in plan.numeric}
            joint = (
                _arrow_joint(batch.column(plan.joint), codes, label, plan.joint, row) if plan.joint else None
            )
            yield _make_chunk(plan, arrays, joint, codes, row, label)
            row += batch.num_rows


def _table_names(table: Any) -> list[str]:
    if isinstance(table, Mapping):
        return [str(key) for key in table]
    for attribute in ("column_names", "columns"):  # pyarrow Table, pandas DataFrame
        names = getattr(table, attribute, None)
        if names is not None:
            return [str(name) for name in names]
    raise InputError(
        "expected a log path or a table of columns (mapping, DataFrame, pyarrow Table), "
        f"got {type(table).__name__}"
    )


def _table_column(table: Any, name: str) -> Any:
    if hasattr(table, "column_names") and hasattr(table, "column"):
        return table.column(name)
    return table[name]


def _iter_table(table: Any, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    plan = _Plan(_table_names(table), columns, label)
    arrays = {name: _table_numeric(_table_column(table, name), name, label) for name in plan.numeric}
    lengths = {name: values.shape for name, values in arrays.items()}
    if len(set(lengths.values())) != 1 or len(next(iter(lengths.values()))) != 1:
        raise InputError(f"{label}: columns must be 1-D and of equal length, got shapes {lengths}")
    codes = _JointCodes()
    joint = None
    if plan.joint:
        raw = _table_column(table, plan.joint)
        if hasattr(raw, "dictionary_encode") or type(raw).__module__.startswith("pyarrow"):
            joint = _arrow_joint(raw, codes, label, plan.joint, 1)
        else:
            names, inverse = np.unique(np.asarray(raw).astype(str), return_inverse=True)
            joint = codes.encode(list(names), inverse)
        if joint.shape != next(iter(lengths.values())):
            raise InputError(
                f"{label}: column {plan.joint!r} has {joint.shape[0]} rows, the others {lengths}"
            )
    total = len(arrays[plan.velocity])
    for start in range(0, total, chunk_rows):
        part = {name: values[start : start + chunk_rows] for name, values in arrays.items()}
        part_joint = None if joint is None else joint[start : start + chunk_rows]
        yield _make_chunk(plan, part, part_joint, codes, start + 1, label)


def _table_numeric(values: Any, name: str, label: str) -> FloatArray:
    if type(values).__module__.startswith("pyarrow"):
        return _arrow_numeric(values, name, label)
    try:
        return np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        for offset, value in enumerate(np.asarray(values, dtype=object).ravel()):
            try:
                float(value)
            except (TypeError, ValueError):
                raise InputError(
                    f"{label}: row {offset + 1}, column {name!r}: got {value!r}; expected a number"
                ) from None
        raise

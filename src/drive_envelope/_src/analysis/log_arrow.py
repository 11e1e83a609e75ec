"""Parquet logs (``.parquet``, ``.pq``; need pyarrow) and in-memory tables, read in chunks.

A table is a mapping of column name to array, a pandas DataFrame or a pyarrow Table. Column names
go through the same :func:`~drive_envelope._src.analysis.log_model.log_plan` as a CSV header
(a name twice, or one column in two roles, is an error).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.columns import ColumnPlan
from drive_envelope._src.analysis.log_model import JointCodes, LogChunk, LogColumns, log_plan, make_chunk
from drive_envelope._src.errors import InputError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]


def one_line(exc: BaseException) -> str:
    """A reader's error as one line of text (the CSV and Parquet readers' messages quote it)."""
    return " ".join(str(exc).split()) or type(exc).__name__


def arrow_numeric(column: Any, name: str, label: str) -> FloatArray:
    """A pyarrow column of numbers (float, integer, decimal) as float64, as written (no unit applied)."""
    import pyarrow as pa

    kind = column.type
    if isinstance(column, pa.ChunkedArray):
        column = column.combine_chunks()
    if not (pa.types.is_floating(kind) or pa.types.is_integer(kind) or pa.types.is_decimal(kind)):
        raise InputError(f"{label}: column {name!r} has type {kind}; expected numbers")
    if pa.types.is_decimal(kind):
        column = column.cast(pa.float64())
    return np.asarray(column.to_numpy(zero_copy_only=False), dtype=np.float64)


def arrow_joint(column: Any, codes: JointCodes, plan: ColumnPlan, first_row: int) -> IntArray:
    """Joint codes of a pyarrow column of names (plain or dictionary-encoded strings)."""
    import pyarrow as pa

    if isinstance(column, pa.ChunkedArray):
        column = column.combine_chunks()
    if column.null_count:
        bad = int(np.flatnonzero(column.is_null().to_numpy(zero_copy_only=False))[0])
        raise InputError(
            f"{plan.label}: row {first_row + bad}, column {plan.name('joint')!r}: empty joint name"
        )
    if not pa.types.is_dictionary(column.type):
        column = column.dictionary_encode()
    names = [str(value) for value in column.dictionary.to_pylist()]
    return codes.encode(names, column.indices.to_numpy(zero_copy_only=False), plan, first_row)


def iter_parquet(path: Path, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    """Chunks of a Parquet log, one row group batch at a time."""
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
        raise InputError(f"{label}: cannot read as Parquet: {one_line(exc)}") from None
    with contextlib.closing(handle):
        plan = log_plan(handle.schema_arrow.names, columns, label)
        names = {role: handle.schema_arrow.names[position] for role, position in plan.position.items()}
        codes = JointCodes()
        row = 1
        try:
            for batch in handle.iter_batches(batch_size=chunk_rows, columns=list(names.values())):
                arrays = {
                    role: arrow_numeric(batch.column(names[role]), plan.name(role), label)
                    for role in plan.numeric
                }
                joint = (
                    arrow_joint(batch.column(names["joint"]), codes, plan, row) if "joint" in plan else None
                )
                yield make_chunk(plan, arrays, joint, codes, row)
                row += batch.num_rows
        except (pa.ArrowException, OSError) as exc:  # a damaged row group
            raise InputError(f"{label}: cannot read near row {row}: {one_line(exc)}") from None


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


def _table_column(table: Any, position: int) -> Any:
    if hasattr(table, "column_names") and hasattr(table, "column"):
        return table.column(position)
    if isinstance(table, Mapping):
        return table[list(table)[position]]
    return table.iloc[:, position]  # a DataFrame: by position, so a name given twice stays unambiguous


def iter_table(table: Any, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    """Chunks of an in-memory table (mapping of arrays, DataFrame, pyarrow Table)."""
    plan = log_plan(_table_names(table), columns, label)
    arrays = {
        role: _table_numeric(_table_column(table, plan.position[role]), plan.name(role), label)
        for role in plan.numeric
    }
    lengths = {plan.name(role): values.shape for role, values in arrays.items()}
    shapes = set(lengths.values())
    if len(shapes) != 1 or len(next(iter(shapes))) != 1:
        raise InputError(f"{label}: columns must be 1-D and of equal length, got shapes {lengths}")
    total = len(arrays["velocity"])
    codes = JointCodes()
    joint = None
    if "joint" in plan:
        raw = _table_column(table, plan.position["joint"])
        if hasattr(raw, "dictionary_encode") or type(raw).__module__.startswith("pyarrow"):
            joint = arrow_joint(raw, codes, plan, 1)
        else:
            names, inverse = np.unique(np.asarray(raw).astype(str), return_inverse=True)
            joint = codes.encode(list(names), inverse.ravel(), plan, 1)
        if joint.shape != (total,):
            raise InputError(
                f"{label}: column {plan.name('joint')!r} has {joint.shape[0]} rows, the others {total}"
            )
    for start in range(0, total, chunk_rows):
        part = {role: values[start : start + chunk_rows] for role, values in arrays.items()}
        part_joint = None if joint is None else joint[start : start + chunk_rows]
        yield make_chunk(plan, part, part_joint, codes, start + 1)


def _table_numeric(values: Any, name: str, label: str) -> FloatArray:
    if type(values).__module__.startswith("pyarrow"):
        return arrow_numeric(values, name, label)
    try:
        return np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        for offset, value in enumerate(np.asarray(values, dtype=object).ravel()):
            try:
                float(value)
            except (TypeError, ValueError, OverflowError):
                raise InputError(
                    f"{label}: row {offset + 1}, column {name!r}: got {value!r}; expected a number"
                ) from None
        raise InputError(f"{label}: column {name!r}: expected a 1-D array of numbers") from None

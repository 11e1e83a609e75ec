"""Trajectories as Parquet files (needs pyarrow): float64 columns, the rest in the schema metadata.

The schema's metadata key ``drive_envelope`` holds the trajectory's header (engine, name, joint,
units, metadata) as JSON, so a Parquet trajectory reads back whole; ``check`` reads the same file
as a log. :mod:`~drive_envelope._src.scenario.trajectory` builds and unpacks the ``Trajectory``.
"""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from drive_envelope._src.errors import InputError
from drive_envelope._src.io.atomic import atomic_path
from drive_envelope._src.io.paths import input_file

METADATA_KEY = b"drive_envelope"
"""Schema metadata key of the trajectory's header (JSON)."""


def have_parquet() -> bool:
    """Whether pyarrow (with Parquet) is installed."""
    return importlib.util.find_spec("pyarrow") is not None


def _pyarrow(path: str | os.PathLike[str]) -> tuple[Any, Any]:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise InputError(
            f"{str(path)!r}: Parquet needs pyarrow (pip install 'drive-envelope[parquet]'); "
            "or write .csv or .json"
        ) from None
    return pa, pq


def write_parquet(
    columns: dict[str, Any], header: dict[str, Any], path: str | os.PathLike[str], *, force: bool = False
) -> None:
    """Write float64 ``columns`` (name -> array) and ``header`` (JSON-compatible) to ``path``, atomically.

    Raises:
        InputError: pyarrow is missing, or the file cannot be written.
    """
    pa, pq = _pyarrow(path)
    schema = pa.schema(
        [(column, pa.float64()) for column in columns],
        metadata={METADATA_KEY: json.dumps(header).encode("utf-8")},
    )
    table = pa.table(columns, schema=schema)
    with atomic_path(path, force=force) as tmp:
        pq.write_table(table, tmp)


def read_parquet(
    path: Path, names: tuple[str, ...], *, optional: tuple[str, ...] = ()
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Read columns ``names`` (as finite float64 arrays) and the header of a Parquet trajectory.

    Columns of ``optional`` are read too when the file has them.

    A file without the header (written elsewhere) gives ``{"joint": "revolute", "metadata": {}}``.

    Raises:
        InputError: pyarrow is missing, the file is unreadable, a column is missing or not
            numeric, or a value is not finite.
    """
    pa, pq = _pyarrow(path)
    input_file(path, max_bytes=None)  # a FIFO or a device is refused before pyarrow opens it
    try:
        schema = pq.read_schema(path)
        missing = [column for column in names if column not in schema.names]
        if missing:
            raise InputError(f"{path}: missing column(s) {', '.join(missing)}; expected {', '.join(names)}")
        names = names + tuple(column for column in optional if column in schema.names)
        repeated = [column for column in names if schema.names.count(column) > 1]
        if repeated:
            raise InputError(
                f"{path}: column {repeated[0]!r} appears {schema.names.count(repeated[0])} times"
            )
        table = pq.read_table(path, columns=list(names))
    except (pa.ArrowException, OSError) as exc:
        raise InputError(f"{path}: cannot read as Parquet: {' '.join(str(exc).split())}") from None
    arrays = {}
    for column in names:
        kind = table.schema.field(column).type
        if not (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
            raise InputError(f"{path}: column {column!r} has type {kind}; expected numbers")
        values = table.column(column)
        if values.null_count:
            raise InputError(f"{path}: column {column!r} has empty cells; expected a number in every row")
        arrays[column] = np.asarray(values.to_numpy(), dtype=np.float64)
        if not np.isfinite(arrays[column]).all():
            row = int(np.flatnonzero(~np.isfinite(arrays[column]))[0])
            raise InputError(
                f"{path}: row {row}, column {column!r}: got {float(arrays[column][row])!r}; "
                "expected a finite number"
            )
    return arrays, _header(schema.metadata or {}, path)


def _header(metadata: dict[bytes, bytes], path: Path) -> dict[str, Any]:
    raw = metadata.get(METADATA_KEY)
    if raw is None:  # a Parquet file from elsewhere: plain columns
        return {"joint": "revolute", "metadata": {}}
    try:
        header = json.loads(raw)
    except (ValueError, UnicodeDecodeError):
        raise InputError(f"{path}: metadata {METADATA_KEY.decode()!r} is not JSON") from None
    if not isinstance(header, dict) or header.get("joint", "revolute") not in ("revolute", "prismatic"):
        raise InputError(
            f"{path}: metadata {METADATA_KEY.decode()!r}: expected a joint of revolute or prismatic"
        )
    header.setdefault("joint", "revolute")
    return header

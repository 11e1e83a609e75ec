"""CSV logs (``.csv``, ``.tsv``, ``.txt``, each optionally ``.gz``), read in bounded-memory chunks.

Two readers give the same chunks: pyarrow's streaming reader (fast, when installed) and the
standard library's ``csv`` module. Leading ``#`` comment lines and blank lines are skipped; the
header is read here once, so both readers agree on the column names (spaces around names removed)
and on the rules of :func:`~drive_envelope._src.analysis.log_model.log_plan`. A damaged file (a
truncated ``.gz``, bytes that are not UTF-8, a field over :data:`FIELD_LIMIT` characters) is an
:class:`InputError` naming the file, and the row where one is known.
"""

from __future__ import annotations

import csv
import gzip
import io
import itertools
import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from drive_envelope._src.analysis.columns import ColumnPlan
from drive_envelope._src.analysis.log_arrow import arrow_joint, one_line
from drive_envelope._src.analysis.log_model import JointCodes, LogChunk, LogColumns, log_plan, make_chunk
from drive_envelope._src.errors import InputError

FIELD_LIMIT = csv.field_size_limit()
"""Longest field the standard library reads [characters] (131072): a longer one is an error."""

_LINE_LIMIT = 1 << 20  # longest comment or header line read [characters]: memory stays bounded
_READ_ERRORS = (OSError, EOFError, UnicodeDecodeError, zlib.error, csv.Error)  # a damaged or truncated file
_Source = tuple[Path, int, str]  # (path, lines before the header, delimiter): where to read a cell again


def _open_text(path: Path) -> io.TextIOBase:
    if path.suffix.lower() == ".gz":
        return io.TextIOWrapper(gzip.open(path, "rb"), encoding="utf-8-sig", newline="")
    return open(path, encoding="utf-8-sig", newline="")  # the caller closes it (with-block); -sig: skip a BOM


def _header_line(handle: io.TextIOBase, label: str) -> tuple[int, str]:
    """Return (lines before the header, the header line); comment and blank lines are skipped."""
    skip = 0
    while True:
        line = handle.readline(_LINE_LIMIT + 1)
        if not line:
            raise InputError(
                f"{label}: empty file (expected a header line naming the columns, then rows of numbers)"
            )
        if len(line) > _LINE_LIMIT:
            raise InputError(
                f"{label}: line {skip + 1} is longer than {_LINE_LIMIT} characters; "
                "expected a header line naming the columns"
            )
        stripped = line.strip()
        if stripped and not stripped.startswith("#"):
            return skip, stripped
        skip += 1


def csv_header(path: Path, label: str) -> tuple[int, list[str], str]:
    """Return (lines before the header, header names, delimiter) of a CSV log.

    Raises:
        InputError: an empty or unreadable file, or a header field over :data:`FIELD_LIMIT` characters.
    """
    try:
        with _open_text(path) as handle:
            skip, line = _header_line(handle, label)
    except _READ_ERRORS as exc:
        raise InputError(f"{label}: cannot read: {one_line(exc)}") from None
    delimiter = max((",", ";", "\t"), key=line.count)
    try:
        header = next(csv.reader([line], delimiter=delimiter))
    except csv.Error as exc:  # a field over FIELD_LIMIT characters
        raise InputError(
            f"{label}: line {skip + 1} (the header): {one_line(exc)}; expected column names"
        ) from None
    return skip, [name.strip() for name in header], delimiter


def iter_csv_arrow(path: Path, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    """Chunks of a CSV log read by pyarrow's streaming reader."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    skip, header, delimiter = csv_header(path, label)
    plan = log_plan(header, columns, label)
    # columns go by position (names "0", "1", ...): the header was read above, so spaces around names
    # and names pyarrow would refuse (duplicates of columns not read) do not matter
    key = {role: str(position) for role, position in plan.position.items()}
    types: dict[str, Any] = {key[role]: pa.float64() for role in plan.numeric}
    if "joint" in plan:
        types[key["joint"]] = pa.dictionary(pa.int32(), pa.string())
    # pyarrow reads about 35 blocks ahead of the consumer: 1 MiB blocks bound that to ~35 MiB
    # whatever the file size (larger blocks parse no faster); batches are cut to chunk_rows below
    read = pacsv.ReadOptions(
        skip_rows=skip + 1, column_names=[str(i) for i in range(len(header))], block_size=1 << 20
    )
    codes = JointCodes()
    row = 1  # first row of the pending blocks
    pending: list[dict[str, Any]] = []
    try:
        reader = pacsv.open_csv(
            path,
            read_options=read,
            parse_options=pacsv.ParseOptions(delimiter=delimiter),
            convert_options=pacsv.ConvertOptions(include_columns=list(types), column_types=types),
        )
        for batch in reader:
            block = {role: batch.column(key[role]).to_numpy(zero_copy_only=False) for role in plan.numeric}
            if "joint" in plan:
                start = row + sum(len(part["velocity"]) for part in pending)
                block["joint"] = arrow_joint(batch.column(key["joint"]), codes, plan, start)
            pending.append(block)
            # blocks are sized in bytes (~25k rows): gather them into chunks of chunk_rows rows, so
            # the per-chunk work (one pass per joint) does not repeat for every small block
            while sum(len(part["velocity"]) for part in pending) >= chunk_rows:
                chunk, pending = _take(pending, chunk_rows)
                yield _chunk(plan, chunk, codes, row, (path, skip, delimiter))
                row += chunk_rows
        if pending:
            chunk, pending = _take(pending, sum(len(part["velocity"]) for part in pending))
            yield _chunk(plan, chunk, codes, row, (path, skip, delimiter))
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
        # pyarrow's message has no reliable row number: rescan with the standard library for one
        for _ in iter_csv_python(path, columns, chunk_rows, label):
            pass
        raise InputError(f"{label}: cannot read as CSV: {one_line(exc)}") from None
    except (OSError, pa.ArrowException) as exc:  # a truncated .gz, an I/O error
        raise InputError(f"{label}: cannot read near row {row}: {one_line(exc)}") from None


def _take(parts: list[dict[str, Any]], rows: int) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The first ``rows`` rows of ``parts`` (blocks of column arrays) joined, and the rest."""
    whole = {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}
    head = {name: values[:rows] for name, values in whole.items()}
    rest = {name: values[rows:] for name, values in whole.items()}
    return head, ([rest] if len(rest["velocity"]) else [])


def _chunk(
    plan: ColumnPlan, columns: dict[str, Any], codes: JointCodes, row: int, source: _Source
) -> LogChunk:
    arrays = {role: columns[role] for role in plan.numeric}

    def text(role: str, index: int) -> str | None:  # only for a message: the file is read again
        return _cell_at(*source, row + index, plan.position[role])

    return make_chunk(plan, arrays, columns.get("joint"), codes, row, text)


def iter_csv_python(path: Path, columns: LogColumns, chunk_rows: int, label: str) -> Iterator[LogChunk]:
    """Chunks of a CSV log read by the standard library's ``csv`` module."""
    skip, header, delimiter = csv_header(path, label)
    plan = log_plan(header, columns, label)
    codes = JointCodes()
    row = 1
    with _open_text(path) as handle:
        try:
            for _ in range(skip + 1):
                handle.readline()
        except _READ_ERRORS as exc:
            raise InputError(f"{label}: cannot read: {one_line(exc)}") from None
        reader = csv.reader(handle, delimiter=delimiter)
        while True:
            try:
                block = [fields for fields in itertools.islice(reader, chunk_rows) if fields]
            except _READ_ERRORS as exc:
                raise InputError(f"{label}: cannot read near row {row}: {one_line(exc)}") from None
            if not block:
                return
            for offset, fields in enumerate(block):
                if len(fields) != len(header):
                    line = _line_of(path, skip, delimiter, row + offset)
                    raise InputError(
                        f"{label}: row {row + offset} (line {line}): {len(fields)} fields, the header has "
                        f"{len(header)} ({', '.join(header)})"
                    )
            arrays = parse_cells(block, plan, row)
            joint = None
            if "joint" in plan:
                column = plan.position["joint"]
                names, inverse = np.unique([fields[column].strip() for fields in block], return_inverse=True)
                joint = codes.encode(list(names), inverse, plan, row)

            def text(role: str, index: int, block: list[list[str]] = block) -> str:
                return block[index][plan.position[role]]

            yield make_chunk(plan, arrays, joint, codes, row, text)
            row += len(block)


def _data_rows(path: Path, skip: int, delimiter: str) -> Iterator[tuple[list[str], int]]:
    """The non-blank data rows of a CSV log with the line (1-based, of the file) each ends on."""
    with _open_text(path) as handle:
        for _ in range(skip + 1):
            handle.readline()
        reader = csv.reader(handle, delimiter=delimiter)
        for fields in reader:
            if fields:
                yield fields, skip + 1 + reader.line_num


def csv_rows(path: Path, label: str) -> tuple[list[str], list[list[str]]]:
    """Header names and every data row's fields of a CSV read whole (identify's bench logs).

    The header, comments, delimiter and byte-order mark follow :func:`csv_header`, so a bench log
    reads as ``check`` reads a log; blank rows are skipped.

    Raises:
        InputError: an empty, damaged or truncated file, naming it.
    """
    skip, header, delimiter = csv_header(path, label)
    try:
        rows = [fields for fields, _ in _data_rows(path, skip, delimiter)]
    except _READ_ERRORS as exc:
        raise InputError(f"{label}: cannot read: {one_line(exc)}") from None
    return header, rows


def _line_of(path: Path, skip: int, delimiter: str, row: int) -> int:
    """The line of the file data row ``row`` (1-based) ends on: read again, for an error message."""
    for number, (_, line) in enumerate(_data_rows(path, skip, delimiter), start=1):
        if number == row:
            return line
    return 0  # pragma: no cover - the row was read before


def _cell_at(path: Path, skip: int, delimiter: str, row: int, column: int) -> str | None:
    """The text of data row ``row``'s field ``column``, read again (for an error message)."""
    try:
        fields = next(itertools.islice(_data_rows(path, skip, delimiter), row - 1, None))[0]
    except (StopIteration, *_READ_ERRORS):
        return None
    return fields[column] if column < len(fields) else None


def _parse_floats(block: list[list[str]], column: int) -> tuple[Any, tuple[int, str] | None]:
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


def parse_cells(block: list[list[str]], plan: ColumnPlan, first_row: int) -> dict[str, Any]:
    """The numeric columns of CSV rows, as written; an unreadable cell raises, naming the earliest.

    ``first_row`` is the row number of ``block[0]``; identify's bench logs read their cells here too.
    """
    arrays: dict[str, Any] = {}
    bad: list[tuple[int, str, str]] = []
    for role in plan.numeric:
        arrays[role], problem = _parse_floats(block, plan.position[role])
        if problem is not None:
            bad.append((problem[0], plan.name(role), problem[1]))
    if bad:
        offset, name, cell = min(bad)
        what = "an empty cell" if not cell.strip() else repr(cell)
        raise InputError(
            f"{plan.label}: row {first_row + offset}, column {name!r}: got {what}; expected a number"
        )
    return arrays

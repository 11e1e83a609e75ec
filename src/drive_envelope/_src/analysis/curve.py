"""Reading points digitized from a datasheet's operating diagram (a torque-speed curve).

The file is a small CSV with a header. A column's unit may follow its name in brackets or
parentheses, as digitizing tools and datasheets write them (``speed [rpm]``, ``torque (mNm)``); a
column without a unit is SI. Headers are read by :mod:`.log_units`, as the logs of ``check`` and
``fit`` are. The points must be joint side: convert motor-side curves through the
gear first (speed / ratio, torque * ratio * efficiency).

    speed [rpm],torque [mNm]
    0,820
    2500,760
    ...

A curve that falls to zero effort at its no-load speed (a DC motor's published curve) is the
speed-torque line of eq. 2, and the fit reads it so, as the datasheet derivation reads the same
points stored as ``[losses] operating_points`` (see :mod:`.fit_choice`).
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.log_units import column_scale, find_columns, split_header
from drive_envelope._src.analysis.logs import LogColumns
from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import input_file

__all__ = ["EFFORT_ALIASES", "VELOCITY_ALIASES", "read_curve"]

FloatArray = npt.NDArray[np.float64]
VELOCITY_ALIASES = ("velocity", "speed", "omega", "v")
"""Column names accepted for the velocity of a curve when the default column name is absent."""
EFFORT_ALIASES = ("effort", "torque", "force", "tau")
"""Column names accepted for the effort of a curve when the default column name is absent."""


def _split_header(cell: str) -> tuple[str, str]:
    name, unit = split_header(cell)
    return name.lower(), unit


def _find(
    cells: list[str], wanted: str, aliases: tuple[str, ...], default: str, label: str, flag: str
) -> int:
    """The one column named ``wanted`` up to case (or, for the default name, one of its aliases)."""
    candidates = [wanted.strip()] + (list(aliases) if wanted == default else [])
    hits = {candidate: find_columns(cells, candidate) for candidate in candidates}
    for candidate, found in hits.items():
        if len(found) > 1:
            raise InputError(f"{label}: column {candidate!r} appears {len(found)} times")
    columns = sorted({index for found in hits.values() for index in found})
    if len(columns) > 1:
        names = [split_header(cells[index])[0].lower() for index in columns]
        raise InputError(
            f"{label}: columns {', '.join(map(repr, names))} could each be the {default}; "
            f"name the one to use with {flag}"
        )
    if not columns:
        names = [split_header(cell)[0].lower() for cell in cells]
        raise InputError(f"{label}: no column {wanted!r} (columns: {', '.join(names)}); name it with {flag}")
    return columns[0]


def read_curve(
    path: str | os.PathLike[str], *, columns: LogColumns | None = None, joint: JointType = "revolute"
) -> tuple[FloatArray, FloatArray]:
    """Read digitized curve points and convert them to SI, joint side.

    Args:
        path: CSV file with a header; units in brackets after the column names.
        columns: Column names (``velocity`` and ``effort``); with the defaults, ``speed``/``torque``/
            ``force`` are accepted too.
        joint: Joint type, which fixes the SI units: rad/s and N*m, or m/s and N.

    Returns:
        ``(velocity [rad/s or m/s], effort [N*m or N])``.

    Raises:
        InputError: missing file or column, an unknown unit, a cell that is not a number.
    """
    columns = columns or LogColumns()
    file = Path(path)
    label = str(file)
    input_file(file, label)  # a FIFO, a device (/dev/zero) or a file over the text cap: refused unopened
    try:
        with open(file, encoding="utf-8-sig", newline="") as handle:
            rows = [
                row for row in csv.reader(line for line in handle if not line.lstrip().startswith("#")) if row
            ]
    except FileNotFoundError:
        raise InputError(f"{label}: no such file") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:  # csv.Error: a field over its size limit
        raise InputError(f"{label}: cannot read: {' '.join(str(exc).split())}") from None
    if not rows:
        raise InputError(
            f"{label}: empty file (expected a header such as 'speed [rpm],torque [mNm]' and points)"
        )
    header = [_split_header(cell) for cell in rows[0]]
    names = [name for name, _ in header]
    v_col = _find(
        rows[0], columns.velocity, VELOCITY_ALIASES, LogColumns().velocity, label, "--velocity-column"
    )
    e_col = _find(rows[0], columns.effort, EFFORT_ALIASES, LogColumns().effort, label, "--effort-column")
    scales = []
    for col, role in ((v_col, "velocity"), (e_col, "effort")):
        name, unit = header[col]
        scales.append(column_scale(role, unit, joint, f"{label}: column {name!r}")[0])
    values = np.empty((len(rows) - 1, 2))
    for row_number, row in enumerate(rows[1:], start=1):
        for out, col in enumerate((v_col, e_col)):
            cell = row[col] if col < len(row) else ""
            try:
                values[row_number - 1, out] = float(cell)
            except ValueError:
                what = "an empty cell" if not cell.strip() else repr(cell)
                raise InputError(
                    f"{label}: row {row_number}, column {names[col]!r}: got {what}; expected a number"
                ) from None
    if not np.isfinite(values).all():
        bad = int(np.flatnonzero(~np.isfinite(values).all(axis=1))[0])
        raise InputError(f"{label}: row {bad + 1}: NaN or infinite value; expected finite numbers")
    if values.shape[0] < 3:
        raise InputError(f"{label}: {values.shape[0]} points; a curve needs at least 3")
    return values[:, 0] * scales[0], values[:, 1] * scales[1]

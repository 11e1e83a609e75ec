"""Reading points digitized from a datasheet's operating diagram (a torque-speed curve).

The file is a small CSV with a header, read by the one log reader of ``check`` and ``fit``
(:func:`~.logs.read_log`: the delimiters ``,``, ``;`` and tab, ``#`` comments, the row checks). A
column's unit may follow its name in brackets or parentheses, as digitizing tools and datasheets
write them (``speed [rpm]``, ``torque (mNm)``); a column without a unit is SI (:mod:`.log_units`).
Only the choice of columns is the curve's own: ``speed``/``torque``/``force`` are accepted for the
default names. The points must be joint side: convert motor-side curves through the gear first
(speed / ratio, torque * ratio * efficiency).

    speed [rpm],torque [mNm]
    0,820
    2500,760
    ...

A curve that falls to zero effort at its no-load speed (a DC motor's published curve) is the
speed-torque line of eq. 2, and the fit reads it so, as the datasheet derivation reads the same
points stored as ``[losses] operating_points`` (see :mod:`.fit_choice`).
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.log_csv import csv_header
from drive_envelope._src.analysis.log_units import find_columns, split_header
from drive_envelope._src.analysis.logs import LogColumns, ReadEngine, read_log
from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import input_file

FloatArray = npt.NDArray[np.float64]
VELOCITY_ALIASES = ("velocity", "speed", "omega", "v")
"""Column names accepted for the velocity of a curve when the default column name is absent."""
EFFORT_ALIASES = ("effort", "torque", "force", "tau")
"""Column names accepted for the effort of a curve when the default column name is absent."""


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
    path: str | os.PathLike[str],
    *,
    columns: LogColumns | None = None,
    joint: JointType = "revolute",
    engine: ReadEngine = "auto",
) -> tuple[FloatArray, FloatArray]:
    """Read digitized curve points and convert them to SI, joint side.

    Args:
        path: CSV file with a header; units in brackets after the column names.
        columns: Column names (``velocity`` and ``effort``); with the defaults, ``speed``/``torque``/
            ``force`` are accepted too.
        joint: Joint type, which fixes the SI units: rad/s and N*m, or m/s and N.
        engine: CSV reader of :func:`~.logs.read_log` (``"auto"``, ``"pyarrow"``, ``"python"``).

    Returns:
        ``(velocity [rad/s or m/s], effort [N*m or N])``.

    Raises:
        InputError: missing file or column, an unknown unit, a cell that is not a number (the
            messages of :func:`~.logs.read_log`), fewer than 3 points.
    """
    columns = columns or LogColumns()
    file = Path(path)
    label = str(file)
    input_file(file, label)  # a FIFO, a device (/dev/zero) or a file over the text cap: refused unopened
    # the role-to-column plan: the header is read as check reads it (delimiter, comments, units),
    # the curve's aliases (speed, torque) pick the names, and the one log reader reads the rows
    header = csv_header(file, label)[1] if file.suffix.lower() not in (".parquet", ".pq", ".json") else []
    plan = columns
    if header:
        v_col = _find(
            header, columns.velocity, VELOCITY_ALIASES, LogColumns().velocity, label, "--velocity-column"
        )
        e_col = _find(header, columns.effort, EFFORT_ALIASES, LogColumns().effort, label, "--effort-column")
        plan = replace(columns, velocity=header[v_col], effort=header[e_col])
    chunk = read_log(file, replace(plan, time=None, joint=None, joint_type=joint), engine=engine)
    if len(chunk) < 3:
        raise InputError(f"{label}: {len(chunk)} points; a curve needs at least 3")
    return chunk.velocity, chunk.effort

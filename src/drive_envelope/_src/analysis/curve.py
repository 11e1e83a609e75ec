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
from drive_envelope._src.analysis.log_model import log_plan
from drive_envelope._src.analysis.log_units import find_columns
from drive_envelope._src.analysis.logs import LogColumns, ReadEngine, read_log
from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import input_file

FloatArray = npt.NDArray[np.float64]
VELOCITY_ALIASES = ("speed", "omega", "v")
"""Other names of a curve's velocity column, looked for beside the default ``velocity``."""
EFFORT_ALIASES = ("torque", "force", "tau")
"""Other names of a curve's effort column, looked for beside the default ``effort``."""


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
    chunk = read_log(file, _curve_columns(columns, joint), engine=engine)
    if len(chunk) < 3:
        raise InputError(f"{label}: {len(chunk)} points; a curve needs at least 3")
    return chunk.velocity, chunk.effort


def _curve_columns(columns: LogColumns, joint: JointType | None) -> LogColumns:
    """The columns a curve is read with: the one reader's plan plus the curve's aliases.

    The aliases (speed, torque) apply only to a default name: a column the user named is that column.
    """
    default = LogColumns()
    return replace(
        columns,
        velocity_aliases=VELOCITY_ALIASES if columns.velocity == default.velocity else (),
        effort_aliases=EFFORT_ALIASES if columns.effort == default.effort else (),
        time=None,
        joint=None,
        joint_type=joint,
    )


def looks_like_curve(path: str | os.PathLike[str]) -> bool:
    """Whether a CSV's columns are a curve's: a velocity and an effort by the curve's names, no time.

    ``fit LOG`` says so when it cannot read such a file as a log (``fit --from-curve`` reads it).
    """
    file = Path(path)
    try:
        input_file(file, str(file))  # a FIFO would block, a device never end: not opened
        header = csv_header(file, str(file))[1]
        log_plan(header, _curve_columns(LogColumns(), None), str(file))
    except InputError:
        return False
    return not find_columns(header, "time")

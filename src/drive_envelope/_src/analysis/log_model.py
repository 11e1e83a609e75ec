"""The data model of a log and the rules every reader shares: columns, units, finite cells.

A log's header is matched against :class:`LogColumns` once, by :func:`log_plan` (the one plan of
:mod:`.columns`, which identify's bench logs and the curve reader use too): names are
compared ignoring case and surrounding spaces, so ``Time, Velocity [RPM], Effort`` reads as
``time,velocity,effort`` (:func:`~.log_units.find_columns`). A column named twice
(``time,velocity,velocity,effort``), two names that differ only in case (``Velocity,velocity``), or
one column given two roles (``--velocity-column effort``) is an error, never a silent first pick.
A header may carry a unit after the name (``velocity [rpm]``, ``effort (mNm)``, see
:mod:`.log_units`): the column is found by its name (``velocity``) or its whole text, and its values
are converted to SI. A ROS 2 bag (:mod:`.log_bag`) becomes a long table of these columns (one
``joint`` per name in its JointState messages) and follows the same rules. Numbers in chunks are
SI: velocity [rad/s or m/s], effort [N*m or N], time [s].
Time may go back (a log of several episodes, each from 0): the check counts each jump back as the
start of an episode and says so (:mod:`.check`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.columns import ColumnPlan, Role, plan_columns
from drive_envelope._src.analysis.log_bag import BagOptions
from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]
CellText = Callable[[str, int], "str | None"]
"""``text(role, index)``: the text of a chunk's cell as written in the file, or None if unknown."""

_INFINITE = ("inf", "+inf", "-inf", "infinity", "+infinity", "-infinity")


@dataclass(frozen=True, kw_only=True, slots=True)
class LogColumns:
    """Which columns of a log hold what; the defaults are those of ``drive-envelope simulate``.

    A name finds the column of that name, or one whose header is that name and a unit
    (``velocity`` finds ``velocity [rpm]``); the whole header text (``velocity [rpm]``) works too.
    Case does not matter (``velocity`` finds ``Velocity [RPM]``), but two columns that differ only
    in case are an error.
    """

    velocity: str = "velocity"
    """Joint velocity column [rad/s or m/s, or the unit in its header]."""
    effort: str = "effort"
    """Total actuator effort column [N*m or N, or the unit in its header]."""
    time: str | None = "time"
    """Time column [s, or the unit in its header], used when present (``None``: never); it locates
    violations in time."""
    joint: str | None = "joint"
    """Joint-name column of a long-format log with several joints, used when present (no unit)."""
    require_time: bool = False
    """Raise when the time column is absent (set when the user named it explicitly)."""
    require_joint: bool = False
    """Raise when the joint column is absent (set when the user named it explicitly)."""
    joint_type: JointType | None = None
    """Joint type the log is read for, which fixes the SI unit a header's unit converts to (rad/s
    and N*m, or m/s and N); a unit of the other type is an error. None: either, as the units say
    (both columns' units must then agree)."""
    velocity_aliases: tuple[str, ...] = ()
    """Other names of the velocity column, looked for beside ``velocity`` (the curve reader's ``speed``);
    two columns that could each be the velocity are an error."""
    effort_aliases: tuple[str, ...] = ()
    """Other names of the effort column, looked for beside ``effort`` (the curve reader's ``torque``)."""
    bag: BagOptions | None = None
    """Topics and time source of a ROS 2 bag (:mod:`.log_bag`); None: the bag's only JointState
    topic, no command topic, header stamps."""


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
    joint_type: JointType | None = None
    """Joint type the units in the header imply (or :attr:`LogColumns.joint_type`); None when no
    read column has a unit that tells (SI numbers fit either)."""

    def __len__(self) -> int:
        return int(self.velocity.shape[0])


def log_roles(columns: LogColumns) -> tuple[Role, ...]:
    """The roles of a (velocity, effort) log as :class:`LogColumns` names them, in the order they resolve."""
    return (
        Role(role="velocity", column=columns.velocity, required=True, aliases=columns.velocity_aliases,
             flag="--velocity-column", quantity="velocity"),
        Role(role="effort", column=columns.effort, required=True, aliases=columns.effort_aliases,
             flag="--effort-column", quantity="effort"),
        Role(role="time", column=columns.time, required=columns.require_time, flag="--time-column",
             quantity="time"),
        Role(role="joint", column=columns.joint, required=columns.require_joint, flag="--joint-column",
             text=True),
    )  # fmt: skip


def log_plan(header: Sequence[str], columns: LogColumns, label: str) -> ColumnPlan:
    """The :class:`~.columns.ColumnPlan` of a log's header for ``columns`` (the one rule of every reader).

    Raises:
        InputError: a column missing, named twice (up to case) or named for two roles, a bad unit,
            or units of two joint types (:func:`~.columns.plan_columns`).
    """
    return plan_columns(header, log_roles(columns), label, joint_type=columns.joint_type)


class JointCodes:
    """Stable integer codes for joint names across chunks (names compared without outer spaces)."""

    def __init__(self) -> None:
        self.codes: dict[str, int] = {}

    def encode(
        self, names: Sequence[Any], indices: npt.NDArray[Any], plan: ColumnPlan, first_row: int
    ) -> IntArray:
        """Codes for ``names[indices]`` (a dictionary-encoded column whose first row is ``first_row``).

        Raises:
            InputError: a row's joint name is empty (or only spaces), naming the row: it would be
                checked as a joint named ``''``.
        """
        blank = [code for code, name in enumerate(names) if not str(name).strip()]
        if blank:
            rows = np.flatnonzero(np.isin(np.asarray(indices), blank))
            if rows.size:
                raise InputError(
                    f"{plan.label}: row {first_row + int(rows[0])}, column {plan.name('joint')!r}: "
                    "empty joint name; expected the joint's name in every row"
                )
        lookup = np.array(
            [self.codes.setdefault(str(name).strip(), len(self.codes)) for name in names], dtype=np.intp
        )
        return lookup[np.asarray(indices, dtype=np.intp)] if lookup.size else np.zeros(0, dtype=np.intp)

    @property
    def names(self) -> tuple[str, ...]:
        """Every joint name seen so far, in order of first appearance."""
        return tuple(self.codes)


def _first_nonfinite(values: FloatArray) -> int | None:
    """Index of the first NaN (empty cells read as NaN) or inf, or None."""
    with np.errstate(over="ignore", invalid="ignore"):
        total = float(np.sum(values))
    if math.isfinite(total):  # one pass, no temporary: a NaN or inf anywhere makes the sum non-finite
        return None
    bad = np.flatnonzero(~np.isfinite(values))
    return int(bad[0]) if bad.size else None


def _check_finite(
    plan: ColumnPlan, arrays: dict[str, FloatArray], first_row: int, text: CellText | None
) -> None:
    """Refuse NaN and inf cells, naming the earliest bad row (and its column, and the cell's text)."""
    found = [
        (index, role) for role, values in arrays.items() if (index := _first_nonfinite(values)) is not None
    ]
    if found:
        index, role = min(found)
        value = float(arrays[role][index])
        what = "an empty cell or NaN" if math.isnan(value) else repr(value)
        cell = None if text is None or math.isnan(value) else text(role, index)
        if cell is not None and cell.strip().lower() not in _INFINITE:
            what += f" (the cell reads {cell.strip()!r}, beyond the float range of about 1.8e308)"
        raise InputError(
            f"{plan.label}: row {first_row + index}, column {plan.name(role)!r}: got {what}; "
            "expected a finite number"
        )


def _to_si(plan: ColumnPlan, arrays: dict[str, FloatArray], first_row: int) -> dict[str, FloatArray]:
    """The arrays scaled by the units of their headers; a value the scale takes beyond float range raises."""
    scaled = dict(arrays)
    for role, scale in plan.scale.items():
        if scale == 1.0:
            continue
        with np.errstate(over="ignore"):
            scaled[role] = arrays[role] * scale
        index = _first_nonfinite(scaled[role])
        if index is not None:
            raise InputError(
                f"{plan.label}: row {first_row + index}, column {plan.name(role)!r}: "
                f"{float(arrays[role][index])!r} {plan.unit[role]} is beyond the float range in SI; "
                "expected a finite number"
            )
    return scaled


def si_arrays(
    plan: ColumnPlan, arrays: dict[str, FloatArray], first_row: int, text: CellText | None = None
) -> dict[str, FloatArray]:
    """``arrays`` (numeric role -> values as written) checked finite and scaled to SI by their units.

    The one cell rule of every reader (identify's bench logs too). ``first_row`` is the row of the
    arrays' first value; ``text`` gives a cell's written text for messages, when known.

    Raises:
        InputError: a NaN, empty or infinite cell, or a value its unit takes beyond float range,
            naming the earliest row and its column.
    """
    _check_finite(plan, arrays, first_row, text)
    return _to_si(plan, arrays, first_row)


def make_chunk(
    plan: ColumnPlan,
    arrays: dict[str, FloatArray],
    joint: IntArray | None,
    codes: JointCodes,
    first_row: int,
    text: CellText | None = None,
) -> LogChunk:
    """A validated :class:`LogChunk` from the numeric arrays of ``plan.numeric`` (keyed by role).

    The values are checked finite and converted to SI by the units in the header. ``text`` gives
    the written text of a cell for messages (a CSV reader's), when known.
    """
    arrays = si_arrays(plan, arrays, first_row, text)
    time = arrays.get("time")
    return LogChunk(
        velocity=arrays["velocity"],
        effort=arrays["effort"],
        time=time,
        joint=joint,
        names=codes.names,
        first_row=first_row,
        joint_type=plan.joint_type,
    )

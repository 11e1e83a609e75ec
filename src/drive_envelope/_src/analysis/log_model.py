"""The data model of a log and the rules every reader shares: which column is which, finite cells.

A log's header is matched against :class:`LogColumns` once, by :class:`ColumnPlan`: a column named
twice (``time,velocity,velocity,effort``), two names that differ only in case or surrounding spaces,
or one column given two roles (``--velocity-column effort``) is an error, never a silent first pick.
Names are compared with surrounding spaces removed, so ``time, velocity, effort`` reads as written.
Numbers are SI: velocity [rad/s or m/s], effort [N*m or N], time [s].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError

__all__ = ["ROLES", "ColumnPlan", "JointCodes", "LogChunk", "LogColumns", "make_chunk"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

ROLES = ("velocity", "effort", "time", "joint")
"""What a log column can hold, in the order columns are resolved."""

_FLAGS = {role: f"--{role}-column" for role in ROLES}


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


class ColumnPlan:
    """Where each role's column sits in a header, checked for duplicates and double use.

    Attributes:
        header: The header names, surrounding spaces removed.
        position: Role (``velocity``, ``effort``, ``time``, ``joint``) -> index in ``header``.
        numeric: The roles read as numbers: velocity, effort and, when present, time.
    """

    def __init__(self, header: Sequence[str], columns: LogColumns, label: str) -> None:
        self.header = [str(name).strip() for name in header]
        self.label = label
        self.position: dict[str, int] = {}
        wanted = {
            "velocity": (columns.velocity, True),
            "effort": (columns.effort, True),
            "time": (columns.time, columns.require_time),
            "joint": (columns.joint, columns.require_joint),
        }
        for role in ROLES:
            name, required = wanted[role]
            if name is not None:
                self._resolve(role, str(name).strip(), required)
        self.numeric: list[str] = [role for role in ("velocity", "effort", "time") if role in self.position]

    def name(self, role: str) -> str:
        """The header name of ``role``'s column."""
        return self.header[self.position[role]]

    @property
    def joint(self) -> bool:
        """Whether the log has a joint column."""
        return "joint" in self.position

    @property
    def time(self) -> bool:
        """Whether the log has a time column."""
        return "time" in self.position

    def _resolve(self, role: str, name: str, required: bool) -> None:
        folded = name.casefold()
        similar = [i for i, column in enumerate(self.header) if column.casefold() == folded]
        if len(similar) > 1:
            found = ", ".join(f"{self.header[i]!r} (column {i + 1})" for i in similar)
            raise InputError(
                f"{self.label}: column {name!r} is ambiguous: the header has {found}; "
                "expected each column name once"
            )
        exact = [i for i in similar if self.header[i] == name]
        if not exact:
            if required:
                columns = ", ".join(self.header) or "none"
                raise InputError(
                    f"{self.label}: no column {name!r} (columns: {columns}); name it with {_FLAGS[role]}"
                )
            return
        for other, position in self.position.items():
            if position == exact[0]:
                if not required:  # a default name (time, joint) taken by an explicit role: not used
                    return
                raise InputError(
                    f"{self.label}: column {name!r} is named by both {_FLAGS[other]} and {_FLAGS[role]}; "
                    "expected a different column for each"
                )
        self.position[role] = exact[0]


class JointCodes:
    """Stable integer codes for joint names across chunks (names compared without outer spaces)."""

    def __init__(self) -> None:
        self.codes: dict[str, int] = {}

    def encode(self, names: Sequence[Any], indices: npt.NDArray[Any]) -> IntArray:
        """Codes for ``names[indices]`` (a dictionary-encoded column)."""
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


def _check_finite(plan: ColumnPlan, arrays: dict[str, FloatArray], first_row: int) -> None:
    """Refuse NaN and inf cells, naming the earliest bad row (and its column)."""
    found = [
        (index, role) for role, values in arrays.items() if (index := _first_nonfinite(values)) is not None
    ]
    if found:
        index, role = min(found)
        value = float(arrays[role][index])
        what = "an empty cell or NaN" if math.isnan(value) else repr(value)
        raise InputError(
            f"{plan.label}: row {first_row + index}, column {plan.name(role)!r}: got {what}; "
            "expected a finite number"
        )


def make_chunk(
    plan: ColumnPlan,
    arrays: dict[str, FloatArray],
    joint: IntArray | None,
    codes: JointCodes,
    first_row: int,
) -> LogChunk:
    """A validated :class:`LogChunk` from the numeric arrays of ``plan.numeric`` (keyed by role)."""
    _check_finite(plan, arrays, first_row)
    return LogChunk(
        velocity=arrays["velocity"],
        effort=arrays["effort"],
        time=arrays.get("time"),
        joint=joint,
        names=codes.names,
        first_row=first_row,
    )

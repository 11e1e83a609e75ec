"""The result of a test-stand run: time, position, velocity and actuator effort per step.

Row 0 is the initial state (effort 0.0: no step has been taken yet); row ``i >= 1`` is the state
at the end of step ``i`` and the step-average total actuator effort over that step (drive +
applied joint effort, what PhysX reports). CSV files have the header ``time,position,velocity,effort``
and are written atomically; JSON files hold the same columns plus the metadata.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.atomic import atomic_write_text
from drive_envelope._src.io.files import read_text

__all__ = [
    "COLUMNS",
    "Trajectory",
    "read_trajectory",
    "save_trajectory",
    "trajectory_to_csv",
    "trajectory_to_json",
]

COLUMNS = ("time", "position", "velocity", "effort")
"""CSV header, in order."""

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, kw_only=True, slots=True)
class Trajectory:
    """Sampled states of one joint; all arrays have the same length ``steps + 1``."""

    time: FloatArray
    """Time at the end of each step, ``time[0] = 0`` [s]."""
    position: FloatArray
    """Joint position [rad or m]."""
    velocity: FloatArray
    """Joint velocity [rad/s or m/s]."""
    effort: FloatArray
    """Step-average total actuator effort (drive + applied joint effort) over the step that ends at
    ``time[i]``; ``effort[0] = 0`` [N*m or N]."""
    joint: JointType = "revolute"
    """Joint type, which fixes the units."""
    engine: str = ""
    """Engine that produced it (``reference``, ``mujoco``, ``physx``), empty if unknown."""
    name: str = ""
    """Scenario name, empty if unknown."""
    metadata: dict[str, Any] = field(default_factory=dict)
    """Free-form JSON-compatible details (solver settings, engine version)."""

    def __post_init__(self) -> None:
        arrays = {}
        for column in COLUMNS:
            values = np.asarray(getattr(self, column), dtype=np.float64)
            if values.ndim != 1:
                raise InputError(
                    f"trajectory column {column!r} must be one-dimensional, got shape {values.shape}"
                )
            arrays[column] = values
        lengths = {values.shape[0] for values in arrays.values()}
        if len(lengths) != 1:
            raise InputError(
                f"trajectory columns have different lengths: { {k: v.shape[0] for k, v in arrays.items()} }"
            )
        for column, values in arrays.items():
            object.__setattr__(self, column, values)

    def __len__(self) -> int:
        return int(self.time.shape[0])

    @property
    def units(self) -> dict[str, str]:
        """SI unit of each column for this joint type."""
        if self.joint == "prismatic":
            return {"time": "s", "position": "m", "velocity": "m/s", "effort": "N"}
        return {"time": "s", "position": "rad", "velocity": "rad/s", "effort": "N*m"}


def _number(value: float) -> str:
    # repr round-trips float64 exactly; CSV readers accept inf/nan spelled this way
    return repr(float(value))


def trajectory_to_csv(trajectory: Trajectory) -> str:
    """CSV text with the header ``time,position,velocity,effort``, one row per sample."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    columns = [getattr(trajectory, c) for c in COLUMNS]
    for row in zip(*columns, strict=True):
        writer.writerow([_number(v) for v in row])
    return buffer.getvalue()


def _json_float(value: float) -> float | str:
    return value if math.isfinite(value) else repr(value)


def trajectory_to_json(trajectory: Trajectory) -> str:
    """JSON text: ``{"engine", "name", "joint", "units", "metadata", "time": [...], ...}``."""
    data: dict[str, Any] = {
        "engine": trajectory.engine,
        "name": trajectory.name,
        "joint": trajectory.joint,
        "units": trajectory.units,
        "metadata": trajectory.metadata,
    }
    for column in COLUMNS:
        data[column] = [_json_float(float(v)) for v in getattr(trajectory, column)]
    return json.dumps(data, indent=1) + "\n"


def save_trajectory(
    trajectory: Trajectory,
    path: str | os.PathLike[str],
    *,
    format: Literal["csv", "json"] | None = None,
) -> None:
    """Write a trajectory atomically; the format follows the suffix (``.json``, else CSV) unless given.

    Raises:
        InputError: the file cannot be written (missing folder, no permission).
    """
    chosen = format or ("json" if Path(path).suffix.lower() == ".json" else "csv")
    text = trajectory_to_json(trajectory) if chosen == "json" else trajectory_to_csv(trajectory)
    try:
        atomic_write_text(path, text)
    except OSError as exc:  # a missing folder or no permission is the user's input, not a bug
        raise InputError(f"--output {str(path)!r}: cannot write: {exc.strerror or exc}") from None


def read_trajectory(path: str | os.PathLike[str], *, joint: JointType = "revolute") -> Trajectory:
    """Read a trajectory CSV (header ``time,position,velocity,effort``) or JSON file.

    An empty effort cell (row 0 of some writers) reads as 0.0.

    Args:
        path: The file.
        joint: Joint type recorded in the result for a CSV file (CSV has no metadata).

    Raises:
        InputError: missing file, missing column, or a cell that is not a number.
    """
    file = Path(path)
    text = read_text(file)
    if file.suffix.lower() == ".json":
        return _from_json(text, file)
    return _from_csv(text, file, joint)


def _cell(value: str | None, where: str) -> float:
    if value is None or value.strip() == "":
        return 0.0
    try:
        return float(value)
    except ValueError:
        raise InputError(f"{where}: expected a number, got {value!r}") from None


def _from_csv(text: str, file: Path, joint: JointType) -> Trajectory:
    reader = csv.DictReader(io.StringIO(text))
    header = reader.fieldnames or []
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise InputError(
            f"{file}: missing column(s) {', '.join(missing)}; expected header {','.join(COLUMNS)}"
        )
    columns: dict[str, list[float]] = {c: [] for c in COLUMNS}
    for line, row in enumerate(reader, start=2):
        for column in COLUMNS:
            columns[column].append(_cell(row.get(column), f"{file}: line {line}, column {column!r}"))
    if not columns["time"]:
        raise InputError(f"{file}: no data rows")
    return Trajectory(
        time=np.asarray(columns["time"]),
        position=np.asarray(columns["position"]),
        velocity=np.asarray(columns["velocity"]),
        effort=np.asarray(columns["effort"]),
        joint=joint,
        name=file.stem,
    )


def _from_json(text: str, file: Path) -> Trajectory:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{file}: malformed JSON: {exc}") from None
    if not isinstance(data, dict):
        raise InputError(f"{file}: expected a JSON object with keys {', '.join(COLUMNS)}")
    arrays = {}
    for column in COLUMNS:
        if not isinstance(data.get(column), list):
            raise InputError(f"{file}: key {column!r}: expected a list of numbers")
        arrays[column] = np.asarray([_cell(str(v), f"{file}: key {column!r}") for v in data[column]])
    joint = data.get("joint", "revolute")
    if joint not in ("revolute", "prismatic"):
        raise InputError(f"{file}: key 'joint': expected 'revolute' or 'prismatic', got {joint!r}")
    metadata = data.get("metadata", {})
    return Trajectory(
        joint=joint,
        engine=str(data.get("engine", "")),
        name=str(data.get("name", "") or file.stem),
        metadata=metadata if isinstance(metadata, dict) else {},
        time=arrays["time"],
        position=arrays["position"],
        velocity=arrays["velocity"],
        effort=arrays["effort"],
    )

"""The result of a test-stand run: time, position, velocity and actuator effort per step.

Row 0 is the initial state (effort 0.0: no step has been taken yet); row ``i >= 1`` is the state
at the end of step ``i`` and the step-average total actuator effort over that step (drive +
applied joint effort, what PhysX reports). Files: CSV with the header ``time,position,velocity,effort``,
JSON with the same columns plus the metadata, or Parquet (needs pyarrow) with the metadata in the
schema; the suffix picks the format (``.csv``/``.txt``/none, ``.json``, ``.parquet``/``.pq``). Files
are written atomically and streamed in blocks, so memory does not grow with the text. Every value
is finite: a NaN or inf in a trajectory, or in a file read as one, is an :class:`InputError`.
:func:`read_operating_log` reads only the velocity, effort and (optional) time of the same files,
for plots of bench logs that have no position.
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, TextIO

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.atomic import atomic_path
from drive_envelope._src.io.files import read_text

if TYPE_CHECKING:
    from drive_envelope._src.scenario.spec import Scenario

COLUMNS = ("time", "position", "velocity", "effort")
"""CSV header, in order."""
TrajectoryFormat = Literal["csv", "json", "parquet"]
TRAJECTORY_FORMATS: tuple[TrajectoryFormat, ...] = ("csv", "json", "parquet")
"""File formats of a trajectory."""

FloatArray = npt.NDArray[np.float64]

_SUFFIXES: dict[str, TrajectoryFormat] = {
    ".csv": "csv",
    ".txt": "csv",
    "": "csv",
    ".json": "json",
    ".parquet": "parquet",
    ".pq": "parquet",
}
_BLOCK_ROWS = 1 << 16  # rows formatted at a time when writing: the text never exists whole


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
            if not np.isfinite(values).all():  # a diverged engine must never write a silent NaN
                row = int(np.flatnonzero(~np.isfinite(values))[0])
                raise InputError(
                    f"trajectory {self.name or self.engine or ''!r}: column {column!r}, row {row} is "
                    f"{float(values[row])!r}; expected finite numbers"
                )
            object.__setattr__(self, column, values)

    def __len__(self) -> int:
        return int(self.time.shape[0])

    @property
    def units(self) -> dict[str, str]:
        """SI unit of each column for this joint type."""
        if self.joint == "prismatic":
            return {"time": "s", "position": "m", "velocity": "m/s", "effort": "N"}
        return {"time": "s", "position": "rad", "velocity": "rad/s", "effort": "N*m"}

    def header(self) -> dict[str, Any]:
        """Everything but the columns: engine, name, joint, units and metadata (JSON-compatible)."""
        return {
            "engine": self.engine,
            "name": self.name,
            "joint": self.joint,
            "units": self.units,
            "metadata": self.metadata,
        }


def stand_run(scenario: Scenario, engine: str, *columns: FloatArray, **metadata: Any) -> Trajectory:
    """An engine's run of ``scenario``: its position, velocity and effort ``columns`` from t = 0.

    One row every ``dt`` [s]; the metadata holds the scenario's solver settings, then ``metadata``.
    """
    sim = scenario.simulation
    position, velocity, effort = columns
    return Trajectory(
        time=np.arange(position.shape[0], dtype=np.float64) * sim.dt,
        position=position,
        velocity=velocity,
        effort=effort,
        joint=scenario.joint.type,
        engine=engine,
        name=scenario.name,
        metadata={**sim.metadata(), **metadata},
    )


def trajectory_format(path: str | os.PathLike[str], format: str | None = None) -> TrajectoryFormat:
    """The format a trajectory file is written in: ``format`` if given, else the file's suffix.

    Raises:
        InputError: an unknown format, or a suffix that names none (``.xlsx``; give ``format``).
    """
    if format is not None:
        if format not in TRAJECTORY_FORMATS:
            raise InputError(f"--format {format!r}: expected one of {', '.join(TRAJECTORY_FORMATS)}")
        return format  # type: ignore[return-value]
    suffix = Path(path).suffix.lower()
    if suffix not in _SUFFIXES:
        raise InputError(
            f"--output {str(path)!r}: unknown suffix {suffix!r}; expected "
            f"{', '.join(sorted(name for name in _SUFFIXES if name))} (or name the format with --format)"
        )
    return _SUFFIXES[suffix]


def _blocks(trajectory: Trajectory) -> Iterator[list[list[float]]]:
    """The columns of ``trajectory`` as Python floats, :data:`_BLOCK_ROWS` rows at a time."""
    columns = [getattr(trajectory, c) for c in COLUMNS]
    for start in range(0, len(trajectory), _BLOCK_ROWS):
        yield [column[start : start + _BLOCK_ROWS].tolist() for column in columns]


def write_trajectory_csv(trajectory: Trajectory, handle: TextIO) -> None:
    """Write CSV (header ``time,position,velocity,effort``) to ``handle``, block by block."""
    handle.write(",".join(COLUMNS) + "\n")
    for block in _blocks(trajectory):
        # repr round-trips float64 exactly
        handle.write("".join(f"{t!r},{q!r},{v!r},{e!r}\n" for t, q, v, e in zip(*block, strict=True)))


def write_trajectory_json(trajectory: Trajectory, handle: TextIO) -> None:
    """Write JSON (:meth:`Trajectory.header` keys, then one list per column) to ``handle``."""
    handle.write("{\n")
    for key, value in trajectory.header().items():
        handle.write(f" {json.dumps(key)}: {json.dumps(value)},\n")
    for index, column in enumerate(COLUMNS):
        handle.write(f" {json.dumps(column)}: [")
        values = getattr(trajectory, column)
        for start in range(0, values.shape[0], _BLOCK_ROWS):
            part = ",\n  ".join(repr(v) for v in values[start : start + _BLOCK_ROWS].tolist())
            handle.write(("\n  " if start == 0 else ",\n  ") + part)
        handle.write("\n ]" + (",\n" if index < len(COLUMNS) - 1 else "\n"))
    handle.write("}\n")


def trajectory_to_csv(trajectory: Trajectory) -> str:
    """CSV text with the header ``time,position,velocity,effort``, one row per sample."""
    buffer = io.StringIO()
    write_trajectory_csv(trajectory, buffer)
    return buffer.getvalue()


def trajectory_to_json(trajectory: Trajectory) -> str:
    """JSON text: ``{"engine", "name", "joint", "units", "metadata", "time": [...], ...}``."""
    buffer = io.StringIO()
    write_trajectory_json(trajectory, buffer)
    return buffer.getvalue()


def save_trajectory(
    trajectory: Trajectory,
    path: str | os.PathLike[str],
    *,
    format: TrajectoryFormat | None = None,
    force: bool = False,
) -> None:
    """Write a trajectory atomically; the format follows the suffix (see :func:`trajectory_format`).

    Args:
        trajectory: The trajectory.
        path: Output file.
        format: ``"csv"``, ``"json"`` or ``"parquet"``; None: from the suffix.
        force: Replace ``path`` even when it is read-only.

    Raises:
        InputError: an unknown suffix, Parquet without pyarrow, or a file that cannot be written
            (missing folder, no permission, a full disk).
    """
    chosen = trajectory_format(path, format)
    if chosen == "parquet":
        from drive_envelope._src.scenario.trajectory_parquet import write_parquet

        columns = {column: getattr(trajectory, column) for column in COLUMNS}
        write_parquet(columns, trajectory.header(), path, force=force)
        return
    writer = write_trajectory_json if chosen == "json" else write_trajectory_csv
    with atomic_path(path, force=force) as tmp, open(tmp, "w", encoding="utf-8", newline="") as handle:
        writer(trajectory, handle)


def read_trajectory(path: str | os.PathLike[str], *, joint: JointType = "revolute") -> Trajectory:
    """Read a trajectory file: CSV (header ``time,position,velocity,effort``), JSON or Parquet.

    An empty effort cell (row 0 of some writers) reads as 0.0; spaces around CSV column names are
    ignored.

    Args:
        path: The file.
        joint: Joint type recorded in the result for a CSV file (CSV has no metadata).

    Raises:
        InputError: missing file, a missing or repeated column, or a cell that is not a finite number.
    """
    file = Path(path)
    if not _has_header(file):
        return _with_header(_csv_columns(read_text(file), file, COLUMNS), {"joint": joint}, file)
    arrays, header = _columns_and_header(file, COLUMNS)
    kind = header.get("joint", "revolute")  # a Parquet file's header has it checked already
    if kind not in ("revolute", "prismatic"):
        raise InputError(f"{file}: key 'joint': expected 'revolute' or 'prismatic', got {kind!r}")
    return _with_header(arrays, {**header, "joint": kind}, file)


def _has_header(file: Path) -> bool:
    """Whether a trajectory file is JSON or Parquet (with a header), not CSV."""
    return file.suffix.lower() == ".json" or _SUFFIXES.get(file.suffix.lower()) == "parquet"


def _columns_and_header(
    file: Path, required: tuple[str, ...], optional: tuple[str, ...] = ()
) -> tuple[dict[str, FloatArray], dict[str, Any]]:
    """The ``required`` (and present ``optional``) columns of a JSON or Parquet file, and its header."""
    if file.suffix.lower() == ".json":
        data = _json_object(read_text(file), file)
        return _json_columns(data, file, required, optional), data
    from drive_envelope._src.scenario.trajectory_parquet import read_parquet

    return read_parquet(file, required, optional=optional)


def _with_header(arrays: dict[str, FloatArray], header: dict[str, Any], file: Path) -> Trajectory:
    """A trajectory file's columns with its header (engine, name, joint, metadata; the stem for no name)."""
    metadata = header.get("metadata")
    return Trajectory(
        joint=header["joint"],
        engine=str(header.get("engine", "")),
        name=str(header.get("name", "") or file.stem),
        metadata=metadata if isinstance(metadata, dict) else {},
        **arrays,
    )


@dataclass(frozen=True, kw_only=True, slots=True)
class OperatingLog:
    """The columns of a trajectory file or bench log that a plot draws (no position needed)."""

    velocity: FloatArray
    """Joint velocity [rad/s or m/s]."""
    effort: FloatArray
    """Total actuator effort [N*m or N]."""
    time: FloatArray | None
    """Time [s], or None when the file has no time column."""
    engine: str = ""
    """Engine that produced it (from a JSON or Parquet trajectory's metadata), empty if unknown."""
    name: str = ""
    """Scenario name from the metadata, else the file's stem."""


_POINTS = ("velocity", "effort")
_POINTS_OPTIONAL = ("time",)


def read_operating_log(path: str | os.PathLike[str]) -> OperatingLog:
    """Read the ``velocity`` and ``effort`` (and, when present, ``time``) of a JSON or Parquet trajectory.

    The formats are those of :func:`read_trajectory`, which needs every column; here ``position``
    is not read and ``time`` may be absent, and the run's ``engine`` and ``name`` come with the
    numbers (SI). A CSV log is read by the one log reader (``analysis.logs.read_log``), as
    ``check`` and ``plot -t`` read it.

    Raises:
        InputError: missing file, a CSV file, a missing or repeated velocity/effort/time column,
            columns of different lengths (JSON), or a value that is not a finite number.
    """
    file = Path(path)
    if not _has_header(file):
        raise InputError(f"{file}: expected a JSON or Parquet trajectory; CSV logs go through read_log")
    arrays, header = _columns_and_header(file, _POINTS, _POINTS_OPTIONAL)
    return OperatingLog(
        velocity=arrays["velocity"],
        effort=arrays["effort"],
        time=arrays.get("time"),
        engine=str(header.get("engine", "")),
        name=str(header.get("name", "") or file.stem),
    )


def _cell(value: str | None, where: str) -> float:
    if value is None or value.strip() == "":
        return 0.0
    try:
        number = float(value)
    except ValueError:
        raise InputError(f"{where}: expected a number, got {value!r}") from None
    if not np.isfinite(number):  # a plot would drop it without a word
        raise InputError(f"{where}: got {value.strip()!r}; expected a finite number")
    return number


def _csv_columns(text: str, file: Path, required: tuple[str, ...]) -> dict[str, FloatArray]:
    """The ``required`` columns of a CSV trajectory (the file format of simulate: SI, exact names).

    Not the log reader of ``analysis`` (names up to case, units in headers): that layer is above
    this one, and this reads back only what :func:`write_trajectory_csv` writes.
    """
    reader = csv.reader(io.StringIO(text))
    try:
        header = [name.strip() for name in next(reader, [])]
        rows = list(reader)
    except csv.Error as exc:  # a field over the csv module's limit
        raise InputError(f"{file}: cannot read as CSV: {exc}") from None
    repeated = sorted({name for name in header if name in required and header.count(name) > 1})
    if repeated:
        raise InputError(f"{file}: column {repeated[0]!r} appears {header.count(repeated[0])} times")
    missing = [c for c in required if c not in header]
    if missing:
        with_unit = [cell for cell in header if cell.split("[")[0].split("(")[0].strip() in missing]
        hint = (
            f" (units in headers, as in {with_unit[0]!r}, are not read here: write SI numbers)"
            if with_unit
            else ""
        )
        raise InputError(
            f"{file}: missing column(s) {', '.join(missing)}; expected header {','.join(required)}{hint}"
        )
    index = {column: header.index(column) for column in required}
    columns: dict[str, list[float]] = {c: [] for c in index}
    for line, row in enumerate(rows, start=2):
        if not row:
            continue
        for column, position in index.items():
            cell = row[position] if position < len(row) else None
            columns[column].append(_cell(cell, f"{file}: line {line}, column {column!r}"))
    if not columns[required[0]]:
        raise InputError(f"{file}: no data rows")
    return {column: np.asarray(values) for column, values in columns.items()}


def _json_object(text: str, file: Path) -> dict[str, Any]:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{file}: malformed JSON: {exc}") from None
    except RecursionError:
        raise InputError(f"{file}: malformed JSON: nested too deeply") from None
    if not isinstance(data, dict):
        raise InputError(f"{file}: expected a JSON object with keys {', '.join(COLUMNS)}")
    return data


def _json_columns(
    data: dict[str, Any], file: Path, required: tuple[str, ...], optional: tuple[str, ...]
) -> dict[str, FloatArray]:
    """The ``required`` columns of a JSON trajectory and those of ``optional`` that it has."""
    arrays = {}
    for column in required + optional:
        if column in optional and column not in data:
            continue
        if not isinstance(data.get(column), list):
            raise InputError(f"{file}: key {column!r}: expected a list of numbers")
        arrays[column] = np.asarray(
            [_cell(str(v), f"{file}: key {column!r}, item {i}") for i, v in enumerate(data[column])]
        )
    if len({values.shape for values in arrays.values()}) != 1:
        lengths = ", ".join(f"{c} {values.shape[0]}" for c, values in arrays.items())
        raise InputError(f"{file}: the columns have different lengths ({lengths}); expected one per row")
    return arrays

"""Bench logs for identification: a joint's measured motion and the commands that caused it.

A log is a CSV (``.csv``, ``.tsv``, ``.txt``, optionally ``.gz``; ``#`` comment lines before the
header are skipped), a Parquet file (needs pyarrow) or one joint of a ROS 2 bag
(:mod:`drive_envelope._src.analysis.log_bag`: JointState states, targets from a command topic, a NaN
target for ``torque_enable = 0``) with the columns

========================  ===========  =========================================================
``time``                  required     sample time [s], on a uniform grid (the replay's step)
``position``              required     measured joint position [rad or m]
``target_position``       required     the drive's goal written at that sample [rad or m]
``velocity``              optional     measured joint velocity [rad/s or m/s] (initial state, MAE)
``effort``                optional     measured actuator effort [N*m or N] (plotted only)
``target_velocity``       optional     drive target velocity [rad/s or m/s]; 0 when absent
``torque_enable``         optional     1 = drive powered, 0 = unpowered (free swing); 1 when absent
========================  ===========  =========================================================

A header may give its column's unit after the name (``position [deg]``, ``time (ms)``): the values
are converted to SI, as ``check`` reads its logs. Other columns are ignored. Sample ``i``'s commands
act from ``time[i]`` to ``time[i + 1]``. A JSON sidecar beside the log (``NAME.json`` for
``NAME.csv``) may give ``kp_duty_per_rad``, the servo firmware's position gain as PWM duty per radian
of error (a voltage-driven servo such as a Dynamixel: see :mod:`drive_envelope._src.identify.stand`);
other sidecar keys are ignored.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.columns import ColumnPlan, Role, plan_columns
from drive_envelope._src.analysis.fit_input import MAX_SAMPLE
from drive_envelope._src.analysis.log_arrow import arrow_numeric
from drive_envelope._src.analysis.log_bag import BagOptions, is_bag, read_bag
from drive_envelope._src.analysis.log_csv import csv_rows, parse_cells
from drive_envelope._src.analysis.log_model import si_arrays
from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.stand import StandWarning
from drive_envelope._src.io.files import read_text
from drive_envelope._src.io.paths import input_file

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

_GRID_TOLERANCE = 0.01  # a time step may differ from the median step by 1 %
_PARQUET = (".parquet", ".pq")


@dataclass(frozen=True, kw_only=True, slots=True)
class BenchLog:
    """One bench log, SI, every array of one length (``rows``)."""

    path: str
    """The file it was read from."""
    time: FloatArray
    """Sample times [s]."""
    position: FloatArray
    """Measured joint position [rad or m]."""
    target_position: FloatArray
    """Drive target position at each sample [rad or m]."""
    target_velocity: FloatArray
    """Drive target velocity [rad/s or m/s] (zeros when the log has none)."""
    enabled: BoolArray
    """Drive powered at each sample (``torque_enable``; all True when absent)."""
    velocity: FloatArray | None = None
    """Measured joint velocity [rad/s or m/s], or None."""
    effort: FloatArray | None = None
    """Measured actuator effort [N*m or N], or None."""
    duty_per_rad: float | None = None
    """Servo gain as PWM duty per radian from the sidecar (``kp_duty_per_rad``) [1/rad], or None."""
    sidecar: Mapping[str, Any] | None = None
    """The whole JSON sidecar, or None (its ``name``, ``mass_kg``, ``length_m`` are checked
    against the log and the stand)."""

    @property
    def name(self) -> str:
        """The file name, which reports key results by."""
        return Path(self.path).name

    @property
    def rows(self) -> int:
        """Number of samples."""
        return int(self.time.shape[0])

    @property
    def dt(self) -> float:
        """The sampling step, the replay's time step [s]."""
        return float(np.median(np.diff(self.time)))


def read_bench_log(
    path: str | os.PathLike[str], *, bag: BagOptions | None = None, joint: str | None = None
) -> BenchLog:
    """Read a bench log (CSV, Parquet or a ROS 2 bag) and its optional JSON sidecar.

    Args:
        path: The log file, or a rosbag2 folder (or its ``.mcap`` / ``.db3`` file).
        bag: A bag's topics (:class:`~drive_envelope._src.analysis.log_bag.BagOptions`): the
            JointState topic and the command topic the targets come from (needed for a bag).
        joint: The joint of a bag to read; None: the bag's only joint.

    Raises:
        InputError: a missing file or column, a cell that is not a finite number (naming the row
            and column) or beyond 1e100 in magnitude, fewer than 3 rows, a time column off a
            uniform grid, a ``torque_enable`` other than 0/1, or a sidecar that is not a JSON object
            with a positive ``kp_duty_per_rad``; for a bag, no command topic or a joint it does not have.
    """
    file = Path(path)
    label = str(file)
    if is_bag(file):
        columns = _read_bag(file, label, bag or BagOptions(), joint)
    else:
        input_file(file, label, max_bytes=None, what="bench log file")  # a FIFO would block: refused
        if file.suffix.lower() == ".json":  # read as CSV it gave "no column ... (columns: {)"
            logs = [file.with_suffix(end) for end in (".csv", ".csv.gz", ".parquet")]
            log = next((candidate for candidate in logs if candidate.is_file()), logs[0])
            raise InputError(
                f"{label}: a JSON file, not a bench log (CSV, Parquet or a ROS 2 bag); a JSON file "
                f"beside a log is its sidecar: pass the log ({log.name}), its sidecar is read with it"
            )
        columns = _read_parquet(file, label) if file.suffix.lower() in _PARQUET else _read_csv(file, label)
    sidecar = _sidecar(file)
    rows = columns["time"].shape[0]
    if rows < 3:
        raise InputError(f"{label}: {rows} data rows; expected at least 3 samples")
    _check_coarse(_check_grid(columns["time"], label), label)
    _check_magnitudes(columns, label)
    enable = columns.get("torque_enable")
    if enable is not None and not np.isin(enable, (0.0, 1.0)).all():
        row = int(np.flatnonzero(~np.isin(enable, (0.0, 1.0)))[0])
        raise InputError(
            f"{label}: row {row + 1}, column 'torque_enable': got {float(enable[row])!r}; expected 0 or 1"
        )
    return BenchLog(
        path=label,
        time=columns["time"],
        position=columns["position"],
        target_position=columns["target_position"],
        target_velocity=columns.get("target_velocity", np.zeros(rows)),
        enabled=(enable != 0.0) if enable is not None else np.ones(rows, dtype=np.bool_),
        velocity=columns.get("velocity"),
        effort=columns.get("effort"),
        duty_per_rad=None if sidecar is None else _sidecar_duty(sidecar, file),
        sidecar=sidecar,
    )


BENCH_ROLES = (
    Role(role="time", column="time", required=True, quantity="time"),
    Role(role="position", column="position", required=True, quantity="position"),
    Role(role="target_position", column="target_position", required=True, quantity="position"),
    Role(role="velocity", column="velocity", quantity="velocity"),
    Role(role="effort", column="effort", quantity="effort"),
    Role(role="target_velocity", column="target_velocity", quantity="velocity"),
    Role(role="torque_enable", column="torque_enable", meaning="0 or 1 per sample"),
)
"""The columns of a bench log as roles of the one column plan: each its own name, its quantity for a
unit in the header (``torque_enable`` takes none)."""


def bench_plan(header: list[str], label: str) -> ColumnPlan:
    """Column index and SI scale of each bench-log column in ``header`` (check's rule and messages).

    Raises:
        InputError: a name twice (up to case), missing required columns, a bad unit, or units of
            two joint types (:func:`~drive_envelope._src.analysis.columns.plan_columns`).
    """
    return plan_columns(header, BENCH_ROLES, label, needs="a bench log")


def _read_bag(file: Path, label: str, options: BagOptions, joint: str | None) -> dict[str, FloatArray]:
    """A bag joint's columns: states from ``options.topic``, targets from ``options.command_topic``."""
    if options.command_topic is None:
        raise InputError(
            f"{label}: a ROS 2 bag needs --command-topic (the targets: JointState, JointTrajectory or "
            "Float64MultiArray) to be replayed"
        )
    joints = read_bag(file, options)
    names = [item.name for item in joints]
    if joint is None:
        if len(joints) != 1:
            raise InputError(f"{label}: the bag has joints {', '.join(names)}; name one with --joint")
        chosen = joints[0]
    elif joint in names:
        chosen = joints[names.index(joint)]
    else:
        raise InputError(f"{label}: --joint {joint!r}: not in the bag's joints ({', '.join(names)})")
    columns = {"time": chosen.time, **chosen.columns}
    for column in ("position", "target_position"):
        if column not in columns:
            what = "the state topic's position" if column == "position" else "a command for this joint"
            raise InputError(f"{label}: joint {chosen.name!r} has no {column}: expected {what}")
    plan = bench_plan(list(columns), label)  # SI already: the cell rule only
    return si_arrays(plan, {column: columns[column] for column in plan.numeric}, 1)


def _read_csv(file: Path, label: str) -> dict[str, FloatArray]:
    header, rows = csv_rows(file, label)  # check's CSV rules: comments, delimiter, BOM, .gz
    plan = bench_plan(header, label)
    width = max(plan.position.values()) + 1
    for row, fields in enumerate(rows, start=1):
        if len(fields) < width:
            raise InputError(f"{label}: row {row}: {len(fields)} fields, the header has {len(header)}")
    return si_arrays(plan, parse_cells(rows, plan, 1), 1, lambda role, i: rows[i][plan.position[role]])


def _read_parquet(file: Path, label: str) -> dict[str, FloatArray]:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise InputError(
            f"{label}: reading Parquet needs pyarrow (pip install 'drive-envelope[parquet]')"
        ) from None
    try:
        table = pq.read_table(file)
    except (OSError, pa.ArrowException) as exc:
        raise InputError(f"{label}: cannot read as Parquet: {' '.join(str(exc).split())}") from None
    plan = bench_plan(list(table.column_names), label)
    columns = {}
    for column, index in plan.position.items():
        data = table.column(index)
        if pa.types.is_boolean(data.type):  # torque_enable written as True/False
            data = data.cast(pa.int8())
        columns[column] = arrow_numeric(data, plan.name(column), label)  # check's type rule; nulls: NaN
    return si_arrays(plan, columns, 1)


def _check_grid(time: FloatArray, label: str) -> float:
    """The log's sampling step [s]; a time that does not increase, or off a uniform grid, is refused."""
    steps = np.diff(time)
    dt = float(np.median(steps))
    if not dt > 0.0:
        raise InputError(f"{label}: column 'time' does not increase (median step {dt!r} s)")
    off = np.flatnonzero(np.abs(steps - dt) > _GRID_TOLERANCE * dt)
    if off.size:
        row = int(off[0]) + 2
        raise InputError(
            f"{label}: row {row}, column 'time': step {float(steps[off[0]]):.6g} s; expected a uniform grid "
            f"of {dt:.6g} s (+-{100 * _GRID_TOLERANCE:g} %): resample the log"
        )
    return dt


COARSEST_STEP = 0.1
"""A log sampled coarser than this [s] draws a warning: the replay steps at the log's own step."""


def _check_coarse(dt: float, label: str) -> None:
    """Warn where the sampling step is coarser than :data:`COARSEST_STEP` (a time in ms read as s).

    A bare ``time`` header is seconds: a servo log in milliseconds read so replayed at 5 s steps
    (reference and PhysX 643 mrad, MuJoCo diverging to 647 rad), silently.
    """
    if dt > COARSEST_STEP:
        warnings.warn(
            f"{label}: samples {dt:.6g} s apart, and the replay steps at the log's own step: a drive needs "
            f"steps of {COARSEST_STEP:g} s or less; a time in ms or us needs its unit in the header "
            "('time [ms]'; a bare 'time' is seconds)",
            StandWarning,
            stacklevel=3,
        )


def _check_magnitudes(columns: Mapping[str, FloatArray], label: str) -> None:
    """Refuse a state or target beyond ``MAX_SAMPLE`` [SI], as ``fit`` does.

    The search squares the position errors (and scales its loss by them): a cell of 1e300 overflowed
    inside SciPy, and a replay printed a 300-digit error. Real joints stay below 1e6 rad or m.
    """
    for name in ("position", "target_position", "velocity", "effort", "target_velocity"):
        values = columns.get(name)
        if values is None:
            continue
        beyond = np.flatnonzero(np.abs(values) > MAX_SAMPLE)
        if beyond.size:
            row = int(beyond[0])
            raise InputError(
                f"{label}: row {row + 1}, column {name!r}: got {float(values[row]):.6g} [SI]; expected "
                f"|{name}| at most {MAX_SAMPLE:g} (check the log's units)"
            )


def sidecar_candidates(file: Path) -> list[Path]:
    """Where the log's JSON sidecar may be, in order.

    ``NAME.json`` beside ``NAME.csv``, ``NAME.csv.gz`` or ``NAME.parquet``; the log's whole name with
    ``.json`` (``NAME.csv.json``, ``NAME.csv.gz.json``); for a bag, ``BAG.json`` beside the bag folder,
    also when the bag is given by its ``.mcap`` / ``.db3`` file (the same log as its folder).
    """
    stem = file.with_suffix("") if file.suffix.lower() == ".gz" else file
    found = [stem.with_suffix(".json"), file.with_name(file.name + ".json")]
    if not file.is_dir() and is_bag(file) and (file.parent / "metadata.yaml").is_file():
        found.append(file.parent.with_suffix(".json"))
    return list(dict.fromkeys(found))


def _sidecar(file: Path) -> dict[str, Any] | None:
    """The log's JSON sidecar (:func:`sidecar_candidates`), or None; two of them are refused."""
    present = [path for path in sidecar_candidates(file) if path.exists() or path.is_symlink()]
    if len(present) > 1:
        raise InputError(
            f"{file}: two sidecars ({', '.join(str(p) for p in present)}): keep one, the log's settings "
            "would depend on which is read"
        )
    if not present:
        return None
    sidecar = present[0]
    text = read_text(sidecar)  # a FIFO, /dev/zero or an oversized file beside the log: refused
    try:
        data: Any = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(
            f"{sidecar}: cannot read the log's JSON sidecar: {' '.join(str(exc).split())}"
        ) from None
    if not isinstance(data, dict):
        raise InputError(f"{sidecar}: expected a JSON object (the log's sidecar)")
    _sidecar_duty(data, sidecar)
    return data


def _sidecar_duty(data: dict[str, Any], sidecar: Path) -> float | None:
    """The sidecar's ``kp_duty_per_rad`` [1/rad], or None; anything but a number > 0 is refused."""
    value = data.get("kp_duty_per_rad")
    if value is None:
        return None
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not (math.isfinite(value) and value > 0)
    ):
        raise InputError(f"{sidecar}: key 'kp_duty_per_rad': expected a number > 0 [1/rad], got {value!r}")
    return float(value)

"""ROS 2 bags as logs: ``sensor_msgs/JointState`` samples and a command topic, per joint.

A bag is a rosbag2 folder (``metadata.yaml`` beside ``.mcap`` or ``.db3`` files) or one of its
``.mcap`` / ``.db3`` files; the pure-Python ``rosbags`` library reads both storage formats (the
``ros`` extra). What is read:

* **States**: the ``sensor_msgs/msg/JointState`` topic ``topic`` (default: the bag's only one
  besides the command topic).
  Joints are found by name in each message (``name[i]`` goes with ``position[i]``, ``velocity[i]``,
  ``effort[i]``; an empty array means the message does not carry that quantity). Each joint is one
  sample per message that names it.
* **Commands** (optional): ``command_topic``, one of ``sensor_msgs/msg/JointState`` (``position``
  and ``velocity`` are the targets), ``trajectory_msgs/msg/JointTrajectory`` (its first point: the
  setpoint a ros2_control controller acts on now) or ``std_msgs/msg/Float64MultiArray`` (``data[i]``
  for the ``i``-th joint of ``joint_order``, by default the order of the first state message: the
  forward controllers' convention; it has no header, so its time is the bag's receive time). A
  sample's target is the latest command at or before its time
  (samples before the first command take the first); a NaN position target means the drive is
  off (``torque_enable = 0``), as ros2_control writes NaN for "no command".
* **Time**: the message header's stamp (``time = "header"``, the default; a bag whose stamps are all
  zero falls back to the bag's receive time) or the bag's receive time (``"bag"``), in seconds from
  the first state sample, computed in integer nanoseconds so a long bag keeps its step exact.

The result is a long table per joint (:func:`bag_table`): ``time``, ``joint``, ``position``,
``velocity``, ``effort``, ``target_position``, ``target_velocity``, ``torque_enable``, read by the
same column rules as a CSV (:mod:`.log_model`), so check, fit, identify and replay all take bags.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError

FloatArray = npt.NDArray[np.float64]
BAG_SUFFIXES = (".mcap", ".db3")
"""Storage files of a rosbag2 bag (its folder has ``metadata.yaml`` beside them)."""
_STATE = "sensor_msgs/msg/JointState"
_COMMANDS = (_STATE, "trajectory_msgs/msg/JointTrajectory", "std_msgs/msg/Float64MultiArray")


@dataclass(frozen=True, kw_only=True, slots=True)
class BagOptions:
    """What to read from a bag."""

    topic: str | None = None
    """The ``sensor_msgs/msg/JointState`` topic of the measured states; None: the bag's only one."""
    command_topic: str | None = None
    """The topic of the targets (JointState, JointTrajectory or Float64MultiArray), or None."""
    joint_order: tuple[str, ...] = ()
    """Joint names of a Float64MultiArray command's ``data``, in order; empty: the state order."""
    time: str = "header"
    """``"header"`` (message stamps) or ``"bag"`` (receive times)."""

    def __post_init__(self) -> None:
        if self.time not in ("header", "bag"):
            raise InputError(f"bag time: expected 'header' or 'bag', got {self.time!r}")


@dataclass(frozen=True, kw_only=True, slots=True)
class BagJoint:
    """One joint's samples from a bag, SI."""

    name: str
    """The joint name in the messages."""
    time: FloatArray
    """Sample time from the first state sample of the bag [s]."""
    columns: dict[str, FloatArray] = field(default_factory=dict)
    """``position`` [rad or m], ``velocity`` [rad/s or m/s], ``effort`` [N*m or N] when the
    messages carry them; with a command topic ``target_position``, ``target_velocity``,
    ``torque_enable`` (1 or 0)."""


def is_bag(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a rosbag2 folder or one of its storage files."""
    file = Path(path)
    if file.is_dir():
        return (file / "metadata.yaml").is_file()
    return file.suffix.lower() in BAG_SUFFIXES


def _bag_folder(path: Path, label: str) -> Path:
    if path.is_dir():
        return path
    if not path.is_file():
        raise InputError(f"{label}: no such file")
    if (path.parent / "metadata.yaml").is_file():
        return path.parent
    raise InputError(
        f"{label}: a ROS 2 bag file needs the bag's metadata.yaml beside it (give the bag folder)"
    )


def read_bag(path: str | os.PathLike[str], options: BagOptions | None = None) -> list[BagJoint]:
    """Read the joints of a bag (see the module docstring).

    Raises:
        InputError: rosbags missing, an unreadable bag, a missing or ambiguous topic, a topic of
            another type, a command for a joint the states do not have, or no state samples.
    """
    options = options or BagOptions()
    label = str(path)
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise InputError(
            f"{label}: reading ROS 2 bags needs rosbags (pip install 'drive-envelope[ros]')"
        ) from None
    folder = _bag_folder(Path(path), label)
    try:
        with AnyReader([folder], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
            states = _connection(reader, options.topic, (_STATE,), "--topic", label, options.command_topic)
            commands = (
                _connection(reader, options.command_topic, _COMMANDS, "--command-topic", label)
                if options.command_topic is not None
                else None
            )
            state_rows = _state_rows(reader, states, options.time)
            command_rows = _command_rows(reader, commands, options, state_rows) if commands else None
    except InputError:
        raise
    except Exception as exc:  # rosbags raises its own error types for damaged bags
        raise InputError(f"{label}: cannot read as a ROS 2 bag: {' '.join(str(exc).split())}") from None
    if not state_rows["order"]:
        raise InputError(f"{label}: topic {states.topic!r} has no joint samples")
    return _joints(state_rows, command_rows, label)


def _connection(
    reader: Any, topic: str | None, types: Sequence[str], flag: str, label: str, other: str | None = None
) -> Any:
    found = [c for c in reader.connections if c.msgtype in types and c.topic != other]
    if topic is None:
        topics = sorted({c.topic for c in found})
        if len(topics) != 1:
            listed = ", ".join(topics) or "none"
            raise InputError(
                f"{label}: {len(topics)} {' or '.join(types)} topics ({listed}); name one with {flag}"
            )
        topic = topics[0]
    named = [c for c in reader.connections if c.topic == topic]
    if not named:
        listed = ", ".join(sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections})) or "none"
        raise InputError(f"{label}: {flag} {topic!r}: no such topic; the bag has {listed}")
    if named[0].msgtype not in types:
        raise InputError(f"{label}: {flag} {topic!r} is {named[0].msgtype}; expected {' or '.join(types)}")
    return named[0]


def _stamp(message: Any, timestamp: int, time: str) -> int:
    if time == "bag":
        return int(timestamp)
    stamp = message.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _state_rows(reader: Any, connection: Any, time: str) -> dict[str, Any]:
    """Per joint: stamps [ns] and the quantities of each message that names it."""
    rows: dict[str, dict[str, list[float]]] = {}
    bag_times: dict[str, list[int]] = {}
    order: list[str] = []
    for conn, timestamp, raw in reader.messages(connections=[connection]):
        message = reader.deserialize(raw, conn.msgtype)
        stamp = _stamp(message, timestamp, time)
        for i, name in enumerate(message.name):
            if name not in rows:
                rows[name] = {"stamp": [], "position": [], "velocity": [], "effort": []}
                bag_times[name] = []
                order.append(name)
            row = rows[name]
            row["stamp"].append(stamp)
            bag_times[name].append(int(timestamp))
            for key in ("position", "velocity", "effort"):
                values = getattr(message, key)
                row[key].append(float(values[i]) if len(values) > i else math.nan)
    if time == "header" and rows and all(not any(row["stamp"]) for row in rows.values()):
        for name, row in rows.items():  # stamps never set: the recorder's receive times
            row["stamp"] = bag_times[name]  # type: ignore[assignment]
    return {"rows": rows, "order": order}


def _command_rows(
    reader: Any, connection: Any, options: BagOptions, states: dict[str, Any]
) -> dict[str, Any]:
    """Per joint: command stamps [ns], target positions and velocities."""
    order = list(options.joint_order) or list(states["order"])
    rows: dict[str, dict[str, list[float]]] = {}
    for conn, timestamp, raw in reader.messages(connections=[connection]):
        message = reader.deserialize(raw, conn.msgtype)
        if conn.msgtype == _STATE:
            names, positions, velocities = message.name, message.position, message.velocity
            stamp = _stamp(message, timestamp, options.time)
        elif conn.msgtype == _COMMANDS[1]:
            if not message.points:
                continue
            point = message.points[0]
            names, positions, velocities = message.joint_names, point.positions, point.velocities
            stamp = _stamp(message, timestamp, options.time)
        else:  # Float64MultiArray: no header
            names, positions, velocities = order, message.data, ()
            stamp = int(timestamp)
            if len(positions) != len(order):
                raise InputError(
                    f"{options.command_topic}: a Float64MultiArray of {len(positions)} values for "
                    f"{len(order)} joints ({', '.join(order)}); give the joint order"
                )
        for i, name in enumerate(names):
            row = rows.setdefault(name, {"stamp": [], "position": [], "velocity": []})
            row["stamp"].append(stamp)
            row["position"].append(float(positions[i]) if len(positions) > i else math.nan)
            row["velocity"].append(float(velocities[i]) if len(velocities) > i else 0.0)
    return rows


def _joints(states: dict[str, Any], commands: dict[str, Any] | None, label: str) -> list[BagJoint]:
    rows = states["rows"]
    first = min(min(row["stamp"]) for row in rows.values())
    if commands is not None:
        unknown = sorted(set(commands) - set(rows))
        if unknown:
            raise InputError(
                f"{label}: the command topic names joint(s) {', '.join(unknown)} the states do not have "
                f"({', '.join(states['order'])})"
            )
    joints = []
    for name in states["order"]:
        row = rows[name]
        stamps = np.asarray(row["stamp"], dtype=np.int64)
        columns = {}
        for key in ("position", "velocity", "effort"):
            values = np.asarray(row[key], dtype=np.float64)
            if not np.isnan(values).all():
                columns[key] = values
        if commands is not None and name in commands:
            columns.update(_held(commands[name], stamps))
        joints.append(BagJoint(name=name, time=(stamps - first) * 1e-9, columns=columns))
    return joints


def _held(command: dict[str, list[float]], stamps: npt.NDArray[np.int64]) -> dict[str, FloatArray]:
    """The latest command at or before each sample (the first one before it); NaN position = off."""
    times = np.asarray(command["stamp"], dtype=np.int64)
    order = np.argsort(times, kind="stable")
    index = np.clip(np.searchsorted(times[order], stamps, side="right") - 1, 0, None)
    target = np.asarray(command["position"], dtype=np.float64)[order][index]
    velocity = np.asarray(command["velocity"], dtype=np.float64)[order][index]
    enabled = np.isfinite(target)
    # a switched-off drive's target is never used: hold the last finite one so the column is numbers
    last = np.maximum.accumulate(np.where(enabled, np.arange(target.size), -1))
    first = target[enabled][0] if enabled.any() else 0.0
    held = np.where(last >= 0, target[np.maximum(last, 0)], first)
    return {
        "target_position": held,
        "target_velocity": np.where(enabled & np.isfinite(velocity), velocity, 0.0),
        "torque_enable": enabled.astype(np.float64),
    }


def bag_table(joints: Sequence[BagJoint]) -> dict[str, Any]:
    """The joints as one long table: ``joint`` names and every column the joints all have."""
    shared = set.intersection(*(set(joint.columns) for joint in joints)) if joints else set()
    ordered = [key for key in ("position", "velocity", "effort", "target_position", "target_velocity",
                               "torque_enable") if key in shared]  # fmt: skip
    table: dict[str, Any] = {
        "time": np.concatenate([joint.time for joint in joints]),
        "joint": np.concatenate([np.full(joint.time.shape, joint.name, dtype=object) for joint in joints]),
    }
    for key in ordered:
        table[key] = np.concatenate([joint.columns[key] for joint in joints])
    return table

"""Command-line options shared by ``drive-envelope check``, ``fit``, ``identify`` and ``replay``.

argparse only: a light import.
"""

from __future__ import annotations

import argparse
from typing import Any


def add_column_arguments(parser: argparse.ArgumentParser, *, time: bool = True) -> None:
    """Add ``--velocity-column``, ``--effort-column``, ``--joint-column`` (and ``--time-column``)."""
    group = parser.add_argument_group("log columns (defaults: the CSV of `drive-envelope simulate`)")
    group.add_argument(
        "--velocity-column", default="velocity", metavar="C", help="joint velocity [rad/s or m/s]"
    )
    group.add_argument(
        "--effort-column", default="effort", metavar="C", help="total actuator effort [N*m or N]"
    )
    if time:
        group.add_argument(
            "--time-column", default=None, metavar="C", help="time [s] (default: 'time' when the log has it)"
        )
    group.add_argument(
        "--joint-column",
        default=None,
        metavar="C",
        help="joint name of a long-format log with several joints (default: 'joint' when the log has it)",
    )
    add_bag_arguments(parser)


def add_bag_arguments(parser: argparse.ArgumentParser, *, joint: bool = False) -> None:
    """Add ``--topic``, ``--command-topic``, ``--command-joints``, ``--bag-time`` for ROS 2 bags.

    ``joint``: also ``--joint``, the one joint of a bag that a bench log is read from.
    """
    group = parser.add_argument_group("ROS 2 bags (a rosbag2 folder or its .mcap/.db3; the ros extra)")
    group.add_argument(
        "--topic", default=None, metavar="TOPIC", help="sensor_msgs/JointState topic (default: the only one)"
    )
    group.add_argument(
        "--command-topic",
        default=None,
        metavar="TOPIC",
        help="targets: JointState, JointTrajectory (first point) or Float64MultiArray; NaN = drive off",
    )
    group.add_argument(
        "--command-joints",
        default=None,
        metavar="A,B,...",
        help="joint order of a Float64MultiArray command (default: the JointState order)",
    )
    group.add_argument(
        "--bag-time",
        choices=("header", "bag"),
        default="header",
        help="sample time from the message header stamps (default) or the bag's receive times",
    )
    if joint:
        parser.add_argument(
            "--joint", default=None, metavar="NAME", help="the joint of a bag (default: its only one)"
        )


def bag_from_args(args: argparse.Namespace) -> Any:
    """The :class:`~drive_envelope._src.analysis.log_bag.BagOptions` the flags name."""
    from drive_envelope._src.analysis.log_bag import BagOptions

    joints = getattr(args, "command_joints", None)
    return BagOptions(
        topic=args.topic,
        command_topic=getattr(args, "command_topic", None),
        joint_order=tuple(name.strip() for name in joints.split(",") if name.strip()) if joints else (),
        time=args.bag_time,
    )


def columns_from_args(args: argparse.Namespace) -> Any:
    """The :class:`LogColumns` the flags name; an explicitly named column must exist."""
    from drive_envelope._src.analysis.logs import LogColumns

    time = getattr(args, "time_column", None)
    return LogColumns(
        velocity=args.velocity_column,
        effort=args.effort_column,
        time=time or "time",
        joint=args.joint_column or "joint",
        require_time=time is not None,
        require_joint=args.joint_column is not None,
        bag=bag_from_args(args),
    )

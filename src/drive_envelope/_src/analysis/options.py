"""Command-line options shared by ``drive-envelope check`` and ``fit`` (argparse only: a light import)."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["add_column_arguments", "columns_from_args"]


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
    )

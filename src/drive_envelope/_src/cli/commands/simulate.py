"""``drive-envelope simulate FILE``: run a test-stand scenario and write its trajectory."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from drive_envelope._src.cli.common import add_output_argument


def register(subparsers: Any) -> None:
    """Add the ``simulate`` command."""
    from drive_envelope._src.teststand.engines import ENGINES

    parser = subparsers.add_parser(
        "simulate",
        help="simulate one actuated joint with the PhysX drive and envelope",
        description=(
            "Run a test-stand scenario (one joint, fixed base, rigid inertia) and write time, position, "
            "velocity and the step-average total actuator effort (SI) as CSV or JSON."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="scenario file (TOML, JSON or YAML)")
    parser.add_argument(
        "--engine",
        choices=tuple(ENGINES),
        default="reference",
        help="reference (float64 model of the PhysX solver, default), mujoco, physx (real PhysX via ovphysx)",
    )
    add_output_argument(parser, "trajectory file, atomically; '-' or absent: stdout", metavar="OUT")
    parser.add_argument(
        "--format", choices=("csv", "json"), help="output format (default: from the suffix, else csv)"
    )
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="SECTION.KEY=VALUE",
        help="override a scenario value, e.g. --set drive.target_velocity=12 (repeatable)",
    )
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.cli.common import checked_output, status
    from drive_envelope._src.scenario.spec import load_scenario
    from drive_envelope._src.scenario.trajectory import (
        save_trajectory,
        trajectory_to_csv,
        trajectory_to_json,
    )
    from drive_envelope._src.teststand.engines import simulate

    scenario = load_scenario(args.file, args.overrides)
    trajectory = simulate(scenario, args.engine)
    if args.output in (None, "-"):
        text = trajectory_to_json(trajectory) if args.format == "json" else trajectory_to_csv(trajectory)
        sys.stdout.write(text)
        return 0
    output = checked_output(args.output)
    assert output is not None
    save_trajectory(trajectory, output, format=args.format)
    status(_summary(trajectory, output))
    return 0


def _summary(trajectory: Any, output: str) -> str:
    import numpy as np

    units = trajectory.units
    effort = np.abs(trajectory.effort[1:]) if len(trajectory) > 1 else np.zeros(1)
    return (
        f"wrote {len(trajectory)} rows to {output} (engine {trajectory.engine}): "
        f"final velocity {trajectory.velocity[-1]:.6g} {units['velocity']}, "
        f"final position {trajectory.position[-1]:.6g} {units['position']}, "
        f"peak |effort| {effort.max():.6g} {units['effort']}"
    )

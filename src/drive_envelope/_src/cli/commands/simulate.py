"""``drive-envelope simulate FILE``: run a test-stand scenario and write its trajectory."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from drive_envelope._src.cli.common import add_force_argument, add_output_argument, integer_at_least

DEFAULT_MAX_STEPS = 10**6
"""Most steps a run takes unless ``--max-steps`` raises it: minutes of the reference engine, not hours."""

ANNOUNCED_STEPS = 10**4
"""Runs of more steps say what they will cost (steps, time, memory) on stderr before they start."""

_SECONDS_PER_STEP = {"reference": 4e-4}
"""Measured cost of one step [s] (reference: 1e5 steps in 39 s of CPU on the CI machine)."""

_BYTES_PER_STEP = 32 + 70  # float64 arrays of the run, plus a CSV/JSON row of the output [bytes]


def register(subparsers: Any) -> None:
    """Add the ``simulate`` command."""
    from drive_envelope._src.teststand.engines import ENGINES

    parser = subparsers.add_parser(
        "simulate",
        help="simulate one actuated joint with the PhysX drive and envelope",
        description=(
            "Run a test-stand scenario (one joint, fixed base, rigid inertia; or a chain of links with a "
            "[[joints]] list, engines reference, physx and mujoco) and write time, position, velocity and "
            "the "
            "step-average total actuator effort (SI) as CSV, JSON or Parquet. A run of "
            "more than --max-steps steps is refused before it starts; long runs show their progress on "
            "stderr when it is a terminal."
        ),
    )
    parser.add_argument("file", metavar="FILE", help="scenario file (TOML, JSON or YAML)")
    parser.add_argument(
        "--engine",
        choices=tuple(ENGINES),
        default="reference",
        help=(
            "reference (float64 model of the PhysX solver, default), mujoco (the native plugin), "
            "physx (real PhysX via ovphysx), newton (Featherstone with the implicit actuator)"
        ),
    )
    add_output_argument(
        parser, "trajectory file (.csv, .json, .parquet), atomically; '-' or absent: stdout", metavar="OUT"
    )
    parser.add_argument(
        "--format",
        choices=("csv", "json", "parquet"),
        help="output format (default: from the suffix, else csv; parquet needs a file and pyarrow)",
    )
    parser.add_argument(
        "--json", dest="format", action="store_const", const="json", help="short for --format json"
    )
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="SECTION.KEY=VALUE",
        help="override a scenario value, e.g. --set drive.target_velocity=12 (repeatable)",
    )
    parser.add_argument(
        "--max-steps",
        type=integer_at_least(1),
        default=DEFAULT_MAX_STEPS,
        metavar="N",
        help=(
            f"refuse runs of more than N time steps (default {DEFAULT_MAX_STEPS:.0e}; the reference "
            "engine takes about 0.4 ms and 100 bytes per step); runs of more than "
            f"{ANNOUNCED_STEPS:.0e} steps say their cost on stderr first"
        ),
    )
    add_force_argument(parser)
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.cli.common import (
        Progress,
        checked_output,
        printed_warnings,
        refuse_input_as_output,
        status,
    )
    from drive_envelope._src.errors import EngineWarning, InputError
    from drive_envelope._src.scenario.chain import ChainScenario, load_stand
    from drive_envelope._src.scenario.trajectory import (
        Trajectory,
        save_trajectory,
        write_trajectory_csv,
        write_trajectory_json,
    )
    from drive_envelope._src.teststand.engines import check_steps, engine_module, simulate

    to_stdout = args.output in (None, "-")
    output = None if to_stdout else checked_output(args.output)
    refuse_input_as_output(output, args.file, "the scenario", "the trajectory")
    chosen = _output_format(args.format, output)  # before the run: a bad output wastes no simulation
    if output is not None:
        from drive_envelope._src.io.atomic import check_writable

        check_writable(output, force=args.force)
    scenario = load_stand(args.file, args.overrides)  # [[joints]]: a multi-DOF chain
    if isinstance(scenario, ChainScenario) and chosen == "parquet":
        raise InputError(f"--output {args.output!r}: chain trajectories are written as CSV or JSON")
    try:
        steps = check_steps(scenario, args.max_steps)
    except InputError as exc:
        raise InputError(f"{args.file}: {exc}") from None
    _say_rounded_duration(scenario.simulation.duration, scenario.simulation.dt, steps)
    _say_cost(steps, args.engine)
    engine_module(args.engine)  # a missing extra is reported as such, not as a problem of the file
    progress = Progress(f"simulate {args.engine}")
    with printed_warnings(EngineWarning, once=False):  # where an engine is known to part from PhysX
        try:
            trajectory = simulate(scenario, args.engine, max_steps=args.max_steps, progress=progress)
        except InputError as exc:  # the run failed on this file's values: say which file
            raise InputError(f"{args.file}: {exc}") from None
        finally:
            progress.close()
    if not isinstance(trajectory, Trajectory):
        return _write_chain(trajectory, output, chosen, args.force)
    if output is None:
        writer = write_trajectory_json if chosen == "json" else write_trajectory_csv
        writer(trajectory, sys.stdout)
        return 0
    save_trajectory(trajectory, output, format=chosen, force=args.force)
    status(_summary(trajectory, output))
    return 0


def _write_chain(trajectory: Any, output: str | None, chosen: str, force: bool) -> int:
    """Write a chain run's trajectory (CSV or JSON, ``<joint>.<quantity>`` columns)."""
    from drive_envelope._src.cli.common import status
    from drive_envelope._src.scenario.chain_trajectory import (
        chain_trajectory_to_csv,
        chain_trajectory_to_json,
        save_chain_trajectory,
    )

    if output is None:
        sys.stdout.write(
            chain_trajectory_to_json(trajectory) if chosen == "json" else chain_trajectory_to_csv(trajectory)
        )
        return 0
    save_chain_trajectory(trajectory, output, format=chosen, force=force)
    finals = ", ".join(
        f"{name} {v:.6g}" for name, v in zip(trajectory.joints, trajectory.velocity[-1], strict=True)
    )
    status(
        f"wrote {len(trajectory)} rows of {len(trajectory.joints)} joints to {output} "
        f"(engine {trajectory.engine}): final velocities {finals}"
    )
    return 0


def _say_cost(steps: int, engine: str) -> None:
    """Say on stderr what a long run will cost before it starts: steps, time and memory."""
    from drive_envelope._src.cli.common import status
    from drive_envelope._src.io.paths import describe_size

    if steps <= ANNOUNCED_STEPS:
        return
    per_step = _SECONDS_PER_STEP.get(engine)
    time = f"about {_duration(steps * per_step)}" if per_step else "time not estimated for this engine"
    status(
        f"simulate: {steps} steps with the {engine} engine: {time}, about "
        f"{describe_size(steps * _BYTES_PER_STEP)} of memory and output"
    )


def _duration(seconds: float) -> str:
    """``seconds`` in words: ``'40 s'``, ``'6.7 min'``, ``'11 h'``."""
    if seconds < 120:
        return f"{seconds:.2g} s"
    if seconds < 7200:
        return f"{seconds / 60:.2g} min"
    return f"{seconds / 3600:.2g} h"


def _say_rounded_duration(duration: float, dt: float, steps: int) -> None:
    """Say on stderr when the run ends elsewhere than ``duration`` (not a whole number of steps)."""
    from drive_envelope._src.cli.common import status

    if abs(steps * dt - duration) > 0.01 * dt:  # a dt written to a few digits (0.0083333) is no news
        status(
            f"simulation.duration = {duration:g} s is not a whole number of steps of dt = {dt:g} s: "
            f"simulating round(duration / dt) = {steps} step{'s' if steps != 1 else ''}, to {steps * dt:g} s"
        )


def _output_format(format: str | None, output: str | None) -> Any:
    from drive_envelope._src.errors import InputError
    from drive_envelope._src.scenario.trajectory import trajectory_format
    from drive_envelope._src.scenario.trajectory_parquet import have_parquet

    if output is None:
        if format == "parquet":
            raise InputError("--format parquet: Parquet is binary; give a file with --output run.parquet")
        return format or "csv"
    chosen = trajectory_format(output, format)
    if chosen == "parquet" and not have_parquet():
        raise InputError(
            f"--output {output!r}: Parquet needs pyarrow (pip install 'drive-envelope[parquet]'); "
            "or write .csv or .json"
        )
    return chosen


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

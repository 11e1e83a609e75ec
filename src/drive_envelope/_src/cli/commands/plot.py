"""``drive-envelope plot ENVELOPE``: draw the feasible region and, optionally, trajectories over it."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import add_output_argument


def register(subparsers: Any) -> None:
    """Add the ``plot`` command."""
    parser = subparsers.add_parser(
        "plot",
        help="plot an envelope (and trajectories) in the (velocity, effort) plane",
        description=(
            "Draw the envelope's feasible region in all four quadrants, each boundary line labelled with its "
            "equation, corners annotated; with --trajectory, the operating points coloured by time and a "
            "second panel with velocity and effort against time. Needs the 'plot' extra (matplotlib)."
        ),
    )
    parser.add_argument(
        "envelope",
        metavar="ENVELOPE_OR_DATASHEET",
        help="envelope file, datasheet file, catalog actuator name, or a scenario file with an [envelope]",
    )
    parser.add_argument(
        "--trajectory",
        "-t",
        action="append",
        default=[],
        metavar="CSV",
        help="a trajectory written by `drive-envelope simulate` (CSV or JSON); repeat for several",
    )
    add_output_argument(parser, "figure file: .png, .svg or .pdf", required=True, metavar="FIG")
    parser.add_argument("--title", default=None, help="figure title (default: the envelope's name)")
    parser.add_argument("--dpi", type=int, default=120, help="resolution of raster output (default 120)")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.cli.common import checked_output, status
    from drive_envelope._src.plots.curve import OperatingPoints
    from drive_envelope._src.plots.figure import plot_envelope, save_figure
    from drive_envelope._src.plots.source import envelope_from_argument
    from drive_envelope._src.scenario.trajectory import read_trajectory

    output = checked_output(args.output)
    assert output is not None  # required
    envelope = envelope_from_argument(args.envelope)
    points = []
    for path in args.trajectory:
        trajectory = read_trajectory(path, joint=envelope.joint)
        label = f"{trajectory.name} ({trajectory.engine})" if trajectory.engine else trajectory.name
        points.append(
            OperatingPoints(
                velocity=trajectory.velocity, effort=trajectory.effort, time=trajectory.time, label=label
            )
        )
    handle = plot_envelope(envelope, points=points or None, title=args.title)
    save_figure(handle, output, dpi=args.dpi)
    status(f"wrote {output}")
    return 0

"""``drive-envelope plot ENVELOPE``: draw the feasible region and, optionally, trajectories over it."""

from __future__ import annotations

import argparse
from typing import Any

ORDER = 50


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
        nargs="+",
        default=[],
        metavar="CSV",
        help="trajectory files written by `drive-envelope simulate` (CSV or JSON)",
    )
    parser.add_argument(
        "--output", "-o", required=True, metavar="FIG", help="figure file: .png, .svg or .pdf"
    )
    parser.add_argument("--title", default=None, help="figure title (default: the envelope's name)")
    parser.add_argument("--dpi", type=int, default=120, help="resolution of raster output (default 120)")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.plots.figure import plot_envelope, save_figure
    from drive_envelope._src.plots.source import envelope_from_argument
    from drive_envelope._src.scenario.trajectory import read_trajectory

    envelope = envelope_from_argument(args.envelope)
    trajectories = [read_trajectory(path, joint=envelope.joint) for path in args.trajectory]
    handle = plot_envelope(envelope, trajectory=trajectories or None, title=args.title)
    save_figure(handle, args.output, dpi=args.dpi)
    print(f"wrote {args.output}")
    return 0

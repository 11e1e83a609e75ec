"""``drive-envelope check ENVELOPE_OR_DATASHEET LOG``: did logged operation stay inside the envelope?"""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import add_force_argument, add_format_argument, fraction, integer_at_least


def register(subparsers: Any) -> None:
    """Add the ``check`` command."""
    from drive_envelope._src.analysis.options import add_column_arguments

    parser = subparsers.add_parser(
        "check",
        help="check a log of (velocity, effort) samples against an envelope",
        description=(
            "Report per joint the fraction of samples outside the envelope, by which curve, the worst "
            "violation and where (time, row), the margin distribution to each limit and the time spent on "
            "each limit. Exit status 1 when a joint's fraction outside exceeds --tolerance (for CI gates), "
            "2 on bad input. Reads CSV (the CSV of `simulate` as-is) or Parquet in chunks."
        ),
    )
    parser.add_argument(
        "envelope",
        metavar="ENVELOPE_OR_DATASHEET",
        help="envelope file, datasheet file, catalog actuator name, or a joint mapping file ([joints] table)",
    )
    parser.add_argument(
        "log",
        metavar="LOG",
        help="log file: .csv, .tsv, .txt (optionally .gz), .parquet, a simulate .json trajectory, a ROS 2 "
        "bag; or a fleet: a folder, a glob ('logs/**/*.parquet') or a partitioned Parquet dataset",
    )
    add_column_arguments(parser)
    parser.add_argument(
        "--tolerance",
        type=fraction,
        default=0.0,
        metavar="F",
        help="largest fraction of samples allowed outside per joint (default 0)",
    )
    parser.add_argument(
        "--slack",
        type=fraction,
        default=1e-6,
        metavar="F",
        help="a margin below -F times the curve's cap counts as outside (default 1e-6: rounding in logs)",
    )
    parser.add_argument(
        "--limit-band",
        type=fraction,
        default=0.01,
        metavar="F",
        help="|margin| <= F times the cap counts as on the limit (default 0.01)",
    )
    parser.add_argument(
        "--max-joints",
        type=integer_at_least(1),
        default=1000,
        metavar="N",
        help="most distinct joint names in the log (default 1000; memory grows ~32 KiB per joint)",
    )
    add_format_argument(parser, ("text", "json"), "the report as text or as one JSON object (SI)")
    parser.add_argument(
        "--plot",
        metavar="FIG",
        default=None,
        help="also write the envelope plot with violations in red (.png/.svg/.pdf; one file per joint)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="check a fleet (LOG a folder, glob or partitioned Parquet dataset) on this running Dask "
        "distributed scheduler (tcp://host:8786); a fleet runs in this process without it",
    )
    add_force_argument(parser)
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.analysis.api import check_log
    from drive_envelope._src.analysis.check import CheckOptions
    from drive_envelope._src.analysis.options import columns_from_args
    from drive_envelope._src.analysis.text import check_warnings, format_check
    from drive_envelope._src.cli.common import checked_output, print_json, status, warn
    from drive_envelope._src.plots.check import plot_check
    from drive_envelope._src.plots.figure import check_figure_path

    if checked_output(args.plot, "--plot") is not None:
        check_figure_path(args.plot, "--plot")  # before the check, which may read a large log
    options = CheckOptions(
        tolerance=args.tolerance,
        slack=args.slack,
        limit_band=args.limit_band,
        keep_points=20000 if args.plot else 0,
        max_joints=args.max_joints,
    )
    from drive_envelope._src.analysis.fleet import is_fleet

    if is_fleet(args.log) or args.scheduler is not None:  # many logs: one report per part, merged
        from drive_envelope._src.analysis.api import resolve_envelope_source
        from drive_envelope._src.analysis.fleet import check_fleet
        from drive_envelope._src.errors import InputError

        if args.plot:
            raise InputError(f"--plot draws one log; {args.log!r} is a fleet of logs")
        fleet = check_fleet(
            resolve_envelope_source(args.envelope),
            args.log,
            columns=columns_from_args(args),
            options=options,
            scheduler=args.scheduler,
        )
        report = fleet.report
        status(f"checked {len(fleet.parts)} log(s), {fleet.rows} samples in {fleet.wall_time_s:.1f} s")
    else:
        report = check_log(args.envelope, args.log, columns=columns_from_args(args), options=options)
    for message in check_warnings(report):  # mapping keys no joint of the log took
        warn(message)
    if args.plot:
        written = plot_check(report, args.plot, force=args.force)
    if args.format == "json":
        print_json(report.to_dict())
    else:
        print(format_check(report))
    if args.plot:
        status("wrote " + ", ".join(str(path) for path in written))
    return 0 if report.passed else 1

"""``drive-envelope plot ENVELOPE``: draw the feasible region and, optionally, trajectories over it."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import (
    add_force_argument,
    add_format_argument,
    add_output_argument,
    integer_at_least,
)


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
        metavar="FILE",
        help="a trajectory written by `drive-envelope simulate` (CSV, JSON or Parquet) or a bench log "
        "with velocity and effort columns (time optional; units in headers as check reads them); repeat "
        "for several",
    )
    # the log reader's error for a missing column names these flags: plot takes them, as check does
    group = parser.add_argument_group("columns of a -t log (defaults: those of `drive-envelope simulate`)")
    group.add_argument("--velocity-column", default="velocity", metavar="C", help="joint velocity")
    group.add_argument("--effort-column", default="effort", metavar="C", help="total actuator effort")
    group.add_argument("--time-column", default=None, metavar="C", help="time (default: 'time' if there)")
    add_output_argument(parser, "figure file: .png, .svg or .pdf", required=True, metavar="FIG")
    parser.add_argument(
        "--title",
        default=None,
        help="figure title, may use matplotlib mathtext (default: the envelope's name)",
    )
    parser.add_argument(
        "--dpi", type=integer_at_least(1), default=120, help="resolution of raster output (default 120)"
    )
    add_format_argument(
        parser, ("text", "json"), "what to print: the status line, or a JSON report on stdout"
    )
    add_force_argument(parser)
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import warnings

    from drive_envelope._src.cli.common import checked_output, print_json, status, warn
    from drive_envelope._src.plots.figure import check_figure_path, plot_envelope, save_figure
    from drive_envelope._src.plots.source import envelope_from_argument

    output = checked_output(args.output)
    assert output is not None  # required
    check_figure_path(output)
    envelope, slips = envelope_from_argument(args.envelope)
    for line in slips:  # derive's unit-slip warnings for a datasheet, on stderr as derive prints them
        warn(line)
    _check_plottable(envelope, args.envelope)
    from drive_envelope._src.analysis.log_model import LogColumns

    columns = LogColumns(
        velocity=args.velocity_column,
        effort=args.effort_column,
        time=args.time_column or "time",
        require_time=args.time_column is not None,
    )
    points = [_points(path, columns) for path in args.trajectory]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        handle = plot_envelope(envelope, points=points or None, title=_title(args.title))
        save_figure(handle, output, dpi=args.dpi, force=args.force)
    for message in dict.fromkeys(" ".join(str(w.message).split()) for w in caught):
        warn(message)  # matplotlib's (a glyph the font lacks, drawn as a box): one line each, no source
    if args.format == "json":  # the report is the command's result: stdout
        from drive_envelope._src.io.envelope_file import envelope_data

        report = {
            "output": output,
            "envelope": envelope_data(envelope),  # inf written as "inf", as everywhere
            "trajectories": [
                {"file": path, "label": p.label, "samples": len(p.velocity)}
                for path, p in zip(args.trajectory, points, strict=True)
            ],
            "dpi": args.dpi,
            "warnings": [*slips, *dict.fromkeys(" ".join(str(w.message).split()) for w in caught)],
        }
        print_json(report, ensure_ascii=False)
        return 0
    status(f"wrote {output}")
    return 0


def _points(path: str, columns: Any) -> Any:
    """The operating points of ``path``: velocity, effort and time; position is not drawn.

    simulate's JSON and Parquet files carry the run's name and engine, which label the points; any
    other log, or one whose columns the flags name, is read by check's reader (its columns, units in
    headers, cell rules).
    """
    from pathlib import Path

    from drive_envelope._src.analysis.log_model import LogColumns
    from drive_envelope._src.plots.curve import OperatingPoints
    from drive_envelope._src.plots.figure import plain_text

    suffix = Path(path).suffix.lower()
    run = None
    if suffix in (".json", ".parquet", ".pq") and columns == LogColumns():
        from drive_envelope._src.errors import InputError
        from drive_envelope._src.scenario.trajectory import read_operating_log

        try:
            run = read_operating_log(path)
        except InputError:
            if suffix == ".json":
                raise
            # not simulate's Parquet (a bench log: units in headers, any case): check's reader below
    if run is not None:
        label = f"{run.name} ({run.engine})" if run.engine else run.name
        velocity, effort, time = run.velocity, run.effort, run.time
    else:
        from drive_envelope._src.analysis.logs import read_log

        log = read_log(path, columns)
        if log.joint is not None and len(log.names) > 1:  # their points were drawn as one series
            from drive_envelope._src.errors import InputError

            raise InputError(
                f"{path}: the log holds {len(log.names)} joints ({', '.join(log.names[:3])}"
                f"{', ...' if len(log.names) > 3 else ''}); plot draws one joint over one envelope: "
                "`drive-envelope check MAPPING LOG --plot FIG` draws each joint over its own"
            )
        label, velocity, effort, time = Path(path).stem, log.velocity, log.effort, log.time
    # a name from a file is text, never mathtext
    return OperatingPoints(velocity=velocity, effort=effort, time=time, label=plain_text(label))


def _title(title: str | None) -> str | None:
    from drive_envelope._src.plots.figure import check_text

    return None if title is None else check_text(title, "--title")


def _check_plottable(envelope: Any, spec: str) -> None:
    from drive_envelope._src.errors import InputError
    from drive_envelope._src.plots.curve import envelope_curve

    try:
        envelope_curve(envelope)
    except InputError as exc:  # values that no window shows to scale: name the file they came from
        raise InputError(f"{spec}: {exc}") from None

"""``drive-envelope fit LOG``: estimate the four envelope parameters from measured saturated operation."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import (
    add_force_argument,
    add_format_argument,
    add_output_argument,
    fraction_in,
    integer_at_least,
)


def register(subparsers: Any) -> None:
    """Add the ``fit`` command."""
    from drive_envelope._src.analysis.options import add_column_arguments

    parser = subparsers.add_parser(
        "fit",
        help="fit an envelope to measured (velocity, effort) samples or a digitized datasheet curve",
        description=(
            "Estimate max_effort, max_actuator_velocity, velocity_dependent_resistance and "
            "speed_effort_gradient as the tightest envelope of the spec's form containing the samples (up "
            "to --outlier-quantile), with bootstrap uncertainties and residuals. Only the frontier is "
            "fitted (the samples on or near the upper hull of |effort| over |velocity|), and the report "
            "says which samples decided each line. A limit the data never reach is reported as "
            "unidentified (max_actuator_velocity = inf), not guessed; one line that reaches zero effort "
            "is the speed-torque line (eq. 2)."
        ),
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "log",
        nargs="?",
        metavar="LOG",
        help="log of saturated operation (.csv, .parquet, or a simulate .json trajectory)",
    )
    source.add_argument(
        "--from-curve",
        metavar="POINTS",
        default=None,
        help="CSV of points digitized from a datasheet's torque-speed diagram ('speed [rpm],torque [mNm]')",
    )
    parser.add_argument(
        "--joint", choices=("revolute", "prismatic"), default="revolute", help="joint type (units)"
    )
    parser.add_argument(
        "--fix",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="hold a parameter: --fix max_effort=12, --fix 'max_actuator_velocity=3000 rpm' (repeatable)",
    )
    parser.add_argument(
        "--outlier-quantile",
        type=fraction_in(0.5),
        default=0.0,
        metavar="Q",
        help="fraction of samples allowed outside (default 0: contain all; 0.5: central line through noise)",
    )
    parser.add_argument(
        "--frontier-band",
        type=fraction_in(above_zero=True),
        default=None,
        metavar="B",
        help="fit the samples within this fraction of the upper hull, in (0, 1]; 1: every sample "
        "(default: the hull's own samples, or 0.01 widened to the noise with --outlier-quantile)",
    )
    parser.add_argument(
        "--bootstrap",
        type=integer_at_least(0, 10_000),
        default=200,
        metavar="N",
        help="bootstrap resamples, 0..10000 (default 200)",
    )
    parser.add_argument(
        "--seed", type=integer_at_least(0), default=0, help="random seed of the bootstrap, >= 0 (default 0)"
    )
    parser.add_argument("--select", metavar="JOINT", default=None, help="joint to fit in a long-format log")
    parser.add_argument("--name", default="", help="name written into the envelope file")
    add_output_argument(parser, "write the fitted envelope file here (.toml or .json), atomically")
    add_force_argument(parser)
    add_format_argument(parser, ("text", "json"), "the fit as a table or as one JSON object (SI)")
    add_column_arguments(parser, time=False)
    parser.set_defaults(func=_run)


def _fixed(items: list[str], joint: str) -> dict[str, float]:
    from drive_envelope._src.envelope.model import ENVELOPE_FIELDS
    from drive_envelope._src.errors import InputError
    from drive_envelope._src.params.table import si_unit
    from drive_envelope._src.validation import nearest_key
    from drive_envelope._src.values import read_quantity

    fixed = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not value.strip():
            raise InputError(f"--fix {item!r}: expected NAME=VALUE, e.g. max_effort=12")
        if name not in ENVELOPE_FIELDS:
            raise InputError(
                f"--fix {item!r}: unknown parameter {name!r}{nearest_key(name, ENVELOPE_FIELDS)}"
            )
        if name in fixed:  # the last would win silently: refused, as derive's --set
            raise InputError(f"--fix {name!r} given twice; give each parameter once")
        # the text itself, as derive's --set: float('1e400') was inf, a speed limit fixed at inf
        fixed[name] = read_quantity(value.strip(), si_unit(name, joint), f"--fix {name}")
    return fixed


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.analysis.api import fit_curve, fit_log
    from drive_envelope._src.analysis.fit import FitOptions
    from drive_envelope._src.analysis.options import columns_from_args
    from drive_envelope._src.analysis.text import format_fit
    from drive_envelope._src.cli.common import (
        check_toml_or_json,
        checked_output,
        print_json,
        refuse_input_as_output,
        status,
    )
    from drive_envelope._src.errors import InputError
    from drive_envelope._src.io.envelope_file import save_envelope

    output = checked_output(args.output)
    check_toml_or_json(output, "--output", "an envelope file")
    source = args.from_curve or args.log  # simulate's JSON trajectory is a log with a .json name
    refuse_input_as_output(output, source, "the curve" if args.from_curve else "the log", "the envelope")
    options = FitOptions(
        joint=args.joint,
        outlier_quantile=args.outlier_quantile,
        fixed=_fixed(args.fix, args.joint),
        bootstrap=args.bootstrap,
        seed=args.seed,
        frontier_band=args.frontier_band,
        name=args.name,
    )
    columns = columns_from_args(args)
    if args.from_curve:
        result = fit_curve(args.from_curve, columns=columns, options=options)
    else:
        try:
            result = fit_log(args.log, columns=columns, options=options, select=args.select)
        except InputError as exc:
            from drive_envelope._src.analysis.curve import looks_like_curve

            if not looks_like_curve(args.log):
                raise
            raise InputError(
                f"{exc}; the columns look like a speed-torque curve: "
                f"drive-envelope fit --from-curve {args.log} reads such curves"
            ) from None
    if output is not None:
        save_envelope(result.envelope, output, force=args.force)
    if args.format == "json":
        print_json(result.to_dict())
    else:
        print(format_fit(result))
    if output is not None:
        status(f"wrote {output}")
    return 0

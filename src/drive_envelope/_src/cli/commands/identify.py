"""``drive-envelope identify TRAIN_LOG... --stand STAND``: the envelope (and more) a bench implies."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import (
    add_force_argument,
    add_format_argument,
    add_output_argument,
    integer_at_least,
)

_PARAMETERS = (
    "max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient, stiffness, "
    "duty_effort, damping, static_friction, dynamic_friction, viscous_friction, armature, angle_offset"
)
_REPORT_EVERY = 10.0  # s between progress lines when stderr is not a terminal (a log file, CI)


def _nonnegative(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not (value >= 0.0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return value


def register(subparsers: Any) -> None:
    """Add the ``identify`` command."""
    from drive_envelope._src.analysis.options import add_bag_arguments

    parser = subparsers.add_parser(
        "identify",
        help="estimate the envelope (and drive, friction, armature) from bench logs",
        description=(
            "Replay bench logs (time, position, target_position; optional velocity, effort, "
            "target_velocity, torque_enable) through the reference test stand of the stand file and "
            "search the parameters that make the simulated positions match the measured ones "
            "(differential evolution over batched replays, then a least-squares polish). Prints the "
            "parameters with their standard deviations and restart spread and the mean absolute position "
            "error per log; writes the identified stand (-o: every identified and fixed parameter, read "
            "by identify --stand and replay --stand), the envelope file (--envelope-output) and a figure "
            "(--plot). Needs SciPy (the identify extra)."
        ),
    )
    parser.add_argument(
        "train", nargs="+", metavar="TRAIN_LOG", help="training logs (.csv, .tsv, .txt, also .gz; .parquet)"
    )
    parser.add_argument(
        "--stand",
        required=True,
        metavar="STAND",
        help="stand file: a scenario (joint, drive, loads such as [pendulum]) plus [servo] and [bounds]",
    )
    parser.add_argument(
        "--validate", nargs="+", default=[], metavar="LOG", help="held-out logs, replayed with the result"
    )
    parser.add_argument(
        "--fit",
        default=None,
        metavar="NAME,...",
        help=f"parameters to estimate, comma-separated (default: the four envelope ones); from {_PARAMETERS}",
    )
    parser.add_argument(
        "--engine",
        choices=("reference", "physx", "mujoco"),
        default="reference",
        help="also replay the result in physx (real PhysX, ovphysx) or mujoco and report its error",
    )
    add_format_argument(parser, ("text", "json"), "the report as text or as one JSON object (SI)")
    add_output_argument(
        parser,
        "write the identified stand (.toml or .json), atomically: replay --stand reads it",
        metavar="STAND",
    )
    parser.add_argument(
        "--envelope-output",
        metavar="FILE",
        default=None,
        help="write the identified envelope file (.toml or .json) for usd apply / mujoco apply",
    )
    parser.add_argument("--plot", metavar="FIG", default=None, help="write the figure (.png, .svg or .pdf)")
    parser.add_argument(
        "--generations",
        type=integer_at_least(1),
        default=60,
        metavar="N",
        help="most search generations (default 60)",
    )
    parser.add_argument(
        "--population",
        type=integer_at_least(1, 1000),
        default=10,
        metavar="N",
        help="candidates per generation per fitted parameter (default 10)",
    )
    parser.add_argument(
        "--velocity-weight",
        type=_nonnegative,
        default=0.0,
        metavar="S",
        help="weight of the velocity error in the cost, in seconds (default 0: position only)",
    )
    parser.add_argument(
        "--seed", type=integer_at_least(0), default=0, metavar="N", help="random seed (default 0)"
    )
    parser.add_argument(
        "--restarts",
        type=integer_at_least(1, 100),
        default=3,
        metavar="N",
        help="independent searches from seeds drawn from --seed; the best wins, their spread is reported "
        "(default 3)",
    )
    add_bag_arguments(parser, joint=True)
    add_force_argument(parser)
    parser.set_defaults(func=_run)


def _fit_names(text: str | None) -> list[str]:
    from drive_envelope._src.errors import InputError
    from drive_envelope._src.identify.parameters import DEFAULT_FIT

    if text is None:
        return list(DEFAULT_FIT)
    names = [name.strip() for name in text.split(",")]
    if not all(names):
        raise InputError(f"--fit {text!r}: expected comma-separated parameter names, e.g. max_effort,damping")
    return names


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.analysis.options import bag_from_args
    from drive_envelope._src.cli.common import (
        Progress,
        check_toml_or_json,
        checked_output,
        print_json,
        printed_warnings,
        status,
        warn,
    )
    from drive_envelope._src.identify.optimize import SearchOptions
    from drive_envelope._src.identify.report import identification_text, identification_to_dict
    from drive_envelope._src.identify.run import identify
    from drive_envelope._src.identify.stand import StandWarning
    from drive_envelope._src.io.atomic import check_writable

    output = checked_output(args.output)
    envelope_output = checked_output(args.envelope_output, "--envelope-output")
    plot = checked_output(args.plot, "--plot")
    check_toml_or_json(output, "--output", "a stand file")
    check_toml_or_json(envelope_output, "--envelope-output", "an envelope file")
    if plot is not None:
        from drive_envelope._src.plots.figure import check_figure_path

        check_figure_path(plot, "--plot")
    _check_apart(output, envelope_output, args.stand)
    for path in (output, envelope_output, plot):  # before the search, which takes a while
        if path is not None:
            check_writable(path, force=args.force)
    options = SearchOptions(
        generations=args.generations,
        population=args.population,
        velocity_weight=args.velocity_weight,
        seed=args.seed,
        restarts=args.restarts,
    )
    progress = _Progress(Progress("identify"))
    with printed_warnings(StandWarning, once=False):
        try:
            result = identify(
                args.train,
                args.stand,
                validate=args.validate,
                fit=_fit_names(args.fit),
                options=options,
                engine=args.engine,
                progress=progress,
                bag=bag_from_args(args),
                joint=args.joint,
            )
        finally:
            progress.close()
    for note in result.notes:
        warn(note)
    if output is not None:
        from drive_envelope._src.identify.stand_file import save_stand

        assert result.stand is not None
        save_stand(result.stand, output, comments=_stand_comments(args, result), force=args.force)
    if envelope_output is not None:
        from drive_envelope._src.io.envelope_file import save_envelope

        save_envelope(result.envelope, envelope_output, force=args.force)
    if plot is not None:
        from drive_envelope._src.plots.identification import save_identification_figure

        save_identification_figure(result, plot, force=args.force)
    if args.format == "json":
        print_json(identification_to_dict(result))
    else:
        print(identification_text(result))
    for path in (output, envelope_output, plot):
        if path is not None:
            status(f"wrote {path}")
    return 0


def _check_apart(output: str | None, envelope_output: str | None, stand: str) -> None:
    """Refuse the envelope file on the identified stand's file or on the --stand it started from.

    Both were written without a word, the envelope last: the stand was lost. ``-o`` may be the
    ``--stand`` file (a search refined in place).
    """
    import os

    from drive_envelope._src.cli.common import same_file
    from drive_envelope._src.errors import InputError

    def same(a: str, b: str) -> bool:  # also two names of one file neither of which exists yet
        return os.path.realpath(a) == os.path.realpath(b) or same_file(a, b)

    if envelope_output is None:
        return
    if output is not None and same(output, envelope_output):
        raise InputError(
            f"--envelope-output {envelope_output!r} is also --output: give the stand and the envelope "
            "two files"
        )
    if same(stand, envelope_output):
        raise InputError(
            f"--envelope-output {envelope_output!r} is the --stand file: the envelope would replace the "
            "stand; give a new file"
        )


def _stand_comments(args: argparse.Namespace, result: Any) -> list[str]:
    """Where the stand came from, for the file's header."""
    from drive_envelope._src.identify.parameters import DEFAULT_FIT
    from drive_envelope._src.identify.run import mean_error

    lines = [
        f"identified by drive-envelope identify from {len(result.train)} log(s) on {args.stand}",
        f"--fit {args.fit or ','.join(DEFAULT_FIT)}",
        f"seed {args.seed}, {args.restarts} restart(s), train cost {result.search.cost:.9g}",
        f"mean position error [rad or m]: train {mean_error(result.train):.9g}"
        + (f", validation {mean_error(result.validation):.9g}" if result.validation else ""),
        "replay LOG... --stand THIS_FILE replays logs with it; identify --stand THIS_FILE starts from it",
    ]
    lines.extend(f"note: {note}" for note in result.notes)
    return lines


class _Progress:
    """The search's progress: a bar on a terminal (global and polish steps), else a line every 10 s."""

    def __init__(self, bar: Any) -> None:
        import sys
        import time

        self.bar = bar
        self.terminal = bar.enabled
        self.clock = time.monotonic
        self.start = self.clock()
        self.last = self.start
        self.stream = sys.stderr

    def __call__(self, state: Any) -> None:
        phase = "search" if state.phase == "global" else "polish"
        where = f"restart {state.restart}/{state.restarts}, {phase} {state.generation}/{state.generations}"
        if self.terminal:
            self.bar.label = f"identify ({where})"
            self.bar(state.done, state.total)
            return
        now = self.clock()
        if now - self.last >= _REPORT_EVERY:
            self.last = now
            print(
                f"identify: {where}, best cost {state.best_cost:.6g}, {now - self.start:.0f} s",
                file=self.stream,
                flush=True,
            )

    def close(self) -> None:
        self.bar.close()

"""Options and output conventions every ``drive-envelope`` command shares.

* ``-o/--output FILE`` on every command that writes a file; the file is written atomically.
* ``--format NAME`` chooses what goes to stdout (``--json`` is the short form of ``--format json``);
  there is never a second flag for the same choice.
* Status lines (``wrote ...``) and warnings go to stderr, so stdout stays pipeable.
* Repeatable options use ``action="append"``.
* ``--force`` on every command that writes: replace a read-only output file.
* A bad flag is one line on stderr and exit 2, like every other user mistake (:class:`Parser`).
* A long run shows its progress on stderr, and only when stderr is a terminal (:class:`Progress`).

This module is imported for ``--help``: it stays free of NumPy, pint and every engine.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, NoReturn, TextIO

from drive_envelope._src.errors import InputError

PROG = "drive-envelope"


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (``PROG CMD: error: ...``) and exit status 2.

    argparse prints the whole usage before the error; here the error names the flag and the value,
    and ``--help`` has the usage. Subcommand parsers inherit the class. Flags are never
    abbreviated: ``check --joint`` was read as ``--joint-column`` while ``replay --joint`` picks a
    joint, so a prefix is an unknown flag with the nearest one named.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        """Print ``message`` as one line on stderr and exit with status 2."""
        text = " ".join(message.split())
        self.exit(2, f"{self.prog}: error: {text} (see {self.prog} --help)\n")


def fraction_in(high: float = 1.0, *, above_zero: bool = False) -> Callable[[str], float]:
    """Argument type: a number in ``[0, high]``, or in ``(0, high]`` with ``above_zero``."""
    span = f"{'(' if above_zero else '['}0, {high:g}]"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (0.0 < value <= high if above_zero else 0.0 <= value <= high):
            raise argparse.ArgumentTypeError(f"expected a fraction in {span}, got {text!r}")
        return value

    return parse


fraction = fraction_in()
"""Argument type: a number in [0, 1] (``--tolerance 0.01``)."""


def integer_at_least(low: int, high: int | None = None) -> Callable[[str], int]:
    """Argument type: an integer in ``[low, high]`` (``--seed``, ``--bootstrap``, ``--max-steps``).

    Accepts ``1e8``-style spellings of whole numbers, so large counts can be written readably.
    """

    def parse(text: str) -> int:
        digits = text.strip().lstrip("+-")
        try:
            if digits.isdigit():
                whole, value = True, int(text)
            else:  # 1e8: a whole number written as a float
                number = float(text)
                whole = math.isfinite(number) and number.is_integer()
                value = int(number) if whole else 0
        except ValueError:
            whole, value = False, 0
        if not whole or value < low or (high is not None and value > high):
            span = f"in {low}..{high}" if high is not None else f">= {low}"
            raise argparse.ArgumentTypeError(f"expected an integer {span}, got {text!r}")
        return value

    parse.__name__ = "integer"  # argparse names the type in its own messages
    return parse


def add_output_argument(
    parser: argparse.ArgumentParser, help: str, *, required: bool = False, metavar: str = "FILE"
) -> None:
    """Add ``-o/--output FILE`` (atomic write; an empty name is refused when the command runs)."""
    parser.add_argument("-o", "--output", metavar=metavar, default=None, required=required, help=help)


class _OneJoint(argparse.Action):
    """``--joint`` given once: argparse keeps the last of repeated flags, which drops joints silently."""

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any, option: Any = None
    ) -> None:
        previous = getattr(namespace, self.dest, None)
        if previous is not None:
            parser.error(
                f"{option}: given twice ({previous!r}, {values!r}): one joint per --joint run; for several "
                "joints write a map file (--map, a pattern per joint or group)"
            )
        setattr(namespace, self.dest, values)


def add_joint_source_arguments(
    parser: argparse.ArgumentParser, *, joint: tuple[str, str], map_help: str
) -> None:
    """Add ``--joint`` | ``--map`` (one required) and ``--datasheet`` | ``--envelope`` (for ``--joint``).

    ``joint`` is the (metavar, help) of ``--joint``: a joint name in MJCF, a prim path in USD.
    """
    target = parser.add_mutually_exclusive_group(required=True)
    target.add_argument("--joint", metavar=joint[0], help=joint[1], action=_OneJoint)
    target.add_argument("--map", metavar="MAP", help=map_help)
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--datasheet", metavar="FILE", help="datasheet file or catalog name (with --joint)")
    source.add_argument("--envelope", metavar="FILE", help="envelope file (with --joint)")


def add_actions(parser: argparse.ArgumentParser, dest: str) -> Any:
    """The ACTION subparsers of a command group; the group without an ACTION prints its help (exit 2)."""

    def usage(args: argparse.Namespace) -> int:
        parser.print_help()
        return 2

    parser.set_defaults(func=usage)
    return parser.add_subparsers(dest=dest, metavar="ACTION")


def check_joint_source(args: argparse.Namespace, command: str, *, map_excludes: tuple[str, ...] = ()) -> None:
    """Refuse ``--joint`` without ``--datasheet``/``--envelope``, and ``--map`` with either.

    ``map_excludes``: the command's other options a map file stands in for (``"instance"``).

    Raises:
        InputError: naming ``command`` (``"usd apply"``) and the flags to give or drop.
    """
    if args.joint is not None and args.datasheet is None and args.envelope is None:
        raise InputError(f"{command} --joint: needs --datasheet FILE or --envelope FILE")
    excluded = any(getattr(args, name) for name in map_excludes)
    if args.map is not None and (args.datasheet is not None or args.envelope is not None or excluded):
        flags = "/".join(f"--{name}" for name in ("datasheet", "envelope", *map_excludes))
        raise InputError(f"{command} --map: the map file names the envelopes; drop {flags}")


def joint_envelope(args: argparse.Namespace) -> Any:
    """The envelope that ``--datasheet`` or ``--envelope`` names for ``--joint``."""
    from drive_envelope._src.datasheet.resolve import resolve_envelope

    if args.datasheet is not None:
        return resolve_envelope(args.datasheet, where="--datasheet")
    return resolve_envelope(args.envelope, where="--envelope")


def add_format_argument(parser: argparse.ArgumentParser, choices: tuple[str, ...], help: str) -> None:
    """Add ``--format {choices}`` (default the first choice) and ``--json`` for ``--format json``."""
    parser.add_argument(
        "--format", choices=choices, default=choices[0], help=f"{help} (default {choices[0]})"
    )
    if "json" in choices:
        parser.add_argument(
            "--json", dest="format", action="store_const", const="json", help="short for --format json"
        )


def add_force_argument(parser: argparse.ArgumentParser) -> None:
    """Add ``--force``: replace an output file even when it is read-only."""
    parser.add_argument(
        "--force", action="store_true", help="replace an output file even when it is read-only"
    )


def print_json(data: object, *, ensure_ascii: bool = True) -> None:
    """Print a command's result on stdout as one indented JSON object (``--format json``)."""
    import json

    print(json.dumps(data, indent=2, ensure_ascii=ensure_ascii))


def status(message: str) -> None:
    """Print a status line (what was written) on stderr."""
    print(message, file=sys.stderr)


def warn(message: str) -> None:
    """Print a warning line on stderr."""
    print(f"{PROG}: warning: {message}", file=sys.stderr)


def checked_output(output: str | None, flag: str = "--output") -> str | None:
    """The output file name given with ``flag``, or None; an empty name or a folder is an error.

    Raises:
        InputError: ``""`` (a file name was expected) or the name of an existing folder.
    """
    if output is None:
        return None
    if not output.strip():
        raise InputError(f"{flag} '': expected a file name")
    if Path(output).is_dir():
        raise InputError(f"{flag} {output!r}: is a folder; expected a file name")
    return output


def check_toml_or_json(path: str | None, flag: str, what: str) -> None:
    """Refuse a ``flag`` file name that ends neither in .toml nor in .json (``what``: "a stand file").

    Raises:
        InputError: naming the flag, the file and what was expected (None, no file, passes).
    """
    if path is not None and Path(path).suffix.lower() not in (".toml", ".json"):
        raise InputError(f"{flag} {path!r}: expected {what} name ending in .toml or .json")


def same_file(a: str, b: str) -> bool:
    """Whether both files exist and are one (a symlink or another spelling of the name too)."""
    import os

    return os.path.exists(a) and os.path.exists(b) and os.path.samefile(a, b)


def refuse_input_as_output(output: str | None, source: str | None, what: str, result: str) -> None:
    """Refuse ``--output`` naming the command's input file: the result would replace it silently.

    Args:
        output: The output file name, or None.
        source: The input file (a datasheet, scenario or log), or None.
        what: The input, for the message (``"the scenario"``).
        result: What would be written (``"the trajectory"``).

    Raises:
        InputError: both exist and are one file (a symlink or another spelling of the name too).
    """
    if output is not None and source is not None and same_file(output, source):
        raise InputError(f"--output {output!r} is {what} itself: write {result} to a new file")


@contextlib.contextmanager
def printed_warnings(
    category: type[Warning] = Warning, *, once: bool = True, also_on_error: bool = False
) -> Iterator[None]:
    """Print each warning of ``category`` the block raises as a ``drive-envelope: warning:`` line.

    Warnings of other categories are dropped; ``once``: a message raised again is printed once.
    When the block fails, its error is the one line: the warnings are printed only with
    ``also_on_error``.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", category)
        try:
            yield
        except BaseException:
            if also_on_error:
                _print_caught(caught, category, once)
            raise
    _print_caught(caught, category, once)


def _print_caught(caught: list[warnings.WarningMessage], category: type[Warning], once: bool) -> None:
    messages = [str(item.message) for item in caught if issubclass(item.category, category)]
    for message in dict.fromkeys(messages) if once else messages:
        warn(message)


def envelope_summary(envelope: Any) -> str:
    """The four parameters as ``name=value unit`` pairs, for a command's line per drive."""
    from drive_envelope._src.envelope.model import ENVELOPE_FIELDS
    from drive_envelope._src.format import format_value
    from drive_envelope._src.params.table import si_unit

    return ", ".join(
        f"{field}={format_value(getattr(envelope, field), si_unit(field, envelope.joint))}"
        for field in ENVELOPE_FIELDS
    )


class Progress:
    """A one-line progress bar on stderr for long runs, shown only when stderr is a terminal.

    Call it with ``(done, total)`` as often as convenient: it draws at most every 0.2 s, and only
    once the run has lasted 1 s, so short runs print nothing. :meth:`close` ends the line.
    """

    def __init__(self, label: str, *, stream: TextIO | None = None, delay: float = 1.0) -> None:
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = self.stream.isatty()
        self.delay = delay
        self.start = time.monotonic()
        self.drawn_at = -math.inf
        self.shown = False

    def __call__(self, done: int, total: int) -> None:
        """Report ``done`` of ``total`` steps."""
        if not self.enabled:
            return
        now = time.monotonic()
        elapsed = now - self.start
        if elapsed < self.delay or now - self.drawn_at < 0.2:
            return
        self.drawn_at = now
        share = done / total if total else 1.0
        width = 30
        filled = min(width, int(share * width))
        left = elapsed * (1.0 - share) / share if share > 0 else math.inf
        eta = f", {left:.0f} s left" if math.isfinite(left) else ""
        bar = "#" * filled + "." * (width - filled)
        self.stream.write(f"\r{self.label} [{bar}] {100 * share:5.1f} % ({done}/{total}{eta})")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        """Finish the bar's line (a no-op when nothing was drawn)."""
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()
            self.shown = False

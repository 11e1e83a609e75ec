"""Options and output conventions every ``drive-envelope`` command shares.

* ``-o/--output FILE`` on every command that writes a file; the file is written atomically.
* ``--format NAME`` chooses what goes to stdout (``--json`` is the short form of ``--format json``);
  there is never a second flag for the same choice.
* Status lines (``wrote ...``) and warnings go to stderr, so stdout stays pipeable.
* Repeatable options use ``action="append"``.

This module is imported for ``--help``: it stays free of NumPy, pint and every engine.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from drive_envelope._src.errors import InputError

__all__ = ["add_format_argument", "add_output_argument", "checked_output", "status", "warn"]

PROG = "drive-envelope"


def add_output_argument(
    parser: argparse.ArgumentParser, help: str, *, required: bool = False, metavar: str = "FILE"
) -> None:
    """Add ``-o/--output FILE`` (atomic write; an empty name is refused when the command runs)."""
    parser.add_argument("-o", "--output", metavar=metavar, default=None, required=required, help=help)


def add_format_argument(parser: argparse.ArgumentParser, choices: tuple[str, ...], help: str) -> None:
    """Add ``--format {choices}`` (default the first choice) and ``--json`` for ``--format json``."""
    parser.add_argument(
        "--format", choices=choices, default=choices[0], help=f"{help} (default {choices[0]})"
    )
    if "json" in choices:
        parser.add_argument(
            "--json", dest="format", action="store_const", const="json", help="short for --format json"
        )


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

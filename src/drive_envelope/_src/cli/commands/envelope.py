"""``drive-envelope envelope show FILE``: print an envelope file as a table with its corner points."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import add_actions, add_format_argument


def register(subparsers: Any) -> None:
    """Add the ``envelope`` command group."""
    parser = subparsers.add_parser("envelope", help="inspect envelope files")
    actions = add_actions(parser, "envelope_command")
    show = actions.add_parser("show", help="print an envelope file as a table with its corner points")
    show.add_argument(
        "file",
        metavar="FILE|NAME",
        help="envelope file (TOML, JSON or YAML), datasheet file or catalog name (its peak envelope)",
    )
    add_format_argument(show, ("text", "json", "toml"), "the table, or the envelope file as JSON or TOML")
    show.set_defaults(func=_show)


def _show(args: argparse.Namespace) -> int:
    from drive_envelope._src.cli.common import warn
    from drive_envelope._src.datasheet.resolve import resolve_with_warnings
    from drive_envelope._src.io.envelope_file import envelope_table, envelope_to_json, envelope_to_toml

    # as plot, check and simulate read an envelope: a datasheet said "unknown key 'description'"
    envelope, slips = resolve_with_warnings(args.file)
    if args.format == "json":
        print(envelope_to_json(envelope), end="")
    elif args.format == "toml":
        print(envelope_to_toml(envelope), end="")
    else:
        print(envelope_table(envelope))
    for line in slips:  # derive's unit-slip warnings for the same datasheet, on stderr as derive has them
        warn(line)
    return 0

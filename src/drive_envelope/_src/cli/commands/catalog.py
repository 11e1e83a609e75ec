"""``drive-envelope catalog [NAME]``: list the catalog actuators, or print one datasheet with its sources."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import add_format_argument


def register(subparsers: Any) -> None:
    """Add the ``catalog`` command."""
    parser = subparsers.add_parser(
        "catalog",
        help="list the real actuators shipped as datasheet files (use a name with `derive`)",
    )
    parser.add_argument(
        "name", nargs="?", metavar="NAME", help="print this actuator's datasheet file (with sources)"
    )
    add_format_argument(parser, ("text", "json"), "how to print the list")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import json

    from drive_envelope._src.datasheet.catalog import catalog_entries, catalog_text, load_catalog_datasheet
    from drive_envelope._src.datasheet.derive import derive
    from drive_envelope._src.format import format_table, format_value

    if args.name:
        print(catalog_text(args.name), end="")
        return 0
    rows, items = [], []
    for entry in catalog_entries():
        env = derive(load_catalog_datasheet(entry.key)).envelope
        effort_unit, speed_unit = ("N*m", "rad/s") if entry.joint == "revolute" else ("N", "m/s")
        rows.append(
            [
                entry.key,
                entry.joint,
                format_value(env.max_effort, effort_unit),
                format_value(env.max_actuator_velocity, speed_unit),
                entry.name,
            ]
        )
        items.append(
            {"key": entry.key, "name": entry.name, "joint": entry.joint, "description": entry.description}
        )
    if args.format == "json":
        print(json.dumps(items, indent=2))
    else:
        print(format_table(["key", "joint", "max_effort", "max_velocity", "name"], rows))
        print(
            "\n`drive-envelope derive KEY` shows the derivation; "
            "`drive-envelope catalog KEY` the datasheet and sources."
        )
    return 0

"""``drive-envelope catalog [NAME]``: the catalog actuators, filtered, or one datasheet with its sources."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import add_format_argument, print_json


def register(subparsers: Any) -> None:
    """Add the ``catalog`` command."""
    parser = subparsers.add_parser(
        "catalog",
        help="list the real actuators shipped as datasheet files (use a name with `derive`)",
        description=(
            "List the catalog actuators (real datasheets, every number with its source), or print one "
            "actuator's datasheet file; --sources prints where each of its values came from."
        ),
    )
    parser.add_argument(
        "name", nargs="?", metavar="NAME", help="print this actuator's datasheet file (with sources)"
    )
    parser.add_argument(
        "--joint", choices=("revolute", "prismatic"), help="list only actuators for this joint type"
    )
    parser.add_argument(
        "--search",
        metavar="WORDS",
        help="list only actuators whose key, name, description or sources contain all these words",
    )
    parser.add_argument(
        "--sources",
        action="store_true",
        help="with NAME: print each value with the document it came from",
    )
    parser.add_argument(
        "--maps",
        action="store_true",
        help="list the shipped robot maps (joint patterns -> catalog actuators) for usd/mujoco apply --map",
    )
    add_format_argument(parser, ("text", "json"), "how to print")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.errors import InputError

    if args.maps:
        if args.name or args.joint or args.search or args.sources:
            raise InputError("--maps lists the robot maps; give it alone (with --format)")
        return _maps(as_json=args.format == "json")
    if args.name:
        if args.joint or args.search:
            raise InputError("--joint and --search filter the list; give them without NAME")
        return _show(args.name, sources=args.sources, as_json=args.format == "json")
    if args.sources:
        raise InputError(
            "--sources needs an actuator NAME (e.g. drive-envelope catalog unitree-go-m8010-6 --sources)"
        )
    return _list(args.joint, args.search, as_json=args.format == "json")


def _show(name: str, *, sources: bool, as_json: bool) -> int:
    from drive_envelope._src.datasheet.catalog import (
        catalog_entry,
        catalog_sources,
        catalog_text,
        load_catalog_datasheet,
    )
    from drive_envelope._src.format import format_table

    sheet = load_catalog_datasheet(name)  # the error for an unknown name, with the nearest key
    key = catalog_entry(name) or name
    if not sources and not as_json:
        print(catalog_text(key), end="")
        return 0
    values = catalog_sources(key)
    if as_json:
        data: dict[str, object] = {
            "key": key,
            "name": sheet.name,
            "joint": sheet.joint,
            "description": sheet.description,
            "sources": list(sheet.sources),
            "values": [{"key": v.key, "value": v.value, "source": v.source} for v in values],
        }
        print_json(data, ensure_ascii=False)
        return 0
    print(f"{sheet.name} ({key}, {sheet.joint})")
    print(format_table(["key", "value", "source"], [[v.key, v.value, v.source] for v in values]))
    print("\ndocuments:")
    for url in sheet.sources:
        print(f"  {url}")
    return 0


def _list(joint: str | None, search: str | None, *, as_json: bool) -> int:
    from drive_envelope._src.datasheet.catalog import catalog_entries, load_catalog_datasheet, no_match_error
    from drive_envelope._src.datasheet.derive import derive
    from drive_envelope._src.envelope.model import ENVELOPE_FIELDS
    from drive_envelope._src.format import format_table, format_value

    entries = catalog_entries(joint=joint, search=search)
    if not entries:  # an empty answer to a search is a mistake to fix, not a result (exit 2)
        raise no_match_error(search, joint)
    rows, items = [], []
    for entry in entries:
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
            {
                "key": entry.key,
                "name": entry.name,
                "joint": entry.joint,
                "description": entry.description,
                "sources": list(entry.sources),
                **{field: getattr(env, field) for field in ENVELOPE_FIELDS},
            }
        )
    if as_json:
        filters = {"joint": joint, "search": search}
        print_json({"count": len(items), "filters": filters, "actuators": items}, ensure_ascii=False)
        return 0
    print(format_table(["key", "joint", "max_effort", "max_velocity", "name"], rows))
    print(
        "\n`drive-envelope derive KEY` shows the derivation; "
        "`drive-envelope catalog KEY --sources` where each number came from."
    )
    return 0


def _maps(*, as_json: bool) -> int:
    from drive_envelope._src.datasheet.maps import robot_maps
    from drive_envelope._src.format import format_table

    maps = robot_maps()
    if as_json:
        listed = [{"key": m.key, "robot": m.title, "path": str(m.path)} for m in maps]
        print_json({"count": len(listed), "maps": listed})
        return 0
    print(format_table(["map", "robot", "file"], [[m.key, m.title, str(m.path)] for m in maps]))
    print(
        "\nuse the file with `drive-envelope usd apply ROBOT.usda --map FILE` (or `mujoco apply --map FILE`)."
    )
    return 0

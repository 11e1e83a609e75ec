"""``drive-envelope usd apply|show``: author envelopes into USD robot assets and list them."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import (
    add_actions,
    add_format_argument,
    add_joint_source_arguments,
    add_output_argument,
)


def register(subparsers: Any) -> None:
    """Add the ``usd`` command group."""
    parser = subparsers.add_parser(
        "usd", help="author envelopes into USD assets (PhysxDrivePerformanceEnvelopeAPI)"
    )
    actions = add_actions(parser, "usd_command")

    apply = actions.add_parser(
        "apply",
        help="write envelopes on joint drives (one joint, or the whole robot from a map file)",
        description="Apply PhysicsDriveAPI + PhysxDrivePerformanceEnvelopeAPI with PhysX's unit conventions "
        "(degrees on angular drives, stage metersPerUnit/kilogramsPerUnit). -o OUT.usda writes a small new "
        "layer that sublayers ROBOT.usd and holds only the envelopes (the asset stays as it is); add "
        "--flatten for one self-contained file, or edit ROBOT.usd itself with --in-place. The result is "
        "reopened and checked before it replaces any file; on any error nothing is written.",
    )
    apply.add_argument("asset", metavar="ROBOT.usd", help="USD file of the robot (or scene)")
    add_joint_source_arguments(
        apply,
        joint=("PATH", "prim path of one joint"),
        map_help="TOML/JSON/YAML map of joint pattern -> envelope or datasheet, or a shipped map's name "
        "(unitree-go2, franka-fr3, ...)",
    )
    apply.add_argument(
        "--instance",
        metavar="INST",
        help="drive instance (angular, linear, rotX, rotY, rotZ); default from the joint type",
    )
    add_output_argument(
        apply, "write a new layer over ROBOT.usd here (.usda, .usd or .usdc)", metavar="OUT.usda"
    )
    apply.add_argument(
        "--flatten",
        action="store_true",
        help="with -o: write the whole composed stage as one self-contained file",
    )
    apply.add_argument(
        "--in-place", action="store_true", help="edit ROBOT.usd itself (its root layer) instead of writing -o"
    )
    apply.add_argument(
        "--force", action="store_true", help="replace a read-only output (or asset, with --in-place)"
    )
    add_format_argument(apply, ("text", "json"), "the report on stdout: a line per drive, or one JSON object")
    apply.set_defaults(func=_apply)

    show = actions.add_parser("show", help="list every joint drive with its envelope in SI")
    show.add_argument("asset", metavar="ROBOT.usd", help="USD file to read")
    add_format_argument(show, ("text", "json"), "the drives as a table or as one JSON object (SI)")
    show.set_defaults(func=_show)


def _apply(args: argparse.Namespace) -> int:
    from drive_envelope._src.cli.common import envelope_summary, print_json, printed_warnings, status

    _check_apply_arguments(args)
    with printed_warnings(also_on_error=True):
        applied, written, drives = _apply_and_save(args)
        for item in applied if args.format == "text" else ():
            where = "" if item.authored_at == item.joint_path else f" [authored on {item.authored_at}]"
            print(f"{item.joint_path} ({item.instance}){where}: {envelope_summary(item.envelope)}")
    kind = "in place" if args.in_place else "self-contained" if args.flatten else f"a layer over {args.asset}"
    enveloped = sum(1 for record in drives if record.envelope is not None)
    if args.format == "json":
        from drive_envelope._src.io.envelope_file import envelope_data

        report = {
            "output": written,
            "asset": args.asset,
            "mode": "in-place" if args.in_place else "flatten" if args.flatten else "layer",
            "drives": [
                {
                    "joint": item.joint_path,
                    "instance": item.instance,
                    "authored_at": item.authored_at,
                    "envelope": envelope_data(item.envelope),  # inf as "inf"
                }
                for item in applied
            ],
            "joint_drives": len(drives),
            "with_envelope": enveloped,
        }
        print_json(report, ensure_ascii=False)
    status(
        f"wrote {len(applied)} drive(s) to {written} ({kind}; reopened: {enveloped} of "
        f"{len(drives)} joint drives have an envelope)"
    )
    return 0


def _apply_and_save(args: argparse.Namespace) -> tuple[list[Any], str, list[Any]]:
    """Edit in memory, write (checked before anything is replaced) and list the written drives."""
    from drive_envelope._src.adapters.usd.apply import Assignment, apply_envelopes, map_assignments
    from drive_envelope._src.adapters.usd.authoring import list_drives
    from drive_envelope._src.adapters.usd.joint_map import read_map
    from drive_envelope._src.adapters.usd.save import save_stage
    from drive_envelope._src.adapters.usd.stage import open_overlay, open_stage
    from drive_envelope._src.cli.common import joint_envelope, warn

    joint_map = read_map(args.map) if args.map is not None else None  # map mistakes before any USD work
    stage = open_stage(args.asset) if args.in_place else open_overlay(args.asset)
    if joint_map is not None:
        assignments, map_warnings = map_assignments(stage, joint_map)
        for message in map_warnings:
            warn(message)
    else:
        envelope = joint_envelope(args)
        assignments = [Assignment(joint_path=args.joint, envelope=envelope, instance=args.instance)]
    applied = apply_envelopes(stage, assignments)
    for item in applied:
        for message in item.warnings:
            warn(message)
    from drive_envelope._src.adapters.usd.apply import rating_report

    for message in rating_report(applied):
        warn(message)
    output = None if args.in_place else args.output
    save_stage(stage, output, flatten=args.flatten, force=args.force)
    return applied, args.asset if args.in_place else args.output, list_drives(stage)


def _check_apply_arguments(args: argparse.Namespace) -> None:
    """Refuse inconsistent flags and outputs USD cannot write before any work is done."""
    from pathlib import Path

    from drive_envelope._src.adapters.usd.save import check_output_name
    from drive_envelope._src.cli.common import check_joint_source, checked_output, same_file
    from drive_envelope._src.errors import InputError

    check_joint_source(args, "usd apply", map_excludes=("instance",))
    if args.in_place and (args.output is not None or args.flatten):
        raise InputError("usd apply --in-place: edits ROBOT.usd itself; drop -o/--output and --flatten")
    if args.in_place:
        if Path(args.asset).suffix.lower() == ".usdz":
            raise InputError(
                f"{args.asset}: a .usdz package cannot be edited in place (USD only reads it); write a "
                f"layer over it instead: -o {Path(args.asset).stem}_envelope.usda"
            )
        return
    if args.output is None:
        raise InputError(
            f"usd apply: say where the result goes: -o {Path(args.asset).stem}_envelope.usda writes a new "
            "layer over the asset (which stays as it is), --flatten -o OUT.usd one self-contained file, "
            "--in-place edits the asset itself"
        )
    check_output_name(checked_output(args.output) or "", "--output")
    if same_file(args.output, args.asset):
        raise InputError(f"--output {args.output!r} is the asset itself: use --in-place to edit it")


def _show(args: argparse.Namespace) -> int:
    from drive_envelope._src.adapters.usd.authoring import list_drives
    from drive_envelope._src.adapters.usd.stage import open_stage, stage_units
    from drive_envelope._src.analysis.report import json_float
    from drive_envelope._src.cli.common import print_json, printed_warnings
    from drive_envelope._src.format import format_table, format_value
    from drive_envelope._src.io.envelope_file import envelope_data

    with printed_warnings(also_on_error=True):
        stage = open_stage(args.asset)
        records = list_drives(stage)
    units = stage_units(stage)
    if args.format == "json":
        data = {
            "file": args.asset,
            "meters_per_unit": units.meters_per_unit,
            "kilograms_per_unit": units.kilograms_per_unit,
            "drives": [
                {
                    "joint": r.joint_path,
                    "kind": r.joint_kind,
                    "instance": r.instance,
                    "articulation": r.in_articulation,
                    "max_effort": json_float(r.max_effort),
                    "stiffness": r.stiffness,
                    "damping": r.damping,
                    "envelope": None if r.envelope is None else envelope_data(r.envelope),
                }
                for r in records
            ],
        }
        print_json(data)
        return 0
    print(
        f"{args.asset}: metersPerUnit {units.meters_per_unit:g}, "
        f"kilogramsPerUnit {units.kilograms_per_unit:g}; values in SI"
    )
    if not records:
        print("no joint drives")
        return 0
    rows = []
    for r in records:
        env = r.envelope
        rows.append(
            [
                r.joint_path,
                r.instance,
                "yes" if r.in_articulation else "NO",
                format_value(r.max_effort),
                "-" if env is None else format_value(env.max_actuator_velocity),
                "-" if env is None else format_value(env.velocity_dependent_resistance),
                "-" if env is None else format_value(env.speed_effort_gradient),
            ]
        )
    header = [
        "joint",
        "drive",
        "artic.",
        "max_effort",
        "max_actuator_velocity",
        "velocity_dep_resistance",
        "speed_effort_gradient",
    ]
    print(format_table(header, rows))
    print("units: revolute N*m, rad/s, N*m*s/rad, (rad/s)/(N*m); prismatic N, m/s, N*s/m, (m/s)/N")
    print("'-': no PhysxDrivePerformanceEnvelopeAPI (PhysX uses maxForce alone)")
    if not all(r.in_articulation for r in records):
        print("artic. NO: PhysX does not make it an articulation joint and ignores its envelope")
    return 0

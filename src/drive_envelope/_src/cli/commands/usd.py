"""``drive-envelope usd apply|show``: author envelopes into USD robot assets and list them."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import add_format_argument, add_output_argument


def register(subparsers: Any) -> None:
    """Add the ``usd`` command group."""
    parser = subparsers.add_parser(
        "usd", help="author envelopes into USD assets (PhysxDrivePerformanceEnvelopeAPI)"
    )
    actions = parser.add_subparsers(dest="usd_command", metavar="ACTION")

    apply = actions.add_parser(
        "apply",
        help="write envelopes on joint drives (one joint, or the whole robot from a map file)",
        description="Apply PhysicsDriveAPI + PhysxDrivePerformanceEnvelopeAPI with PhysX's unit conventions "
        "(degrees on angular drives, stage metersPerUnit/kilogramsPerUnit). The input is left untouched "
        "on any error; without --output it is replaced atomically.",
    )
    apply.add_argument("asset", metavar="ROBOT.usd", help="USD file to edit")
    target = apply.add_mutually_exclusive_group(required=True)
    target.add_argument("--joint", metavar="PATH", help="prim path of one joint")
    target.add_argument(
        "--map", metavar="MAP", help="TOML/JSON map of joint-path glob -> envelope or datasheet"
    )
    source = apply.add_mutually_exclusive_group()
    source.add_argument("--datasheet", metavar="FILE", help="datasheet file or catalog name (with --joint)")
    source.add_argument("--envelope", metavar="FILE", help="envelope file (with --joint)")
    apply.add_argument(
        "--instance",
        metavar="INST",
        help="drive instance (angular, linear, rotX..transZ); default from the joint type",
    )
    add_output_argument(apply, "write here instead of replacing ROBOT.usd", metavar="OUT.usd")
    apply.set_defaults(func=_apply)

    show = actions.add_parser("show", help="list every joint drive with its envelope in SI")
    show.add_argument("asset", metavar="ROBOT.usd", help="USD file to read")
    add_format_argument(show, ("text", "json"), "the drives as a table or as one JSON object (SI)")
    show.set_defaults(func=_show)
    parser.set_defaults(func=lambda args: _usage(parser))


def _usage(parser: argparse.ArgumentParser) -> int:
    parser.print_help()
    return 2


def _apply(args: argparse.Namespace) -> int:
    from drive_envelope._src.adapters.usd.apply import apply_envelopes, match_map, read_map
    from drive_envelope._src.adapters.usd.stage import open_stage, save_stage
    from drive_envelope._src.cli.common import checked_output, status, warn
    from drive_envelope._src.datasheet.resolve import resolve_envelope
    from drive_envelope._src.errors import InputError

    if args.joint is not None and args.datasheet is None and args.envelope is None:
        raise InputError("usd apply --joint: needs --datasheet FILE or --envelope FILE")
    if args.map is not None and (args.datasheet is not None or args.envelope is not None or args.instance):
        raise InputError(
            "usd apply --map: the map file names the envelopes; drop --datasheet/--envelope/--instance"
        )
    if checked_output(args.output) is not None:
        _check_output(args.output)
    stage = open_stage(args.asset)
    if args.map is not None:
        assignments = match_map(stage, read_map(args.map), args.map)
    else:
        flag, source = (
            ("--datasheet", args.datasheet) if args.datasheet is not None else ("--envelope", args.envelope)
        )
        envelope = resolve_envelope(source, where=flag)
        assignments = [(args.joint, envelope, args.instance)]
    applied = apply_envelopes(stage, assignments)
    output = args.output if args.output is not None else args.asset
    save_stage(stage, output)
    for item in applied:
        for message in item.warnings:
            warn(message)
        print(f"{item.joint_path} ({item.instance}): {_summary(item.envelope)}")
    status(f"wrote {len(applied)} drive(s) to {output}")
    return 0


def _check_output(output: str) -> None:
    """Refuse an output name USD cannot write before any work is done."""
    from pathlib import Path

    from drive_envelope._src.errors import InputError

    if Path(output).suffix.lower() not in (".usd", ".usda", ".usdc"):
        raise InputError(f"--output {output!r}: expected a .usd, .usda or .usdc file name")
    if not Path(output).parent.exists() and str(Path(output).parent):
        raise InputError(f"--output {output!r}: folder {str(Path(output).parent)!r} does not exist")


def _summary(envelope: Any) -> str:
    from drive_envelope._src.format import format_value
    from drive_envelope._src.params.table import si_unit

    parts = [
        f"{field}={format_value(getattr(envelope, field), si_unit(field, envelope.joint))}"
        for field in (
            "max_effort",
            "max_actuator_velocity",
            "velocity_dependent_resistance",
            "speed_effort_gradient",
        )
    ]
    return ", ".join(parts)


def _show(args: argparse.Namespace) -> int:
    import json
    import math

    from drive_envelope._src.adapters.usd.authoring import list_drives
    from drive_envelope._src.adapters.usd.stage import open_stage, stage_units
    from drive_envelope._src.format import format_table, format_value

    stage = open_stage(args.asset)
    records = list_drives(stage)
    units = stage_units(stage)
    if args.format == "json":

        def number(value: float) -> float | str:
            return value if math.isfinite(value) else repr(value)

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
                    "max_effort": number(r.max_effort),
                    "stiffness": r.stiffness,
                    "damping": r.damping,
                    "envelope": None
                    if r.envelope is None
                    else {
                        k: number(v) if isinstance(v, float) else v for k, v in r.envelope.to_dict().items()
                    },
                }
                for r in records
            ],
        }
        print(json.dumps(data, indent=2))
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
    return 0

"""``drive-envelope mujoco apply|show``: equip MJCF robots with envelope drives and list them."""

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
    """Add the ``mujoco`` command group."""
    parser = subparsers.add_parser(
        "mujoco", help="equip MJCF robots with drive_envelope.envelope drives and list them"
    )
    actions = add_actions(parser, "mujoco_command")

    apply = actions.add_parser(
        "apply",
        help="give joints envelope drives (one joint, or the whole robot from a map file)",
        description="Replace each chosen joint's actuators by a drive_envelope.envelope drive (the actuator "
        "keeps its name and control slot; a position or general PD actuator keeps its kp and kv) and write a "
        "new MJCF that loads in MuJoCo with the plugin. The result is compiled before it is written; on any "
        "error nothing is written.",
    )
    apply.add_argument("model", metavar="ROBOT.xml", help="MJCF file of the robot (or scene)")
    add_joint_source_arguments(
        apply,
        joint=("NAME", "name of one hinge or slide joint"),
        map_help="TOML/JSON/YAML map of joint pattern -> envelope or datasheet (as for usd apply), or the "
        "name of a shipped robot map (drive-envelope catalog --maps)",
    )
    apply.add_argument(
        "--stiffness",
        metavar="K",
        help="drive stiffness for every joint, SI or with units ('60 N*m/rad'); default: the replaced "
        "actuator's kp",
    )
    apply.add_argument(
        "--damping",
        metavar="C",
        help="drive damping for every joint, SI or with units; default: the replaced actuator's kv",
    )
    add_output_argument(apply, "the new MJCF file", metavar="OUT.xml")
    apply.add_argument("--force", action="store_true", help="replace a read-only output file")
    add_format_argument(apply, ("text", "json"), "the report on stdout: a line per drive, or one JSON object")
    apply.set_defaults(func=_apply)

    show = actions.add_parser("show", help="list the model's envelope drives (and joints without one)")
    show.add_argument("model", metavar="ROBOT.xml", help="MJCF file to read")
    add_format_argument(show, ("text", "json"), "the drives as a table or as one JSON object (SI)")
    show.set_defaults(func=_show)

    build = actions.add_parser(
        "build-plugin",
        help="build the native MuJoCo plugin for the installed mujoco (reused when current)",
        description="Compile plugin/mujoco with CMake against the installed mujoco wheel's headers and "
        "library, into plugin/mujoco/build in a checkout or a cache folder per MuJoCo version and "
        "environment for an installed package; prints the library's path. A current build is reused.",
    )
    build.add_argument("--force", action="store_true", help="rebuild even when a current build exists")
    build.add_argument("--build-dir", default=None, metavar="DIR", help="build folder (default: see above)")
    build.add_argument("--quiet", action="store_true", help="show the compiler's output only on failure")
    build.set_defaults(func=_build_plugin)


def _build_plugin(args: argparse.Namespace) -> int:
    from drive_envelope._src.adapters.mujoco.build import build_plugin

    print(build_plugin(build_dir=args.build_dir, quiet=args.quiet, force=args.force))
    return 0


def _check_arguments(args: argparse.Namespace) -> None:
    from pathlib import Path

    from drive_envelope._src.cli.common import check_joint_source, checked_output, same_file
    from drive_envelope._src.errors import InputError

    check_joint_source(args, "mujoco apply")
    if args.output is None:
        raise InputError(
            f"mujoco apply: say where the result goes: -o {Path(args.model).stem}_envelope.xml (MuJoCo's "
            "writer drops comments and includes, so ROBOT.xml itself is never rewritten)"
        )
    output = checked_output(args.output) or ""
    if Path(output).suffix.lower() != ".xml":
        raise InputError(f"--output {output!r}: expected an .xml file name")
    if same_file(output, args.model):
        raise InputError(f"--output {output!r} is ROBOT.xml itself: write a new file")


def _assignments(args: argparse.Namespace, spec: Any) -> list[Any]:
    from drive_envelope._src.adapters.mujoco.mjcf import Assignment, driven_joints
    from drive_envelope._src.adapters.usd.joint_map import match_joints, read_map, resolve_envelopes
    from drive_envelope._src.cli.common import joint_envelope, warn

    if args.map is None:
        return [Assignment(joint=args.joint, envelope=joint_envelope(args), where="--joint")]
    joint_map = read_map(args.map)  # a file, or a shipped robot map's name
    match = match_joints(joint_map, driven_joints(spec))
    for message in match.warnings:
        warn(message)
    items = []
    for item in resolve_envelopes(match):
        if item.entry.instance is not None:
            warn(f"{item.entry.where}: key 'instance' is a USD drive instance; MuJoCo ignores it")
        if item.envelope is not None:
            items.append(Assignment(joint=item.joint, envelope=item.envelope, where=item.entry.where))
    return items


def _apply(args: argparse.Namespace) -> int:
    import warnings

    from drive_envelope._src.adapters.mujoco.bypass import bypass_warnings, is_bypass_warning, other_actuators
    from drive_envelope._src.adapters.mujoco.contacts import neighbour_contact_warnings, neighbour_contacts
    from drive_envelope._src.adapters.mujoco.loader import load_plugin
    from drive_envelope._src.adapters.mujoco.mjcf import apply_drives, load_spec, write_mjcf
    from drive_envelope._src.adapters.mujoco.params import model_drives
    from drive_envelope._src.cli.common import status, warn

    _check_arguments(args)
    load_plugin()
    spec = load_spec(args.model)
    assignments = _assignments(args, spec)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        done = apply_drives(spec, assignments, stiffness=args.stiffness, damping=args.damping)
        model = write_mjcf(spec, args.output, source=args.model, force=args.force)
    drives = model_drives(model)
    # the plugin warns once per process and per joint; say it once per actuator, from the result,
    # and an actuatorfrcrange only where it can bind, once per map key (_report)
    for message in dict.fromkeys(str(w.message) for w in caught):
        if not is_bypass_warning(message) and not _is_frcrange_warning(message):
            warn(message)
    for message in bypass_warnings(other_actuators(model, drives)):
        warn(message)
    for message in _report(done, model):
        warn(message)
    for message in _half_gains(done, args):
        warn(message)
    for message in neighbour_contact_warnings(neighbour_contacts(model), [item.joint for item in done]):
        warn(f"{args.model}: {message}")
    if args.format == "json":
        _print_apply_json(done, args, len(drives))
    for item in done if args.format == "text" else ():
        replaced = f"replaces {item.replaced}" if item.replaced else "new actuator"
        print(
            f"{item.joint}: drive {item.drive!r} ({replaced}; inputs {' '.join(item.inputs)}; gains "
            f"{item.gains_from}): {_summary(item.envelope, item.stiffness, item.damping)}"
        )
    status(f"wrote {len(done)} drive(s) to {args.output} (reloaded: {len(drives)} drives)")
    return 0


def _half_gains(done: list[Any], args: argparse.Namespace) -> list[str]:
    """One line where --stiffness or --damping alone left joints with the replaced actuators' other gain."""
    from drive_envelope._src.format import first_few

    given = "--stiffness" if args.stiffness is not None else "--damping"
    other = "damping" if given == "--stiffness" else "stiffness"
    mixed = [item for item in done if item.kept_gain is not None]
    if not mixed:
        return []
    units = {("damping", "revolute"): "N*m*s/rad", ("damping", "prismatic"): "N*s/m"}
    units |= {("stiffness", "revolute"): "N*m/rad", ("stiffness", "prismatic"): "N/m"}
    shown = [f"{i.joint} {getattr(i, other):.6g} {units[other, i.envelope.joint]}" for i in mixed]
    kept = first_few(shown, 3, str)
    return [
        f"{given} is given without --{other}: {len(mixed)} joint(s) keep their replaced actuator's "
        f"{other} ({kept}), tuned for its own gains; give --{other} too to set both"
    ]


def _print_apply_json(done: list[Any], args: argparse.Namespace, reloaded: int) -> None:
    """The report of ``mujoco apply`` as one JSON object on stdout (inf written as ``"inf"``)."""
    from drive_envelope._src.cli.common import print_json
    from drive_envelope._src.io.envelope_file import envelope_data

    drives = [
        {
            "joint": item.joint,
            "drive": item.drive,
            "replaced": item.replaced,
            "inputs": list(item.inputs),
            "gains_from": item.gains_from,
            "stiffness": item.stiffness,
            "damping": item.damping,
            "envelope": envelope_data(item.envelope),
        }
        for item in done
    ]
    report = {"output": args.output, "model": args.model, "drives": drives, "reloaded_drives": reloaded}
    print_json(report, ensure_ascii=False)


def _is_frcrange_warning(message: str) -> bool:
    """Whether ``message`` is the plugin's note that a driven joint has an ``actuatorfrcrange``."""
    return message.startswith("drive_envelope.envelope: joint ") and "has an actuatorfrcrange" in message


def _report(done: list[Any], model: Any) -> list[str]:
    """Caps below the model's own rating, actuatorfrcranges that bind, equalities between drives."""
    from drive_envelope._src.adapters.mujoco.ratings import (
        binding_force_ranges,
        coupled_driven_joints,
        rating_lines,
    )

    groups: dict[str, list[tuple[str, float, str]]] = {}
    for item in done:
        groups.setdefault(item.where, []).append((item.joint, item.envelope.max_effort, item.envelope.joint))
    ratings = {item.joint: item.rating for item in done if item.rating is not None}
    return (
        binding_force_ranges(groups, ratings)
        + rating_lines(groups, ratings)
        + coupled_driven_joints(model, [item.joint for item in done])
    )


def _summary(envelope: Any, stiffness: float, damping: float) -> str:
    from drive_envelope._src.cli.common import envelope_summary
    from drive_envelope._src.format import format_value

    gains = ("N*m/rad", "N*m*s/rad") if envelope.joint == "revolute" else ("N/m", "N*s/m")
    return (
        f"{envelope_summary(envelope)}, stiffness={format_value(stiffness, gains[0])}, "
        f"damping={format_value(damping, gains[1])}"
    )


def _show(args: argparse.Namespace) -> int:
    from drive_envelope._src.adapters.mujoco.bypass import other_actuators
    from drive_envelope._src.adapters.mujoco.mjcf import read_model, uses_plugin
    from drive_envelope._src.adapters.mujoco.params import model_drives
    from drive_envelope._src.analysis.report import json_float
    from drive_envelope._src.cli.common import print_json, printed_warnings
    from drive_envelope._src.format import format_table, format_value
    from drive_envelope._src.io.envelope_file import envelope_data

    with printed_warnings():
        model = read_model(args.model)
    drives = model_drives(model) if uses_plugin(model) else ()
    others = other_actuators(model, drives)
    if args.format == "json":
        data = {
            "file": args.model,
            "drives": [
                {
                    "actuator": d.name,
                    "joint": d.joint,
                    "inputs": list(d.inputs),
                    "drive_type": d.drive_type,
                    "dynprm": [json_float(v) for v in d.dynprm],
                    "envelope": None if d.envelope is None else envelope_data(d.envelope),
                    "stiffness": d.stiffness,
                    "damping": d.damping,
                }
                for d in drives
            ],
            "other_actuators": [
                {
                    "joint": o.joint,
                    "actuator": o.actuator,
                    "kind": o.kind,
                    "transmission": o.transmission,
                    "bypasses_drive": o.drive,
                }
                for o in others
            ],
        }
        print_json(data)
        return 0
    print(f"{args.model}: {len(drives)} drive_envelope.envelope drive(s); values in SI")
    if drives:
        rows = []
        for d in drives:
            limit = "no limit" if d.dynprm[0] == -1 else format_value(d.dynprm[0])
            speed = "inf" if d.dynprm[1] == -1 else format_value(d.dynprm[1])
            rows.append(
                [d.name, d.joint, " ".join(d.inputs), limit, speed, format_value(d.dynprm[2]),
                 format_value(d.dynprm[3]), format_value(d.stiffness), format_value(d.damping)]
            )  # fmt: skip
        header = ["actuator", "joint", "inputs", "max_effort", "max_actuator_velocity",
                  "velocity_dep_resistance", "speed_effort_gradient", "stiffness", "damping"]  # fmt: skip
        print(format_table(header, rows))
        print(
            "units: revolute N*m, rad/s, N*m*s/rad, (rad/s)/(N*m), N*m/rad, N*m*s/rad; prismatic N, m/s, ..."
        )
    if others:
        print("joints with other actuators (their force bypasses any envelope):")
        rows = [[o.joint, o.actuator, o.kind, o.transmission, o.drive or "-"] for o in others]
        print(format_table(["joint", "actuator", "kind", "transmission", "bypasses drive"], rows))
    return 0

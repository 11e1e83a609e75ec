"""``drive-envelope derive SPEC``: the envelope from a datasheet file or a catalog actuator."""

from __future__ import annotations

import argparse
import os
from typing import Any

from drive_envelope._src.cli.common import add_force_argument, add_format_argument, add_output_argument


def register(subparsers: Any) -> None:
    """Add the ``derive`` command."""
    from drive_envelope._src.datasheet.spec import GRADIENT_METHODS  # numpy-free: --help stays light

    parser = subparsers.add_parser(
        "derive",
        help="derive the envelope from motor, gear and controller datasheets",
        description=(
            "Derive the four PhysX envelope parameters at the joint from a datasheet file (values in the "
            "units the datasheets print) or a catalog actuator; every candidate limit is shown and the "
            "binding one named."
        ),
    )
    parser.add_argument("spec", metavar="FILE|NAME", help="datasheet file (TOML/JSON/YAML) or catalog name")
    add_format_argument(
        parser,
        ("text", "json", "toml", "envelope-json", "usd-snippet"),
        "what to print: the report, the derivation as JSON (SI), or the envelope as a TOML file, "
        "a JSON file or a USD snippet",
    )
    add_output_argument(
        parser, "also write the envelope file here, atomically (format from the suffix: .toml, .json, .usda)"
    )
    add_force_argument(parser)  # the read-only refusal names --force: every command with -o takes it
    parser.add_argument(
        "--duty",
        choices=("peak", "continuous"),
        default="peak",
        help="motor torque rating: max_torque (peak, default) or continuous_torque",
    )
    parser.add_argument(
        "--gradient-method",
        choices=GRADIENT_METHODS,
        help="motor speed-torque gradient when the voltage limit binds (default: the file's, else auto)",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="SECTION.KEY=VALUE",
        help="override a datasheet value, e.g. --set controller.max_voltage='48 V' (repeatable; a bare "
        "number is SI, as in a file)",
    )
    parser.add_argument(
        "--approximate-line",
        action="store_true",
        help="when a mechanical limit binds, also report the best line through min(mechanical, voltage)",
    )
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.cli.common import (
        checked_output,
        print_json,
        refuse_input_as_output,
        status,
        warn,
    )
    from drive_envelope._src.datasheet.catalog import load_catalog_datasheet
    from drive_envelope._src.datasheet.derive import derive
    from drive_envelope._src.datasheet.load import load_datasheet
    from drive_envelope._src.datasheet.report import derivation_report, envelope_text
    from drive_envelope._src.datasheet.resolve import refuse_missing_file
    from drive_envelope._src.io.atomic import atomic_write_text

    output = checked_output(args.output)
    file_format = _format_from_suffix(output) if output is not None else None
    refuse_input_as_output(output, args.spec, "the datasheet", "the envelope")
    overrides = _overrides(args.set)
    if os.path.exists(args.spec):  # not is_file(): a FIFO or a device is refused by type when read
        sheet = load_datasheet(args.spec, overrides=overrides)
    else:
        refuse_missing_file(args.spec)
        sheet = load_catalog_datasheet(args.spec, overrides=overrides)
    derivation = derive(
        sheet, duty=args.duty, gradient_method=args.gradient_method, approximate_line=args.approximate_line
    )
    if output is not None and file_format is not None:
        atomic_write_text(output, envelope_text(derivation.envelope, file_format), force=args.force)
    if args.format == "json":
        print_json(derivation.to_dict())
    elif args.format == "text":
        print(derivation_report(derivation))
    else:
        print(envelope_text(derivation.envelope, args.format), end="")
    for warning in derivation.warnings:  # on stderr too: stdout may be a file nobody reads now
        warn(warning)
    if output is not None:
        status(f"wrote {output} ({file_format})")
    return 0


def _overrides(items: list[str]) -> dict[str, object]:
    """``SECTION.KEY=VALUE`` strings -> mapping of strings, read like a quoted value in a file.

    The value stays text: the datasheet reader applies the one rule for values, so a bare number is
    SI exactly as in a file (``--set gear.ratio=6`` and ``ratio = "6"`` mean the same), and
    ``1e400``, ``nan`` or ``1_000`` are refused the same way.
    """
    from drive_envelope._src.errors import InputError

    result: dict[str, object] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise InputError(
                f"--set {item!r}: expected SECTION.KEY=VALUE, e.g. controller.max_voltage='48 V'"
            )
        if key.strip() in result:
            raise InputError(f"--set {key.strip()!r} given twice; give each key once")
        result[key.strip()] = value.strip()
    return result


_OUTPUT_FORMATS = {".toml": "toml", ".json": "envelope-json", ".usda": "usd-snippet", ".usd": "usd-snippet"}


def _format_from_suffix(output: str) -> str:
    """The envelope format the name of ``-o`` asks for; any other suffix is refused before any work."""
    from pathlib import Path

    from drive_envelope._src.errors import InputError

    suffix = Path(output).suffix.lower()
    if suffix not in _OUTPUT_FORMATS:
        raise InputError(
            f"--output {output!r}: expected a file name ending in .toml, .json, .usda or .usd "
            "(the envelope format is taken from the suffix)"
        )
    return _OUTPUT_FORMATS[suffix]

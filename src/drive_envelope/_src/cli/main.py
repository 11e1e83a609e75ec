"""The ``drive-envelope`` command line: subcommands discovered in ``_src/cli/commands``.

Every user mistake ends in one line on stderr (``drive-envelope: error: ...``) and exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from collections.abc import Sequence

from drive_envelope._src.errors import DriveEnvelopeError

__all__ = ["build_parser", "main"]

PROG = "drive-envelope"


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser, with every subcommand module registered."""
    from drive_envelope._src.cli import commands
    from drive_envelope._src.version import VERSION as __version__

    parser = argparse.ArgumentParser(
        prog=PROG,
        description="The PhysX drive performance envelope: derive, inspect, simulate, check.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    modules = [
        importlib.import_module(f"{commands.__name__}.{info.name}")
        for info in pkgutil.iter_modules(commands.__path__)
        if not info.name.startswith("_")
    ]
    for module in sorted(modules, key=lambda m: (getattr(m, "ORDER", 100), m.__name__)):
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the exit status (0 ok, 1 a check failed, 2 bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except DriveEnvelopeError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0

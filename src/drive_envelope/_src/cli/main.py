"""The ``drive-envelope`` command line: every subcommand, registered explicitly in :data:`COMMANDS`.

Every user mistake ends in one line on stderr (``drive-envelope: error: ...``) and exit status 2,
a bad flag included (:class:`~drive_envelope._src.cli.common.Parser`). A bug ends in one line too
(exit 1), with a hint to report it; ``DRIVE_ENVELOPE_TRACEBACK=1`` shows the traceback. Building
the parser imports only the command modules, which import their work lazily, so ``--help`` and
argument errors load neither NumPy nor an engine.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from drive_envelope._src.cli.commands import (
    catalog,
    check,
    derive,
    envelope,
    fit,
    identify,
    mujoco,
    plot,
    simulate,
    usd,
)
from drive_envelope._src.cli.common import PROG, Parser
from drive_envelope._src.errors import DriveEnvelopeError
from drive_envelope._src.version import VERSION

__all__ = ["COMMANDS", "build_parser", "main"]

COMMANDS = (derive, catalog, envelope, simulate, plot, usd, mujoco, check, fit, identify)
"""The subcommand modules, in the order ``--help`` lists them; each has ``register(subparsers)``."""

_ISSUES = "https://github.com/drive-envelope/drive-envelope/issues"


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser, with every subcommand of :data:`COMMANDS` registered."""
    parser = Parser(
        prog=PROG,
        description="The PhysX drive performance envelope: derive, inspect, simulate, check.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {VERSION}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in COMMANDS:
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the exit status (0 ok, 1 a check failed or a bug, 2 bad input)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a bad flag (one line, see Parser): its status
        return exc.code if isinstance(exc.code, int) else 2
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
    except Exception as exc:  # last resort: a bug, never a user mistake (those are InputError)
        if os.environ.get("DRIVE_ENVELOPE_TRACEBACK"):
            raise
        detail = " ".join(str(exc).split())[:300]
        print(
            f"{PROG}: internal error: {type(exc).__name__}: {detail} (a bug: please report it at "
            f"{_ISSUES} with the command; DRIVE_ENVELOPE_TRACEBACK=1 shows the traceback)",
            file=sys.stderr,
        )
        return 1

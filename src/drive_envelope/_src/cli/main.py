"""The ``drive-envelope`` command line: every subcommand, registered explicitly in :data:`COMMANDS`.

Every user mistake ends in one line on stderr (``drive-envelope: error: ...``) and exit status 2,
a bad flag included (:class:`~drive_envelope._src.cli.common.Parser`). A bug ends in one line too
(exit 1), with a hint to report it; ``DRIVE_ENVELOPE_TRACEBACK=1`` shows the traceback. Building
the parser imports only the command modules, which import their work lazily, so ``--help`` and
argument errors load neither NumPy nor an engine.
"""

from __future__ import annotations

import argparse
import errno
import os
import sys
from collections.abc import Sequence
from typing import TextIO

from drive_envelope._src.cli.commands import (
    catalog,
    check,
    derive,
    envelope,
    fit,
    identify,
    mujoco,
    plot,
    replay,
    simulate,
    usd,
)
from drive_envelope._src.cli.common import PROG, Parser
from drive_envelope._src.errors import DriveEnvelopeError, InputError
from drive_envelope._src.version import VERSION

COMMANDS = (derive, catalog, envelope, simulate, plot, usd, mujoco, check, fit, identify, replay)
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


class _StandardOutput:
    """Standard output that survives its reader leaving and says so when it cannot be written.

    ``check ... | head -1`` must still exit 1 on a failed check: once the pipe is closed, the rest of
    the output goes to the null device and the command runs to its real exit status. Any other write
    error (a full disk behind ``> file``) is the user's environment, not a bug: one line, exit 2.
    """

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        self._guarded(lambda: self._stream.write(text))
        return len(text)

    def flush(self) -> None:
        self._guarded(self._stream.flush)

    def __getattr__(self, name: str) -> object:
        return getattr(self._stream, name)

    def _guarded(self, action: object) -> None:
        try:
            action()  # type: ignore[operator]
        except BrokenPipeError:
            self._discard()
        except OSError as exc:
            self._discard()
            reason = os.strerror(exc.errno) if exc.errno else str(exc)
            raise InputError(f"cannot write to standard output: {reason}") from None

    def _discard(self) -> None:
        """Point the file descriptor at the null device: what is still buffered and written later goes."""
        try:
            fileno = self._stream.fileno()
        except (OSError, ValueError):
            return
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, fileno)
        os.close(null)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the exit status (0 ok, 1 a check failed or a bug, 2 bad input)."""
    if isinstance(sys.stdout, _StandardOutput) or sys.stdout is None:
        return _main(argv)
    original = sys.stdout
    sys.stdout = _StandardOutput(original)  # type: ignore[assignment]
    try:
        return _main(argv)
    finally:
        sys.stdout = original


def _parse(parser: argparse.ArgumentParser, argv: list[str]) -> argparse.Namespace:
    """``parse_args`` whose unknown-flag error names the subcommand and the nearest flag.

    argparse reports leftovers from the top-level parser (``drive-envelope: error: unrecognized
    arguments: --tolerence 0.1 (see drive-envelope --help)``); the subcommand's parser knows the
    flags to suggest and the help to point to.
    """
    import difflib

    args, extra = parser.parse_known_args(argv)
    if not extra:
        return args
    command = parser
    for token in argv:  # the chain of subcommands named before the first unknown token
        choices = next(
            (a.choices for a in command._actions if isinstance(a, argparse._SubParsersAction)), None
        )
        if choices is None or token not in choices:
            if token == extra[0]:
                break
            continue
        command = choices[token]
    flags = [flag for action in command._actions for flag in action.option_strings]
    hints = []
    for item in extra:
        if item.startswith("--"):
            flag = item.split("=", 1)[0]
            # a prefix of flags (argparse abbreviations are off: say them in full), else the nearest
            close = [f for f in flags if f.startswith(flag)][:3]
            close = close or difflib.get_close_matches(flag, flags, n=1, cutoff=0.6)
            hints += [f"{flag}: did you mean {' or '.join(close)}?"] if close else []
    hint = f" ({'; '.join(hints)})" if hints else ""
    command.error(f"unrecognized arguments: {' '.join(extra)}{hint}")


def _main(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    try:
        args = _parse(parser, sys.argv[1:] if argv is None else list(argv))
    except SystemExit as exc:  # --help, --version, or a bad flag (one line, see Parser): its status
        return exc.code if isinstance(exc.code, int) else 2
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    try:
        status = int(args.func(args) or 0)
        sys.stdout.flush()  # a write error surfaces here, not after the status is decided
        return status
    except DriveEnvelopeError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # a pipe other than standard output (which _StandardOutput handles)
        return 141  # what a shell reports for a writer ended by SIGPIPE
    except OSError as exc:
        if exc.errno != errno.ENAMETOOLONG:
            return _internal_error(exc)
        # a path the readers did not check first (Path.is_file() raises on it): still the user's
        from drive_envelope._src.io.paths import check_path_name

        try:
            check_path_name(os.fsdecode(exc.filename or ""))
        except InputError as named:
            print(f"{PROG}: error: {named}", file=sys.stderr)
        else:
            print(f"{PROG}: error: a file name is too long (at most 255 bytes per name)", file=sys.stderr)
        return 2
    except Exception as exc:  # last resort: a bug, never a user mistake (those are InputError)
        return _internal_error(exc)


def _internal_error(exc: Exception) -> int:
    """Report a bug in one line (exit 1), or re-raise it with ``DRIVE_ENVELOPE_TRACEBACK=1``."""
    if os.environ.get("DRIVE_ENVELOPE_TRACEBACK"):
        raise exc
    detail = " ".join(str(exc).split())[:300]
    print(
        f"{PROG}: internal error: {type(exc).__name__}: {detail} (a bug: please report it at "
        f"{_ISSUES} with the command; DRIVE_ENVELOPE_TRACEBACK=1 shows the traceback)",
        file=sys.stderr,
    )
    return 1

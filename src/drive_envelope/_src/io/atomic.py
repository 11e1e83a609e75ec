"""Atomic output: write to a temporary file beside the target, then rename over it.

A failed or interrupted command therefore never leaves a half-written output file:

* the temporary file ``.<name>.<random>.tmp<suffix>`` sits in the target's folder and is removed on
  any error, on Ctrl-C (SIGINT) and on SIGTERM; only SIGKILL (or a power cut) can leave one behind,
  and its name always matches that pattern;
* a target that is a symbolic link is written through: the link stays, the file it points to is
  replaced (so the real asset is edited, not the link turned into a copy);
* a read-only target is refused unless ``force=True``: a 0444 file is somebody's way of saying
  "do not edit this";
* the new file gets the mode of the file it replaces (else the umask's default) and, where the
  process may, its owner and group.

Every failure is an :class:`~drive_envelope._src.errors.InputError` naming the file: a missing
folder, a folder given as the file, no permission, a full disk.
"""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from types import FrameType

from drive_envelope._src.errors import InputError

__all__ = [
    "TEMPORARY_PATTERN",
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_writable",
    "write_target",
]

TEMPORARY_PATTERN = ".<name>.*.tmp<suffix>"
"""Name of the temporary file beside the target; only a SIGKILL mid-write can leave one."""


def write_target(path: str | os.PathLike[str]) -> Path:
    """The file a write to ``path`` replaces: ``path`` itself, or the end of its symlink chain."""
    target = Path(path)
    if target.is_symlink():
        return Path(os.path.realpath(target))
    return target


def check_writable(path: str | os.PathLike[str], *, force: bool = False) -> None:
    """Refuse now what :func:`atomic_path` would refuse at the end of a long run.

    Raises:
        InputError: the folder does not exist, the target is a folder, or it is read-only (without
            ``force``).
    """
    _check_target(write_target(path), Path(path), force)


def _check_target(target: Path, shown: Path, force: bool) -> None:
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise InputError(f"{shown}: cannot write: folder {str(directory)!r} does not exist")
    if target.is_dir():
        raise InputError(f"{shown}: cannot write: it is a folder; expected a file name")
    if target.exists() and not force and _read_only(target):
        raise InputError(f"{shown}: cannot write: the file is read-only (pass --force to replace it)")


def _read_only(target: Path) -> bool:
    """No write permission for this process, or no write bit at all (root may write a 0444 file)."""
    return not os.access(target, os.W_OK) or not target.stat().st_mode & 0o222


class _Interrupted(BaseException):
    """SIGTERM arrived while a temporary file existed (turned into an exception to clean up)."""


@contextlib.contextmanager
def _cleanup_on_sigterm() -> Iterator[None]:
    """Turn SIGTERM into an exception while the block runs (main thread only), so ``finally`` runs."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        raise _Interrupted(signum)

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, force: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it is renamed to ``path``, else removed.

    The temporary file keeps the target's suffix so writers that pick a format from it (matplotlib,
    USD) still work.

    Args:
        path: The output file; a symlink is written through to its target.
        force: Replace a read-only target.

    Raises:
        InputError: the folder does not exist, the target is a folder or read-only (without
            ``force``), or the file cannot be created or filled (no permission, disk full).
    """
    shown = Path(path)
    target = write_target(shown)
    _check_target(target, shown, force)
    try:
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{target.name}.", suffix=f".tmp{target.suffix}", dir=target.parent or Path(".")
        )
    except OSError as exc:
        raise InputError(f"{shown}: cannot write: {exc.strerror}") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        with _cleanup_on_sigterm():
            try:
                yield tmp
                _copy_metadata(target, tmp)
                os.replace(tmp, target)
            except _Interrupted:
                raise SystemExit(128 + signal.SIGTERM) from None
    except OSError as exc:
        raise InputError(f"{shown}: cannot write: {_reason(exc)}") from None
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _reason(exc: OSError) -> str:
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    return exc.strerror or str(exc)


def _copy_metadata(target: Path, tmp: Path) -> None:
    """Give ``tmp`` the mode (and, where allowed, owner) of ``target``, or a new file's default mode."""
    if not target.exists():
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes it 0600; a plain open() would not
        return
    stat = target.stat()
    os.chmod(tmp, stat.st_mode & 0o7777)
    if hasattr(os, "chown"):
        with contextlib.suppress(OSError):  # only root (or the owner, for the group) may
            os.chown(tmp, stat.st_uid, stat.st_gid)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_text(path: str | os.PathLike[str], text: str, *, force: bool = False) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path, force=force) as tmp:
        tmp.write_text(text, encoding="utf-8")


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes, *, force: bool = False) -> None:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path, force=force) as tmp:
        tmp.write_bytes(data)

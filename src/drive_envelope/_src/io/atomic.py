"""Atomic output: write to a temporary file beside the target, then rename over it.

A failed or interrupted command therefore never leaves a half-written output file:

* the temporary file ``.<name>.<random>.tmp<suffix>`` sits in the target's folder and is removed on
  any error, on Ctrl-C (SIGINT) and on SIGTERM; only SIGKILL (or a power cut) can leave one behind,
  and its name always matches that pattern;
* a target that is a symbolic link is written through: the link stays, the file it points to is
  replaced (so the real asset is edited, not the link turned into a copy);
* a target that is not a regular file is never replaced by one: a character device (``/dev/null``,
  a terminal, ``-o /dev/stdout``) or a FIFO is written through once the output is complete (it is
  made in a temporary file of the system's temporary folder first, so a failed command still
  writes nothing); a FIFO without a reader, a block device and a socket are refused;
* missing folders of the target are created (and removed again when the write fails);
* a read-only target is refused unless ``force=True``: a 0444 file is somebody's way of saying
  "do not edit this";
* the new file gets the mode of the file it replaces (else the umask's default) and, where the
  process may, its owner and group.

Every failure is an :class:`~drive_envelope._src.errors.InputError` naming the file: a file where
a folder should be, a folder given as the file, a name too long, no permission, a full disk.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import signal
import stat
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from types import FrameType

from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import check_path_name, node_kind

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
        InputError: a name too long, a file where a folder should be, the target is a folder, a
            block device or a socket, or it is read-only (without ``force``).
    """
    shown = Path(path)
    check_path_name(shown)
    if _stream_kind(shown) is None:
        _check_target(write_target(shown), shown, force)


def _stream_kind(shown: Path) -> str | None:
    """What ``shown`` is when it is a FIFO or a character device (written through), else None.

    None for a regular or missing file; a block device or a socket is refused. ``/dev/stdout``,
    ``/dev/stderr`` and ``/dev/fd/N`` are always written through their open descriptor, whatever it
    is: replacing the file a shell redirected stdout to (``> run.csv``, ``>> log``) would lose it.
    """
    if _descriptor(shown) is not None:
        return "an open file descriptor"
    try:
        # os.stat follows every link, /dev/stdout's /proc/self/fd/1 (a pipe, a terminal) included
        mode = os.stat(shown).st_mode
    except OSError:
        return None  # missing (or unreachable): _check_target names the reason
    kind = node_kind(mode)
    if kind is None:
        return None
    if stat.S_ISFIFO(mode) or stat.S_ISCHR(mode):
        return kind
    raise InputError(f"{shown}: cannot write: it is {kind}; expected a file name")


def _check_target(target: Path, shown: Path, force: bool) -> None:
    check_path_name(target, str(shown))
    if target.is_dir():
        raise InputError(f"{shown}: cannot write: it is a folder; expected a file name")
    folder = _existing_ancestor(target)
    if not folder.is_dir():
        raise InputError(f"{shown}: cannot write: {str(folder)!r} is a file, not a folder")
    if target.exists() and not force and _read_only(target):
        raise InputError(f"{shown}: cannot write: the file is read-only (pass --force to replace it)")


def _existing_ancestor(target: Path) -> Path:
    """The nearest folder above ``target`` that exists (or the file in the way of one)."""
    folder = target.parent if str(target.parent) else Path(".")
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    return folder


def _make_folders(target: Path, shown: Path) -> list[Path]:
    """Create the missing folders above ``target``; return them, deepest first (to undo)."""
    missing = []
    folder = target.parent if str(target.parent) else Path(".")
    while not folder.exists() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    for created in reversed(missing):
        try:
            created.mkdir()
        except FileExistsError:
            pass  # another writer made it meanwhile
        except OSError as exc:
            _remove_folders(missing)
            raise InputError(f"{shown}: cannot create folder {str(created)!r}: {_reason(exc)}") from None
    return missing


def _remove_folders(folders: list[Path]) -> None:
    for folder in folders:  # deepest first; one another writer has filled meanwhile stays
        with contextlib.suppress(OSError):
            folder.rmdir()


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
    USD) still work. A FIFO or character device target gets the finished file's bytes instead.

    Args:
        path: The output file; a symlink is written through to its target, missing folders are
            created.
        force: Replace a read-only target.

    Raises:
        InputError: a name too long, a file where a folder should be, the target is a folder, a
            block device, a socket, a FIFO without a reader or read-only (without ``force``), or the
            file cannot be created or filled (no permission, disk full).
    """
    shown = Path(path)
    check_path_name(shown)
    kind = _stream_kind(shown)
    if kind is not None:
        with _streamed(shown, kind) as tmp:
            yield tmp
        return
    target = write_target(shown)
    _check_target(target, shown, force)
    created = _make_folders(target, shown)
    try:
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{target.name[:200]}.", suffix=f".tmp{target.suffix}", dir=target.parent or Path(".")
        )
    except OSError as exc:
        _remove_folders(created)
        raise InputError(f"{shown}: cannot write: {_reason(exc)}") from None
    os.close(fd)
    tmp = Path(tmp_name)
    done = False
    try:
        with _finishing(tmp, shown):
            yield tmp
            _copy_metadata(target, tmp)
            os.replace(tmp, target)
            done = True
    finally:
        if not done:
            _remove_folders(created)


@contextlib.contextmanager
def _streamed(shown: Path, kind: str) -> Iterator[Path]:
    """Yield a temporary path in the system's temporary folder; on success copy it into ``shown``.

    The device or FIFO is opened only once the output is complete, so a failed command writes
    nothing to it, and a FIFO's reader sees one whole file.
    """
    fd, tmp_name = tempfile.mkstemp(prefix="drive-envelope.", suffix=f".tmp{shown.suffix[:32]}")
    os.close(fd)
    tmp = Path(tmp_name)
    with _finishing(tmp, shown):
        yield tmp
        _copy_into(tmp, shown, kind)


@contextlib.contextmanager
def _finishing(tmp: Path, shown: Path) -> Iterator[None]:
    """Remove ``tmp`` after the block, however it ends; SIGTERM exits, an OSError names ``shown``."""
    try:
        with _cleanup_on_sigterm():
            try:
                yield
            except _Interrupted:
                raise SystemExit(128 + signal.SIGTERM) from None
    except OSError as exc:
        raise InputError(f"{shown}: cannot write: {_reason(exc)}") from None
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _descriptor(shown: Path) -> int | None:
    """The descriptor ``shown`` names (``/dev/stdout`` 1, ``/dev/fd/3`` 3), or None for other paths."""
    text = os.fspath(shown)
    named = {"/dev/stdout": 1, "/dev/stderr": 2}
    if text in named:
        return named[text]
    for prefix in ("/dev/fd/", "/proc/self/fd/"):
        if text.startswith(prefix) and text[len(prefix) :].isdigit():
            return int(text[len(prefix) :])
    return None


def _write_all(out: int, tmp: Path) -> None:
    with open(tmp, "rb") as source:
        while block := source.read(1 << 20):
            view = memoryview(block)
            while view:
                view = view[os.write(out, view) :]


def _copy_into(tmp: Path, shown: Path, kind: str) -> None:
    """Write the bytes of ``tmp`` through ``shown`` (a FIFO or a character device), never replacing it."""
    descriptor = _descriptor(shown)
    if descriptor is not None:  # the process's own stream: its offset and O_APPEND are kept
        if descriptor == 1:
            sys.stdout.flush()  # anything the command printed goes first
        _write_all(descriptor, tmp)
        return
    try:
        # O_NONBLOCK: a FIFO without a reader fails at once (ENXIO) instead of waiting for ever
        out = os.open(shown, os.O_WRONLY | os.O_NONBLOCK)
    except OSError as exc:
        if exc.errno == errno.ENXIO:
            raise InputError(
                f"{shown}: cannot write: it is {kind} and nothing reads from it (start the reader first)"
            ) from None
        raise
    try:
        flags = fcntl.fcntl(out, fcntl.F_GETFL)
        fcntl.fcntl(out, fcntl.F_SETFL, flags & ~os.O_NONBLOCK)  # now block as a plain write would
        _write_all(out, tmp)
    finally:
        os.close(out)


def _reason(exc: OSError) -> str:
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    if exc.errno == errno.EPIPE:
        return "the reader closed the pipe before the output was complete"
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

"""What every input and output path goes through first: name lengths, file types and sizes.

One rule for every reader and writer, so no command can hang, exhaust memory or crash on a path:

* a name component over :data:`NAME_MAX` bytes (or a path over :data:`PATH_MAX`) is a one-line
  :class:`InputError` naming it, never ``OSError: [Errno 36] File name too long``;
* an input must be a regular file: a FIFO (which would block for ever without a writer), a device
  (``/dev/zero`` is endless) or a socket is refused *before* it is opened, by its type;
* a text input read whole is at most :data:`MAX_TEXT_BYTES`; the error says so (logs are read in
  bounded-memory chunks and have no such cap).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from drive_envelope._src.errors import InputError

NAME_MAX = 255
"""Longest name of one path component [bytes] (Linux, macOS and Windows file systems)."""

PATH_MAX = 4095
"""Longest whole path [bytes] (Linux's PATH_MAX less the terminating NUL)."""

MAX_TEXT_BYTES = 256 * 1024 * 1024
"""Largest text input read whole (TOML/JSON/YAML, trajectories, curves, USD/MJCF text) [bytes]."""


def check_path_name(path: str | os.PathLike[str], label: str | None = None) -> None:
    """Refuse a path the file system cannot name: a component over 255 bytes, or over 4095 in all.

    Raises:
        InputError: naming the path (shortened) and the limit.
    """
    text = os.fspath(path)
    shown = label if label is not None else _shorten(text)
    encoded = os.fsencode(text)
    for part in encoded.split(b"/"):
        if len(part) > NAME_MAX:
            raise InputError(
                f"{shown}: a name in this path is {len(part)} bytes long; file systems allow at most "
                f"{NAME_MAX} bytes per name"
            )
    if len(encoded) > PATH_MAX:
        raise InputError(f"{shown}: the path is {len(encoded)} bytes long; expected at most {PATH_MAX} bytes")


def _shorten(text: str) -> str:
    """A path shown in a message: a very long one is cut in the middle (the line stays readable)."""
    return text if len(text) <= 120 else f"{text[:60]}...{text[-40:]}"


def node_kind(mode: int) -> str | None:
    """What a file that is not a regular file or a folder is (``'a FIFO'``...), or None."""
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def describe_size(size: int) -> str:
    """``size`` bytes in words: ``'300 MiB'``, ``'1.5 GiB'`` [bytes]."""
    for unit, scale in (("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if size >= scale:
            return f"{size / scale:.3g} {unit}"
    return f"{size} bytes"


def input_file(
    path: str | os.PathLike[str],
    label: str | None = None,
    *,
    max_bytes: int | None = MAX_TEXT_BYTES,
    what: str = "file",
) -> Path:
    """Check that ``path`` is a regular file that may be read, without opening it.

    Args:
        path: The input.
        label: How messages name it (default the path).
        max_bytes: Largest size read whole [bytes]; None for a reader that streams in chunks.
        what: The kind of file expected, for messages (``"file"``, ``"MJCF file"``).

    Raises:
        InputError: a name too long, no such file, a folder, a FIFO/device/socket, or a file larger
            than ``max_bytes``.
    """
    file = Path(path)
    shown = label if label is not None else _shorten(os.fspath(path))
    check_path_name(file, shown)
    try:
        mode = os.stat(file)  # follows symlinks: a link to /dev/zero is a character device
    except FileNotFoundError:
        raise InputError(f"{shown}: no such {what}") from None
    except NotADirectoryError:
        raise InputError(f"{shown}: no such {what} (a name in the path is a file, not a folder)") from None
    except OSError as exc:
        raise InputError(f"{shown}: cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(mode.st_mode):
        raise InputError(f"{shown}: is a folder; expected {_article(what)} {what}")
    kind = node_kind(mode.st_mode)
    if kind is not None:
        raise InputError(
            f"{shown}: is {kind}, not a regular file; expected {_article(what)} {what} (inputs are read from "
            "regular files only: save the stream to a file first)"
        )
    if max_bytes is not None and mode.st_size > max_bytes:
        raise InputError(
            f"{shown}: is {describe_size(mode.st_size)}; a text input is read whole and may be at "
            f"most {describe_size(max_bytes)}"
        )
    return file


def _article(word: str) -> str:
    """``a`` or ``an`` before ``word`` (``an MJCF file``, ``a USD file``)."""
    return "an" if word[:1].lower() in "aeiou" or word.startswith("MJCF") else "a"


def read_input_bytes(
    path: str | os.PathLike[str],
    label: str | None = None,
    *,
    max_bytes: int = MAX_TEXT_BYTES,
    what: str = "file",
) -> bytes:
    """The bytes of a regular file of at most ``max_bytes`` (see :func:`input_file`).

    The read itself is bounded too: a file that grows while it is read (or reports a size of 0, as
    ``/proc`` files do) is still refused past ``max_bytes``.

    Raises:
        InputError: as :func:`input_file`, or the file cannot be read.
    """
    file = input_file(path, label, max_bytes=max_bytes, what=what)
    shown = label if label is not None else _shorten(os.fspath(path))
    try:
        # O_NONBLOCK: should the file be swapped for a FIFO after the check, open() still returns
        fd = os.open(file, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as exc:
        raise InputError(f"{shown}: cannot read: {exc.strerror or exc}") from None
    if len(data) > max_bytes:
        raise InputError(
            f"{shown}: is larger than {describe_size(max_bytes)}, the most a text input is read whole"
        )
    return data

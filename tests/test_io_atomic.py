"""Atomic writes: symlinks written through, read-only targets refused, no temporary file left behind."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from drive_envelope import InputError
from drive_envelope._src.io.atomic import atomic_path, atomic_write_text


def test_symlink_is_written_through(tmp_path: Path) -> None:
    """Replace the file a link points to and keep the link (the real asset is edited)."""
    real = tmp_path / "assets" / "robot.toml"
    real.parent.mkdir()
    real.write_text("old", encoding="utf-8")
    link = tmp_path / "robot.toml"
    link.symlink_to(real)
    atomic_write_text(link, "new")
    assert link.is_symlink() and real.read_text(encoding="utf-8") == "new"
    assert sorted(p.name for p in real.parent.iterdir()) == ["robot.toml"]


def test_read_only_target_is_refused_unless_forced(tmp_path: Path) -> None:
    """Refuse a 0444 file with one line naming it; --force replaces it and keeps its mode."""
    target = tmp_path / "locked.toml"
    target.write_text("keep", encoding="utf-8")
    target.chmod(0o444)  # refused for every user, root too: the missing write bits decide
    with pytest.raises(InputError, match="read-only"):
        atomic_write_text(target, "lost")
    assert target.read_text(encoding="utf-8") == "keep"
    atomic_write_text(target, "forced", force=True)
    assert target.read_text(encoding="utf-8") == "forced"
    assert target.stat().st_mode & 0o777 == 0o444


def test_read_only_refusal_as_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Decide read-only-ness from os.access, so the rule holds whoever runs the command."""
    target = tmp_path / "locked.toml"
    target.write_text("keep", encoding="utf-8")
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    with pytest.raises(InputError, match=r"locked\.toml: cannot write: the file is read-only"):
        atomic_write_text(target, "lost")
    assert target.read_text(encoding="utf-8") == "keep"


@pytest.mark.parametrize("case", ["folder", "file as a folder"])
def test_bad_targets_are_one_line_errors(tmp_path: Path, case: str) -> None:
    """Name the file and the reason for a folder or a file where a folder should be; create nothing."""
    if case == "folder":
        target, needle = tmp_path, "it is a folder"
    else:
        (tmp_path / "plain").write_text("x", encoding="utf-8")
        target, needle = tmp_path / "plain" / "deeper" / "x.toml", "plain' is a file, not a folder"
    with pytest.raises(InputError, match=f"cannot write: .*{needle}"):
        atomic_write_text(target, "x")
    assert [p.name for p in tmp_path.iterdir()] == ([] if case == "folder" else ["plain"])


def test_failure_inside_the_block_leaves_no_temporary_file(tmp_path: Path) -> None:
    """Remove the temporary file when the writer fails, and leave the old file untouched."""
    target = tmp_path / "out.csv"
    target.write_text("old", encoding="utf-8")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("partial", encoding="utf-8")
        raise RuntimeError("writer failed")
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    assert target.read_text(encoding="utf-8") == "old"


def test_disk_full_is_a_one_line_error(tmp_path: Path) -> None:
    """Turn ENOSPC from the writer into 'no space left on the device' naming the file."""
    target = tmp_path / "out.csv"
    with pytest.raises(InputError, match=r"out\.csv: cannot write: no space left"), atomic_path(target):
        raise OSError(28, "No space left on device")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_signal_mid_write_leaves_no_temporary_file(tmp_path: Path, signum: int) -> None:
    """Clean up the temporary file when SIGTERM or SIGINT arrives in the middle of a write."""
    target = tmp_path / "big.usda"
    ready = tmp_path / "ready"
    code = (
        "import sys, time, pathlib, signal\n"
        # a shell without job control starts background jobs with SIGINT ignored, and Python then
        # rightly keeps ignoring it: give the writer the interactive default, where Ctrl-C reaches it
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "from drive_envelope._src.io.atomic import atomic_path\n"
        f"with atomic_path({str(target)!r}) as tmp:\n"
        "    tmp.write_text('x' * 1000)\n"
        f"    pathlib.Path({str(ready)!r}).write_text('1')\n"
        "    time.sleep(30)\n"
    )
    process = subprocess.Popen([sys.executable, "-c", code], stderr=subprocess.PIPE)
    deadline = time.monotonic() + 20
    while not ready.exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    assert ready.exists(), "the writer did not start"
    assert any(p.name.startswith(".big.usda.") for p in tmp_path.iterdir())
    process.send_signal(signum)
    process.wait(timeout=20)
    assert process.returncode != 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ready"]


def test_missing_folders_are_created_and_removed_again_on_failure(tmp_path: Path) -> None:
    """Create the folders above a new output; a failed write leaves none of them behind."""
    target = tmp_path / "a" / "b" / "out.toml"
    atomic_write_text(target, "x")
    assert target.read_text(encoding="utf-8") == "x"
    failed = tmp_path / "c" / "d" / "out.toml"
    with pytest.raises(RuntimeError), atomic_path(failed) as tmp:
        tmp.write_text("partial", encoding="utf-8")
        raise RuntimeError("writer failed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a"]


def _reader(fifo: Path, into: list[bytes]) -> threading.Thread:
    def read() -> None:
        with open(fifo, "rb") as handle:
            into.append(handle.read())

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    return thread


def test_fifo_is_written_through_and_stays_a_fifo(tmp_path: Path) -> None:
    """Give a FIFO's reader the whole file; the FIFO is still a FIFO afterwards, and no file is left."""
    fifo = tmp_path / "run.csv"
    os.mkfifo(fifo)
    got: list[bytes] = []
    thread = _reader(fifo, got)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:  # the reader's open() must be pending before ours
        try:
            atomic_write_text(fifo, "time,velocity\n0,1\n")
            break
        except InputError as exc:
            assert "nothing reads from it" in str(exc)
            time.sleep(0.02)
    thread.join(timeout=10)
    assert got == [b"time,velocity\n0,1\n"]
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]


def test_fifo_without_a_reader_is_refused_at_once(tmp_path: Path) -> None:
    """Refuse a FIFO nobody reads (never block), keep it a FIFO and leave no file."""
    fifo = tmp_path / "run.csv"
    os.mkfifo(fifo)
    start = time.monotonic()
    with pytest.raises(InputError, match=r"run\.csv: cannot write: it is a FIFO .* nothing reads from it"):
        atomic_write_text(fifo, "x")
    assert time.monotonic() - start < 5
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]


def _char_device(path: Path) -> None:
    """A character device like /dev/null (1, 3) at ``path``; only root may make one."""
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a device node needs root")


@pytest.mark.parametrize("through_link", [False, True])
def test_character_device_is_written_through_and_kept(tmp_path: Path, through_link: bool) -> None:
    """Write into a device node (or a link to one) without replacing it by a regular file."""
    device = tmp_path / "n.csv"
    _char_device(device)
    target = device
    if through_link:
        target = tmp_path / "link.csv"
        target.symlink_to(device)
    atomic_write_text(target, "x" * 3_000_000)  # /dev/null swallows it
    assert stat.S_ISCHR(os.stat(device).st_mode) and os.stat(device).st_rdev == os.makedev(1, 3)
    assert target.is_symlink() == through_link
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted({"n.csv", target.name})


def test_a_failed_write_leaves_a_device_untouched(tmp_path: Path) -> None:
    """Open the device only once the output is complete: a writer that fails writes nothing into it."""
    fifo = tmp_path / "run.csv"
    os.mkfifo(fifo)
    with pytest.raises(RuntimeError), atomic_path(fifo) as tmp:
        tmp.write_text("partial", encoding="utf-8")
        raise RuntimeError("writer failed")  # a reader would have blocked: the FIFO was never opened
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_dev_stdout_is_written_through(tmp_path: Path) -> None:
    """``-o /dev/stdout`` writes into the pipe the process's standard output is (the idiom works)."""
    code = (
        "from drive_envelope._src.io.atomic import atomic_write_text\n"
        "atomic_write_text('/dev/stdout', 'through the pipe\\n')\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "through the pipe\n"
    assert list(tmp_path.iterdir()) == []


def test_socket_and_long_names_are_refused(tmp_path: Path) -> None:
    """Refuse a socket as an output, and a name over 255 bytes, in one line each."""
    import socket

    path = tmp_path / "s.csv"
    with socket.socket(socket.AF_UNIX) as server:
        server.bind(str(path))
        with pytest.raises(InputError, match=r"s\.csv: cannot write: it is a socket"):
            atomic_write_text(path, "x")
    with pytest.raises(InputError, match=r"a name in this path is 300 bytes long; .* at most 255"):
        atomic_write_text(tmp_path / ("a" * 296 + ".csv"), "x")
    assert [p.name for p in tmp_path.iterdir()] == ["s.csv"]


def test_dev_stdout_redirected_to_a_file_keeps_the_shell_redirection(tmp_path: Path) -> None:
    """``-o /dev/stdout >> log`` appends through the descriptor; the file is neither replaced nor cut."""
    log = tmp_path / "log.csv"
    log.write_text("kept\n", encoding="utf-8")
    inode = log.stat().st_ino
    code = (
        "from drive_envelope._src.io.atomic import atomic_write_text\n"
        "atomic_write_text('/dev/stdout', 'new\\n')\n"
    )
    with open(log, "a", encoding="utf-8") as handle:
        result = subprocess.run(
            [sys.executable, "-c", code], stdout=handle, stderr=subprocess.PIPE, text=True
        )
    assert result.returncode == 0, result.stderr
    assert log.read_text(encoding="utf-8") == "kept\nnew\n" and log.stat().st_ino == inode
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.csv"]

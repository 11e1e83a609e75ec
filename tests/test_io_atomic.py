"""Atomic writes: symlinks written through, read-only targets refused, no temporary file left behind."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
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


@pytest.mark.parametrize("case", ["folder", "missing folder"])
def test_bad_targets_are_one_line_errors(tmp_path: Path, case: str) -> None:
    """Name the file and the reason for a folder or a missing folder; create nothing."""
    target = tmp_path if case == "folder" else tmp_path / "nope" / "x.toml"
    with pytest.raises(InputError, match="cannot write"):
        atomic_write_text(target, "x")
    assert list(tmp_path.iterdir()) == []


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

"""A fresh copy of the checkout's tracked files, as a clone has them (the docs and packaging tests)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"


def tracked_files() -> list[str]:
    """The repository's tracked files (working-tree contents), relative to the root; skip outside git."""
    try:
        out = subprocess.run(
            ["git", "ls-files", "-z", "--cached"], cwd=ROOT, capture_output=True, check=True, timeout=60
        ).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        pytest.skip(f"not a git checkout ({exc}): the tracked files are unknown")
    # a tracked file deleted in the working tree is not part of what a commit of it would hold
    return [name for name in out.decode().split("\0") if name and (ROOT / name).is_file()]


def copy_checkout(dest: Path) -> Path:
    """Copy the tracked files into ``dest`` (created) and return it; untracked and ignored files stay out."""
    for name in tracked_files():
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / name, target)
    return dest

"""The glossary generator writes only where it is told (issue 24): an explicit OUT, or stdout."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from drive_envelope._src.params.glossary import GLOSSARY_PATH, render_glossary


def _run(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "drive_envelope._src.params.glossary", *args]
    return subprocess.run(command, capture_output=True, text=True, cwd=cwd)


def test_writes_only_the_file_it_is_told(tmp_path: Path) -> None:
    """OUT gets the glossary; without OUT: usage and exit 2, and docs/ of the checkout is not touched."""
    before = GLOSSARY_PATH.stat().st_mtime_ns
    result = _run(cwd=tmp_path)
    assert result.returncode == 2 and "usage:" in result.stderr and result.stdout == ""
    result = _run(str(tmp_path / "g.md"), cwd=tmp_path)
    assert result.returncode == 0 and result.stderr == f"wrote {tmp_path / 'g.md'}\n"
    assert (tmp_path / "g.md").read_text(encoding="utf-8") == render_glossary()
    assert GLOSSARY_PATH.stat().st_mtime_ns == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.md"]


def test_dash_is_stdout_and_a_bad_path_is_one_line(tmp_path: Path) -> None:
    """``-`` prints the glossary; a folder that is a file is one error line, exit 2."""
    result = _run("-", cwd=tmp_path)
    assert result.returncode == 0 and result.stdout == render_glossary()
    (tmp_path / "plain").write_text("x", encoding="utf-8")
    result = _run(str(tmp_path / "plain" / "g.md"), cwd=tmp_path)
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and "cannot write" in result.stderr

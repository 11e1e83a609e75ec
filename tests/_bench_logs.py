"""Helpers for tests that run the CLI on bench logs written as a new user types them."""

from __future__ import annotations

from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main


def write_log(path: Path, text: str) -> Path:
    """Write a bench log as a new user types it."""
    path.write_text(text, encoding="utf-8")
    return path


def run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Run the CLI: exit status, stdout, stderr."""
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out, captured.err

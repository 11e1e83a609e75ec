"""TOML's duplicate-key errors with the key named, as JSON's and YAML's are.

JSON and YAML duplicates are named by the reader (``duplicate key 'max_effort' (line 4)``), but
TOML's own parser refuses them first, with a position and no name: ``Cannot overwrite a value (at
line 4, column 20)``. The key is on the line that error points at, so it is read from there.
"""

from __future__ import annotations

import re
from pathlib import Path

_OVERWRITE = re.compile(r"^Cannot overwrite a value \(at line (\d+), column \d+\)$")
_TABLE_TWICE = re.compile(r"^Cannot declare \((.*)\) twice \(at line (\d+), column \d+\)$")
_KEY = r"""(?:[A-Za-z0-9_-]+|"[^"\n]*"|'[^'\n]*')"""
_ASSIGNMENT = re.compile(rf"^\s*({_KEY}(?:\s*\.\s*{_KEY})*)\s*=")
_HEADER = re.compile(rf"^\s*\[\[?\s*({_KEY}(?:\s*\.\s*{_KEY})*)\s*\]")


def named_duplicate(file: Path, text: str, error: str) -> str | None:
    """The duplicate-key message for TOML's unnamed ``error`` on ``text``, or None (another error)."""
    table = _TABLE_TWICE.search(error)
    if table is not None:
        names = ".".join(part.strip().strip("'\"") for part in table.group(1).split(",") if part.strip())
        return (
            f"{file}: duplicate table [{names}] (line {table.group(2)}): each table may be written once; "
            f"put all its keys under one [{names}]"
        )
    overwrite = _OVERWRITE.search(error)
    if overwrite is None:
        return None
    number = int(overwrite.group(1))
    lines = text.splitlines()
    if not 0 < number <= len(lines):
        return None
    assignment = _ASSIGNMENT.match(lines[number - 1])
    if assignment is None:
        return None
    key = _dotted(assignment.group(1))
    for line in reversed(lines[: number - 1]):  # the table the key is in: the last header above it
        header = _HEADER.match(line)
        if header is not None:
            key = f"{_dotted(header.group(1))}.{key}"
            break
    return f"{file}: duplicate key {key!r} (line {number}): each key may be written once"


def _dotted(text: str) -> str:
    """``motor . "max_torque"`` -> ``motor.max_torque``."""
    parts = re.findall(_KEY, text)
    return ".".join(part.strip("'\"") for part in parts)

"""Plain-text numbers and tables, shared by reports and the command line (no dependencies)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TypeVar

_T = TypeVar("_T")


def format_value(value: float | None, unit: str = "") -> str:
    """Readable number with unit; ``-`` for a missing value."""
    if value is None:
        return "-"
    if math.isinf(value):
        text = "inf" if value > 0 else "-inf"
    else:
        text = f"{value:.6g}"
    return f"{text} {unit}".rstrip()


def format_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Left-aligned plain-text table."""
    widths = [max(len(str(cell)) for cell in column) for column in zip(header, *rows, strict=True)]
    lines = [
        "  ".join(str(cell).ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip()
        for row in [header, *rows]
    ]
    lines.insert(1, "  ".join("-" * width for width in widths))
    return "\n".join(lines)


def first_few(items: Sequence[_T], count: int, show: Callable[[_T], str] = repr) -> str:
    """The first ``count`` of ``items`` (each written by ``show``, quoted by default) and N more."""
    shown = ", ".join(show(item) for item in items[:count])
    return shown + (f" and {len(items) - count} more" if len(items) > count else "")

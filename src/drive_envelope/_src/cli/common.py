"""Helpers shared by the CLI subcommands."""

from __future__ import annotations

import math
from collections.abc import Sequence

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.params.table import si_unit

__all__ = ["envelope_table", "format_table", "format_value"]


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


def envelope_table(envelope: PerformanceEnvelope) -> str:
    """The envelope's parameters and first-quadrant corner points as text."""
    rows = [
        [field, format_value(getattr(envelope, field)), si_unit(field, envelope.joint)]
        for field in ENVELOPE_FIELDS
    ]
    parts = []
    title = f"{envelope.name} ({envelope.joint})" if envelope.name else f"envelope ({envelope.joint})"
    parts.append(title)
    parts.append(format_table(["parameter", "value", "unit"], rows))
    v_unit, e_unit = si_unit("max_actuator_velocity", envelope.joint), si_unit("max_effort", envelope.joint)
    extent = None
    if math.isinf(envelope.no_load_velocity()):
        extent = 1.0
    corners = envelope.corners(velocity_extent=extent)
    corner_rows = [["stall", *map(format_value, corners.stall)]]
    if corners.corner is not None:
        corner_rows.append(["corner (both curves bind)", *map(format_value, corners.corner)])
    no_load = (envelope.no_load_velocity(), 0.0)
    corner_rows.append(["no-load", *map(format_value, no_load)])
    parts.append("")
    parts.append("corner points (first quadrant; the region is symmetric in velocity and effort)")
    parts.append(format_table(["point", f"velocity [{v_unit}]", f"effort [{e_unit}]"], corner_rows))
    return "\n".join(parts)

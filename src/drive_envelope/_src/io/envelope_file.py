"""Envelope files: TOML or JSON with ``name``, ``joint`` and the four envelope parameters."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Literal

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.format import format_table, format_value
from drive_envelope._src.io.atomic import atomic_write_text
from drive_envelope._src.io.files import format_toml_value, read_mapping
from drive_envelope._src.params.table import si_unit


def load_envelope(path: str | os.PathLike[str]) -> PerformanceEnvelope:
    """Read an envelope file (TOML, JSON or YAML; SI numbers or strings with units).

    Raises:
        InputError: a one-line message naming the file, the key and what was expected.
    """
    file = Path(path)
    if not file.suffix and not file.exists():
        raise InputError(
            f"{str(path)!r}: no such envelope file; a catalog name or datasheet is read by "
            "drive_envelope.datasheet.resolve_envelope (the command line takes either)"
        )
    return PerformanceEnvelope.from_dict(read_mapping(path), source=str(path))


def envelope_to_toml(envelope: PerformanceEnvelope) -> str:
    """TOML text of an envelope file, SI values, units in comments."""
    lines = []
    if envelope.name:
        lines.append(f"name = {format_toml_value(envelope.name)}")
    lines.append(f"joint = {format_toml_value(envelope.joint)}")
    for field in ENVELOPE_FIELDS:
        value = getattr(envelope, field)
        lines.append(f"{field} = {format_toml_value(value)}  # {si_unit(field, envelope.joint)}")
    return "\n".join(lines) + "\n"


def envelope_data(envelope: PerformanceEnvelope) -> dict[str, object]:
    """The envelope as a JSON-ready dict; an infinite ``max_actuator_velocity`` is ``"inf"``."""
    return {
        k: ("inf" if isinstance(v, float) and math.isinf(v) else v) for k, v in envelope.to_dict().items()
    }


def envelope_to_json(envelope: PerformanceEnvelope) -> str:
    """JSON text of an envelope file (:func:`envelope_data`)."""
    return json.dumps(envelope_data(envelope), indent=2) + "\n"


def save_envelope(
    envelope: PerformanceEnvelope,
    path: str | os.PathLike[str],
    *,
    format: Literal["toml", "json"] | None = None,
    force: bool = False,
) -> None:
    """Write an envelope file atomically; the format follows the suffix unless ``format`` is given.

    Args:
        envelope: The envelope.
        path: Output file (``.json`` for JSON, anything else TOML).
        format: ``"toml"`` or ``"json"``; None: from the suffix.
        force: Replace ``path`` even when it is read-only.

    Raises:
        InputError: a suffix other than ``.toml`` or ``.json`` without ``format``, or the file cannot
            be written (missing folder, a folder, read-only, a full disk).
    """
    suffix = Path(path).suffix.lower()
    if format is None and suffix not in (".toml", ".json"):
        raise InputError(f"{str(path)!r}: expected an envelope file name ending in .toml or .json")
    chosen = format or ("json" if suffix == ".json" else "toml")
    text = envelope_to_json(envelope) if chosen == "json" else envelope_to_toml(envelope)
    atomic_write_text(path, text, force=force)


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
    unbounded = math.isinf(envelope.no_load_velocity())
    stall = envelope.stall_effort()
    corner_rows = [["stall", format_value(0.0), format_value(stall)]]
    if math.isfinite(stall):  # max_effort = inf without a speed line: no polygon to clip (it showed 0)
        corners = envelope.corners(velocity_extent=1.0 if unbounded else None)
        if corners.corner is not None and not unbounded:  # unbounded: the "corner" is the cut at 1
            corner_rows.append(["corner (both curves bind)", *map(format_value, corners.corner)])
    no_load = (envelope.no_load_velocity(), 0.0)
    corner_rows.append(["no-load", *map(format_value, no_load)])
    parts.append("")
    parts.append("corner points (first quadrant; the region is symmetric in velocity and effort)")
    parts.append(format_table(["point", f"velocity [{v_unit}]", f"effort [{e_unit}]"], corner_rows))
    return "\n".join(parts)

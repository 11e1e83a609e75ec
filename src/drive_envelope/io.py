"""Envelope file text (TOML/JSON) and atomic output.

Reading and writing envelope files is ``drive_envelope.load_envelope`` and
``drive_envelope.save_envelope`` (one import path each); a catalog name or datasheet is read by
``drive_envelope.datasheet.resolve_envelope``.
"""

from __future__ import annotations

from drive_envelope._src.io.atomic import atomic_path, atomic_write_bytes, atomic_write_text
from drive_envelope._src.io.envelope_file import envelope_to_json, envelope_to_toml

__all__ = [
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "envelope_to_json",
    "envelope_to_toml",
]

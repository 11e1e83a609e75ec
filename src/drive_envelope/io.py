"""Envelope files (TOML/JSON) and atomic output."""

from __future__ import annotations

from drive_envelope._src.io.atomic import atomic_path, atomic_write_bytes, atomic_write_text
from drive_envelope._src.io.envelope_file import (
    envelope_to_json,
    envelope_to_toml,
    load_envelope,
    save_envelope,
)

__all__ = [
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "envelope_to_json",
    "envelope_to_toml",
    "load_envelope",
    "save_envelope",
]

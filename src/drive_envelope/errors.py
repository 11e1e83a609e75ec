"""Exceptions raised by drive_envelope.

Every user mistake (a bad file, key, unit or argument) raises :class:`InputError` with a one-line
message that names the file or argument, the key, the offending value and what was expected. The
CLI prints that line and exits with status 2; it never shows a traceback for an :class:`InputError`.
"""

from __future__ import annotations

from drive_envelope._src.errors import DriveEnvelopeError, InputError, UnitsError

__all__ = ["DriveEnvelopeError", "InputError", "UnitsError"]

"""Exceptions raised by drive_envelope.

Every user mistake (a bad file, key, unit or argument) raises :class:`InputError` with a one-line
message that names the file or argument, the key, the offending value and what was expected. The
CLI prints that line and exits with status 2; it never shows a traceback for an :class:`InputError`.
"""

from __future__ import annotations

__all__ = ["DriveEnvelopeError", "InputError", "UnitsError"]


class DriveEnvelopeError(Exception):
    """Base class of every error drive_envelope raises on purpose."""


class InputError(DriveEnvelopeError, ValueError):
    """Bad user input: a file, key, value, unit or argument that cannot be used as given."""


class UnitsError(InputError):
    """A quantity with an unknown unit or a unit of the wrong dimension."""

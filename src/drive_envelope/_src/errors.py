"""Exceptions of drive_envelope (public: :mod:`drive_envelope.errors`)."""

from __future__ import annotations


class DriveEnvelopeError(Exception):
    """Base class of every error drive_envelope raises on purpose."""


class InputError(DriveEnvelopeError, ValueError):
    """Bad user input: a file, key, value, unit or argument that cannot be used as given."""


class UnitsError(InputError):
    """A quantity with an unknown unit or a unit of the wrong dimension."""


class EngineWarning(UserWarning):
    """An engine ran, but where it is known to part from PhysX (the CLI prints it as a warning line)."""

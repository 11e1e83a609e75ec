"""drive-envelope: the PhysX articulation drive performance envelope, from datasheet to simulation.

The core (this package) is NumPy + pint only. Engines live in their own modules, each importing its
engine lazily: ``drive_envelope.datasheet``, ``drive_envelope.teststand``, ``drive_envelope.plots``,
``drive_envelope.mujoco``, ``drive_envelope.usd``, ``drive_envelope.warp``, ``drive_envelope.torch``,
``drive_envelope.newton``, ``drive_envelope.analysis``.

Conventions: SI floats everywhere, joint side; revolute joints in N*m and rad/s, prismatic joints
in N and m/s. Effort is the TOTAL actuator effort on the DOF (drive plus any commanded joint force).
"""

from __future__ import annotations

from drive_envelope._src.envelope.clamp import clamp_drive_impulse, clamp_effort, clamp_effort_implicit
from drive_envelope._src.envelope.drive import implicit_drive_effort
from drive_envelope._src.envelope.model import PerformanceEnvelope, QuadrantCorners
from drive_envelope._src.io.envelope_file import load_envelope, save_envelope
from drive_envelope.errors import DriveEnvelopeError, InputError, UnitsError

__version__ = "0.1.0"

__all__ = [
    "DriveEnvelopeError",
    "InputError",
    "PerformanceEnvelope",
    "QuadrantCorners",
    "UnitsError",
    "__version__",
    "clamp_drive_impulse",
    "clamp_effort",
    "clamp_effort_implicit",
    "implicit_drive_effort",
    "load_envelope",
    "save_envelope",
]

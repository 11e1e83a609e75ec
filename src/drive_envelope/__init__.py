"""drive-envelope: the PhysX articulation drive performance envelope, from datasheet to simulation.

The core (this package) is NumPy + pint only. Engines live in their own modules, each importing its
engine lazily: ``drive_envelope.datasheet``, ``drive_envelope.teststand``, ``drive_envelope.plots``,
``drive_envelope.mujoco``, ``drive_envelope.usd``, ``drive_envelope.warp``, ``drive_envelope.torch``,
``drive_envelope.newton``, ``drive_envelope.isaaclab``, ``drive_envelope.analysis``.

Conventions: SI floats everywhere, joint side; revolute joints in N*m and rad/s, prismatic joints
in N and m/s. Effort is the TOTAL actuator effort on the DOF (drive plus any commanded joint force).

The names below are loaded on first access, so ``import drive_envelope`` (and the command line's
``--help``) costs neither NumPy nor pint until a name is used.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from drive_envelope._src.errors import DriveEnvelopeError, InputError, UnitsError
from drive_envelope._src.version import VERSION as __version__

if TYPE_CHECKING:
    from drive_envelope._src.envelope.clamp import clamp_drive_impulse, clamp_effort, clamp_effort_implicit
    from drive_envelope._src.envelope.drive import implicit_drive_effort
    from drive_envelope._src.envelope.model import PerformanceEnvelope, QuadrantCorners
    from drive_envelope._src.io.envelope_file import load_envelope, save_envelope

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

_LAZY = {
    "PerformanceEnvelope": "drive_envelope._src.envelope.model",
    "QuadrantCorners": "drive_envelope._src.envelope.model",
    "clamp_drive_impulse": "drive_envelope._src.envelope.clamp",
    "clamp_effort": "drive_envelope._src.envelope.clamp",
    "clamp_effort_implicit": "drive_envelope._src.envelope.clamp",
    "implicit_drive_effort": "drive_envelope._src.envelope.drive",
    "load_envelope": "drive_envelope._src.io.envelope_file",
    "save_envelope": "drive_envelope._src.io.envelope_file",
}


def __getattr__(name: str) -> Any:
    """Load a public name from its implementation module on first access."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later accesses skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(__all__)

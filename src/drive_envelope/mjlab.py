"""mjlab (Isaac Lab's API on MuJoCo Warp): actuators whose effort the PhysX envelope limits.

:class:`PerformanceEnvelopeActuatorCfg` is an mjlab actuator config (a subclass of mjlab's
``IdealPdActuatorCfg``) with the envelope's four parameters, or an ``envelope`` from a file or the
catalog. By default it builds :class:`PerformanceEnvelopeActuator`: the PD torque clipped by the
envelope at the current velocity, in torch, fused by mjlab with every actuator of its kind. With
``implicit=True`` it builds :class:`PerformanceEnvelopeImplicitActuator`: MJWarp's step solves
PhysX's implicit drive and the envelope at the end-of-step velocity, all drives together (see
``drive_envelope.mjwarp``). Needs ``pip install mjlab`` (it pins MuJoCo 3.11; this module loads
neither mjlab nor torch until a class is used).

SI units: efforts [N*m or N], velocities [rad/s or m/s].
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "PerformanceEnvelopeActuator",
    "PerformanceEnvelopeActuatorCfg",
    "PerformanceEnvelopeImplicitActuator",
]

# Loaded by __getattr__ on first access (annotation only: this module stays free of mjlab until then)
PerformanceEnvelopeActuator: Any
PerformanceEnvelopeActuatorCfg: Any
PerformanceEnvelopeImplicitActuator: Any


def __getattr__(name: str) -> Any:
    """Load the mjlab actuators on first access (this imports mjlab and torch)."""
    if name in __all__:
        try:
            from drive_envelope._src.adapters.mjlab import actuator
        except ModuleNotFoundError as exc:
            raise ImportError(f"{name} needs mjlab: pip install mjlab ({exc})") from exc
        return getattr(actuator, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

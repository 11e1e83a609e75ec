"""The envelope in Newton (extra ``newton``): a clamping stage, USD import glue and the gravity bias.

``ClampingPerformanceEnvelope`` follows Newton's public clamping interface
(``newton.actuators.ClampingBase``): ``modify_forces`` clamps at the measured velocity (explicit
mode), ``evaluate_clamp`` clamps at the predicted end-of-step velocity inside Newton's implicit
effort mode (PhysX's semantics). Use it with ``DrivePD`` so a Newton model gets the PhysX envelope::

    import newton
    from newton.actuators import DrivePD
    from drive_envelope.newton import ClampingPerformanceEnvelope

    builder.add_actuator(DrivePD, index=dof, kp=0.0, kd=5.0, clamping=[(ClampingPerformanceEnvelope, {
        "max_effort": 12.0, "max_actuator_velocity": "300 rpm", "speed_effort_gradient": 0.5})])

A robot whose USD carries ``PhysxDrivePerformanceEnvelopeAPI`` (``drive-envelope usd apply``)::

    builder.add_usd("robot_envelope.usda")
    added = add_envelopes_from_usd(builder, "robot_envelope.usda")   # PD + envelope per drive
    model = builder.finalize()

In implicit mode pass the gravity and Coriolis bias so the clamp predicts the velocity the step
reaches: ``bias = BiasForce(model)``, then ``actuator.step(state, control, dt=dt,
bias_force=bias.compute(state))``.

Importing this module does not import Newton; the first access to ``ClampingPerformanceEnvelope``
and the first call of the others do. Arguments are SI numbers or strings with units; see
``docs/newton.md``.
"""

from __future__ import annotations

from typing import Any

from drive_envelope._src.adapters.newton.bias import BiasForce
from drive_envelope._src.adapters.newton.clamp import resolve_envelope_arguments
from drive_envelope._src.adapters.newton.usd import (
    EnvelopeImportWarning,
    UsdEnvelopeActuator,
    add_envelopes_from_usd,
)

__all__ = [
    "BiasForce",
    "ClampingPerformanceEnvelope",
    "EnvelopeImportWarning",
    "UsdEnvelopeActuator",
    "add_envelopes_from_usd",
    "resolve_envelope_arguments",
]

# Created by __getattr__ on first access (annotation only: the module stays free of Newton until then)
ClampingPerformanceEnvelope: Any


def __getattr__(name: str) -> Any:
    """Define ``ClampingPerformanceEnvelope`` on first access (this imports Newton and Warp)."""
    if name == "ClampingPerformanceEnvelope":
        try:
            from drive_envelope._src.adapters.newton.clamp_stage import ClampingPerformanceEnvelope
        except ModuleNotFoundError as exc:
            raise ImportError(f"{name} needs Newton: pip install 'drive-envelope[newton]'") from exc
        return ClampingPerformanceEnvelope
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

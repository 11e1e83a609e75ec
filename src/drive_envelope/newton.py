"""The envelope in Newton (extra ``newton``): a clamping stage for ``newton.actuators``.

``ClampingPerformanceEnvelope`` follows Newton's public clamping interface
(``newton.actuators.ClampingBase``): ``modify_forces`` clamps at the measured velocity (explicit
mode), ``evaluate_clamp`` clamps at the predicted end-of-step velocity inside Newton's implicit
effort mode (PhysX's semantics). Use it with ``DrivePD`` so a Newton model gets the PhysX envelope::

    import newton
    from newton.actuators import DrivePD
    from drive_envelope.newton import ClampingPerformanceEnvelope

    builder.add_actuator(DrivePD, index=dof, kp=0.0, kd=5.0, clamping=[(ClampingPerformanceEnvelope, {
        "max_effort": 12.0, "max_actuator_velocity": "300 rpm", "speed_effort_gradient": 0.5})])

Importing this module does not import Newton; the first access to ``ClampingPerformanceEnvelope``
does. Arguments are SI numbers or strings with units; see ``docs/kernels.md`` for where the envelope
differs from Newton's ``ClampingDCMotor``.
"""

from __future__ import annotations

from typing import Any

from drive_envelope._src.adapters.newton.clamp import resolve_envelope_arguments

__all__ = ["ClampingPerformanceEnvelope", "resolve_envelope_arguments"]

# Created by __getattr__ on first access (annotation only: the module stays free of Newton until then)
ClampingPerformanceEnvelope: Any


def __getattr__(name: str) -> Any:
    """Define ``ClampingPerformanceEnvelope`` on first access (this imports Newton and Warp)."""
    if name == "ClampingPerformanceEnvelope":
        from drive_envelope._src.adapters.newton.clamp import build

        try:
            return build()
        except ModuleNotFoundError as exc:
            raise ImportError(f"{name} needs Newton: pip install 'drive-envelope[newton]'") from exc
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

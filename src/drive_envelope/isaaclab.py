"""The envelope in Isaac Lab (extra ``isaaclab``): an explicit actuator, event term and the implicit path.

Explicit: ``PerformanceEnvelopeActuatorCfg`` is an Isaac Lab ``IdealPDActuatorCfg`` whose actuator,
``PerformanceEnvelopeActuator``, clips the PD effort by the PhysX envelope at the current joint
velocity; put it in ``ArticulationCfg.actuators`` like any Isaac Lab actuator::

    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg

    actuators = {"legs": PerformanceEnvelopeActuatorCfg(
        joint_names_expr=[".*_HAA", ".*_HFE", ".*_KFE"], stiffness=80.0, damping=2.0,
        datasheet="myactuator-rmd-x8-120", speed_effort_gradient={".*_KFE": 0.05})}

Implicit (PhysX applies the envelope in its solver): author it in the robot's USD and use the
matching ``ImplicitActuatorCfg`` (:func:`author_implicit_envelopes`), or write it at run time in the
PhysX tensor API's order (:func:`drive_model_properties`). See ``docs/isaaclab.md``.

Newton actuators (Isaac Lab 3.0, ``use_newton_actuators=True``): ``PerformanceEnvelopeArticulationCfg``
(``envelope_clamping={"group": envelope}`` beside Isaac Lab's own ``IdealPDActuatorCfg`` groups) puts
the envelope on the ``NewtonActuator`` prims Isaac Lab authors, as the USD schema
``DriveEnvelopeClampingAPI`` that Newton builds into a ``ClampingPerformanceEnvelope`` stage
(:func:`register_envelope_clamping` before the first stage, :func:`author_envelope_clamping`).

Importing this module does not import Isaac Lab, torch or warp; the first access to the two
classes imports ``isaaclab.actuators``.
"""

from __future__ import annotations

from typing import Any

from drive_envelope._src.adapters.isaaclab.events import (
    randomize_actuator_envelope,
    set_response_from_mass_matrix,
)
from drive_envelope._src.adapters.isaaclab.implicit import (
    ImplicitEnvelopeSetup,
    author_implicit_envelopes,
    check_implicit_actuator,
)
from drive_envelope._src.adapters.isaaclab.newton_route import (
    ENVELOPE_CLAMPING_SCHEMA,
    author_envelope_clamping,
    register_envelope_clamping,
)
from drive_envelope._src.adapters.isaaclab.tensor_api import (
    DRIVE_MODEL_ORDER,
    drive_model_properties,
    envelope_from_drive_model_properties,
    write_envelope_to_sim,
)

__all__ = [
    "DRIVE_MODEL_ORDER",
    "ENVELOPE_CLAMPING_SCHEMA",
    "ImplicitEnvelopeSetup",
    "PerformanceEnvelopeActuator",
    "PerformanceEnvelopeActuatorCfg",
    "PerformanceEnvelopeArticulationCfg",
    "author_envelope_clamping",
    "author_implicit_envelopes",
    "check_implicit_actuator",
    "drive_model_properties",
    "envelope_from_drive_model_properties",
    "randomize_actuator_envelope",
    "register_envelope_clamping",
    "set_response_from_mass_matrix",
    "write_envelope_to_sim",
]

# Loaded by __getattr__ on first access (annotations only: the module stays free of Isaac Lab until then)
PerformanceEnvelopeActuator: Any
PerformanceEnvelopeActuatorCfg: Any
PerformanceEnvelopeArticulationCfg: Any


def __getattr__(name: str) -> Any:
    """Load the actuator and its cfg on first access (this imports ``isaaclab.actuators`` and torch)."""
    if name == "PerformanceEnvelopeArticulationCfg":
        from drive_envelope._src.adapters.isaaclab.newton_route import build_articulation_cfg

        try:
            return build_articulation_cfg()
        except ImportError as exc:
            raise ImportError(f"{name} needs Isaac Lab 3.x (isaaclab.assets, newton, pxr): {exc}") from exc
    if name in ("PerformanceEnvelopeActuator", "PerformanceEnvelopeActuatorCfg"):
        try:
            from drive_envelope._src.adapters.isaaclab import actuator_classes
        except ImportError as exc:
            raise ImportError(
                f"{name} needs Isaac Lab's isaaclab.actuators (run inside Isaac Lab / Isaac Sim; "
                f"see docs/isaaclab.md): {exc}"
            ) from exc
        return getattr(actuator_classes, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

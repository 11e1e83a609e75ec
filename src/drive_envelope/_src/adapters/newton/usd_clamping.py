"""``ClampingPerformanceEnvelope`` as the component of a USD API schema in Newton's actuator parser.

``newton.actuators.register_actuator_component(schema, class, ComponentKind.CLAMPING)`` (newton
1.6.1, Isaac Lab 3.0's pin, and 1.8) makes ``parse_actuator_prim`` build the class for each
``NewtonActuator`` prim that has the schema applied, in ``ModelBuilder.add_usd`` and in Isaac Lab's
``NewtonActuatorAdapter.from_usd`` alike. The parser hands the class the prim's attributes as
snake_case keys (``newton:envelopeMaxEffort`` -> ``envelope_max_effort``); the subclass maps them
back to the spec names before the usual validation.
"""

from __future__ import annotations

import functools
from typing import Any

from drive_envelope._src.adapters.newton.clamp import resolve_envelope_arguments
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS

_PARSED_KEYS = {"envelope_" + field: field for field in ENVELOPE_FIELDS}


@functools.cache
def register_clamping_component(schema_name: str) -> type:
    """Register the envelope's clamping class for ``schema_name`` with Newton (once per name).

    Returns:
        The registered class: a ``ClampingPerformanceEnvelope`` that also takes the parsed keys.
    """
    from newton.actuators import ComponentKind, register_actuator_component

    from drive_envelope._src.adapters.newton.clamp_stage import ClampingPerformanceEnvelope as base

    class ClampingPerformanceEnvelope(base):  # type: ignore[misc,valid-type]
        """``ClampingPerformanceEnvelope`` as built from a USD API schema's attributes."""

        @classmethod
        def resolve_arguments(cls, args: dict[str, Any]) -> dict[str, Any]:
            """Map the parsed USD keys (``envelope_max_effort`` ...) to the spec names and validate."""
            return resolve_envelope_arguments({_PARSED_KEYS.get(k, k): v for k, v in args.items()})

    ClampingPerformanceEnvelope.__module__ = "drive_envelope.newton"
    ClampingPerformanceEnvelope.__qualname__ = "ClampingPerformanceEnvelope"
    register_actuator_component(schema_name, ClampingPerformanceEnvelope, ComponentKind.CLAMPING)
    return ClampingPerformanceEnvelope

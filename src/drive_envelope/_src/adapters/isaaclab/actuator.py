"""``PerformanceEnvelopeActuator``: Isaac Lab's ideal PD actuator clipped by the PhysX envelope.

Isaac Lab's explicit actuators compute ``effort = stiffness*(q_target - q) + damping*(v_target - v)
+ effort_target`` for every environment and joint and clip it (``IdealPDActuator``: to
``+-effort_limit``; ``DCMotor``: to a torque-speed line). :class:`PerformanceEnvelopeActuator` is an
``IdealPDActuator`` whose clip is the envelope's effort limit at the current joint velocity,
with ``effort_limit`` (Isaac Lab's own field) as max_effort. The clip follows the cfg's ``clip``
(``kernels/torch_clip.py``): ``"end_of_step"`` (default) is PhysX's implicit clamp at the velocity
the step will end with, which needs each joint's unit response (the cfg's ``effective_inertia``, or
:func:`set_response_from_mass_matrix` from the articulation's mass matrix) and the physics ``dt``;
``"start_of_step"`` is the limit ``L(v) = max(min(effort_limit - R|v|, (v_max - |v|)/G), 0)`` at the
velocity the step starts from, which runs away after a step that ends beyond the speed line
(``docs/isaaclab.md``; the implicit path is there too).

The four envelope parameters are ``(num_envs, num_joints)`` tensors on the actuator
(``effort_limit``, ``max_actuator_velocity``, ``velocity_dependent_resistance``,
``speed_effort_gradient``), read at every :meth:`compute`, so an event term can write them per
environment the way Isaac Lab's ``randomize_actuator_gains`` writes ``actuator.stiffness[env_ids]``;
``default_*`` keep the configured values. This module reads the cfg's values (it imports neither
Isaac Lab nor torch); the classes subclass Isaac Lab's, so they live in
:mod:`~drive_envelope._src.adapters.isaaclab.actuator_classes`, which imports both at its top and is
loaded on first use.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any

from drive_envelope._src.adapters.isaaclab import compat
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import read_envelope_value

CFG_NAME = "PerformanceEnvelopeActuatorCfg"
"""The cfg's class name, which every error about a cfg value starts with."""

ENVELOPE_ATTRIBUTES = ("effort_limit", *ENVELOPE_FIELDS[1:])
"""The actuator's envelope tensors in Isaac Lab 2.3, in the order of the envelope fields."""


def envelope_attributes() -> tuple[str, ...]:
    """The actuator's envelope tensors, in the order of the envelope fields.

    max_effort is Isaac Lab's effort limit (2.3 ``effort_limit``, 3.0 ``actuator_effort_limit``).
    """
    return (compat.api().effort_limit, *ENVELOPE_FIELDS[1:])


def limits_in_si(cfg: Any, names: Any) -> None:
    """Read the cfg's effort and speed limits given as strings with units as SI numbers, in place.

    Isaac Lab's own parser takes numbers and ``{regex: number}`` dicts only; the envelope fields take
    ``"23.5 N*m"``, so the limits beside them do too (and a wrong unit is a one-line InputError).
    """
    groups = (
        ("max_effort", (names.effort_limit, *names.deprecated_effort_limits)),
        ("max_actuator_velocity", (names.velocity_limit, *names.deprecated_velocity_limits)),
    )
    for field, attributes in groups:
        for attribute in attributes:
            value = getattr(cfg, attribute, None)
            if value is None or (isinstance(value, (int, float)) and not isinstance(value, bool)):
                continue
            where = f"{CFG_NAME}.{attribute}"
            if isinstance(value, Mapping):
                value = {str(k): read_envelope_value(v, field, f"{where}[{k!r}]") for k, v in value.items()}
            elif isinstance(value, str):
                value = read_envelope_value(value, field, where)
            else:
                raise InputError(
                    f"{where}: got {value!r}; expected a number, a string with units or a "
                    "{joint regex: value} dict"
                )
            setattr(cfg, attribute, value)


def si_value(value: Any, field: str) -> Any:
    """A cfg value in SI: a number or string with units, or a ``{joint regex: value}`` dict of them.

    Raises:
        InputError: a wrong unit, or a value that is not a number, string or dict.
    """
    where = f"{CFG_NAME}.{field}"
    if isinstance(value, Mapping):
        return {
            str(key): read_envelope_value(item, field, f"{where}[{key!r}]") for key, item in value.items()
        }
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise InputError(
            f"{where}: got {value!r}; expected a number, a string with units or a {{joint regex: value}} dict"
        )
    return read_envelope_value(value, field, where)


def resolve_datasheets(datasheet: Any, joint_names: list[str]) -> dict[str, PerformanceEnvelope]:
    """The envelope of every joint a ``datasheet`` cfg value names: one source, or ``{joint regex: source}``.

    Raises:
        InputError: a source the resolver cannot read, or a regex that matches no joint.
    """
    import re

    from drive_envelope._src.datasheet.resolve import resolve_envelope

    where = f"{CFG_NAME}.datasheet"
    sources = datasheet if isinstance(datasheet, Mapping) else {".*": datasheet}
    found: dict[str, PerformanceEnvelope] = {}
    for pattern, source in sources.items():
        matched = [name for name in joint_names if re.fullmatch(str(pattern), name)]
        if not matched:
            raise InputError(f"{where}[{pattern!r}]: matches none of the joints {joint_names}")
        envelope = resolve_envelope(source, where=f"{where}[{pattern!r}]")
        for name in matched:
            if name in found:
                raise InputError(f"{where}[{pattern!r}]: joint {name!r} is matched by an earlier key too")
            found[name] = envelope
    return found


def inertia_value(value: Any) -> Any:
    """The cfg's ``effective_inertia`` in SI: a number or string with units, or a regex dict of them."""
    from drive_envelope._src.values import read_joint_quantity

    where = f"{CFG_NAME}.effective_inertia"
    if isinstance(value, Mapping):
        return {str(k): read_joint_quantity(v, "kg*m^2", "kg", f"{where}[{k!r}]") for k, v in value.items()}
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise InputError(
            f"{where}: got {value!r}; expected a number [kg*m^2 or kg], a string with units or a "
            "{joint regex: value} dict"
        )
    return read_joint_quantity(value, "kg*m^2", "kg", where)


_LONGEST_STEP = 0.1
"""[s] Robot physics steps are 0.1-20 ms: a ``physics_dt`` above this is probably milliseconds."""


def time_step(value: Any) -> float:
    """The cfg's ``physics_dt`` [s], finite and > 0 (a warning above :data:`_LONGEST_STEP`)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < float(value) < math.inf:
        raise InputError(f"{CFG_NAME}.physics_dt: got {value!r}; expected a time step > 0 and finite [s]")
    if value > _LONGEST_STEP:
        warnings.warn(
            f"{CFG_NAME}.physics_dt = {value:g} s is a very long physics step (robots step 0.1-20 ms); "
            f"physics_dt is in seconds: {value:g} ms is {value / 1000:g}",
            UserWarning,
            stacklevel=3,
        )
    return float(value)

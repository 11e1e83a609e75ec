"""``PerformanceEnvelopeActuator``: Isaac Lab's ideal PD actuator clipped by the PhysX envelope.

Isaac Lab's explicit actuators compute ``effort = stiffness*(q_target - q) + damping*(v_target - v)
+ effort_target`` for every environment and joint and clip it (``IdealPDActuator``: to
``+-effort_limit``; ``DCMotor``: to a torque-speed line). :class:`PerformanceEnvelopeActuator` is an
``IdealPDActuator`` whose clip is the envelope's effort limit at the current joint velocity,
``L(v) = max(min(effort_limit - R|v|, (v_max - |v|)/G), 0)``, with ``effort_limit`` (Isaac Lab's own
field) as max_effort. It is an explicit actuator: the clip acts at the velocity the step starts
from, one step behind PhysX's implicit clamp (``docs/isaaclab.md`` has the implicit path).

The four envelope parameters are ``(num_envs, num_joints)`` tensors on the actuator
(``effort_limit``, ``max_actuator_velocity``, ``velocity_dependent_resistance``,
``speed_effort_gradient``), read at every :meth:`compute`, so an event term can write them per
environment the way Isaac Lab's ``randomize_actuator_gains`` writes ``actuator.stiffness[env_ids]``;
``default_*`` keep the configured values. The classes subclass Isaac Lab's, so they are defined
when first asked for (:func:`build`), which imports ``isaaclab.actuators``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from typing import Any

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import read_envelope_value

__all__ = ["ENVELOPE_ATTRIBUTES", "build", "resolve_datasheets", "si_value"]

ENVELOPE_ATTRIBUTES = ("effort_limit", *ENVELOPE_FIELDS[1:])
"""The actuator's envelope tensors, in the order of the envelope fields: max_effort is ``effort_limit``."""
_DEFAULTS = {
    "max_actuator_velocity": math.inf,
    "velocity_dependent_resistance": 0.0,
    "speed_effort_gradient": 0.0,
}
_CFG = "PerformanceEnvelopeActuatorCfg"


def si_value(value: Any, field: str) -> Any:
    """A cfg value in SI: a number or string with units, or a ``{joint regex: value}`` dict of them.

    Raises:
        InputError: a wrong unit, or a value that is not a number, string or dict.
    """
    where = f"{_CFG}.{field}"
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

    where = f"{_CFG}.datasheet"
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


@functools.cache
def build() -> tuple[type, type]:
    """Define ``(PerformanceEnvelopeActuatorCfg, PerformanceEnvelopeActuator)`` (imports Isaac Lab once).

    Raises:
        ImportError: Isaac Lab's ``isaaclab.actuators`` cannot be imported.
    """
    import isaaclab.utils.string as string_utils
    import torch
    from isaaclab.actuators import IdealPDActuator, IdealPDActuatorCfg
    from isaaclab.utils import configclass

    from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors
    from drive_envelope._src.kernels.torch_ops import clamp_effort

    class PerformanceEnvelopeActuator(IdealPDActuator):  # type: ignore[misc,valid-type]
        """Ideal PD actuator whose effort is clipped by the PhysX drive performance envelope.

        ``computed_effort`` holds the PD law, ``applied_effort`` the clipped effort sent to the
        simulation as a joint effort (Isaac Lab sets the simulation's own drive gains to 0).
        """

        cfg: Any
        effort_limit: Any
        """max_effort [N*m or N], ``(num_envs, num_joints)`` (Isaac Lab's own field)."""
        max_actuator_velocity: Any
        """Speed cap at zero effort [rad/s or m/s], ``(num_envs, num_joints)``."""
        velocity_dependent_resistance: Any
        """Effort lost per unit speed [N*m*s/rad or N*s/m], ``(num_envs, num_joints)``."""
        speed_effort_gradient: Any
        """Speed lost per unit effort [(rad/s)/(N*m) or (m/s)/N], ``(num_envs, num_joints)``."""

        def __init__(
            self,
            cfg: Any,
            joint_names: list[str],
            joint_ids: Any,
            num_envs: int,
            device: str,
            stiffness: Any = 0.0,
            damping: Any = 0.0,
            armature: Any = 0.0,
            friction: Any = 0.0,
            dynamic_friction: Any = 0.0,
            viscous_friction: Any = 0.0,
            effort_limit: Any = torch.inf,
            velocity_limit: Any = torch.inf,
        ) -> None:
            """Build the actuator as ``Articulation._process_actuators_cfg`` does (Isaac Lab's keywords).

            The defaults of stiffness ... velocity_limit are the simulation's values for these joints
            (from the USD through PhysX); the cfg's values replace them, Isaac Lab's rule.

            Raises:
                InputError: an envelope value that is negative, NaN, of the wrong unit or matches no
                    joint, or a datasheet that cannot be read.
            """
            super().__init__(
                cfg,
                joint_names,
                joint_ids,
                num_envs,
                device,
                stiffness=stiffness,
                damping=damping,
                armature=armature,
                friction=friction,
                dynamic_friction=dynamic_friction,
                viscous_friction=viscous_friction,
                effort_limit=effort_limit,
                velocity_limit=velocity_limit,
            )
            sheets = resolve_datasheets(cfg.datasheet, joint_names) if cfg.datasheet is not None else {}
            if cfg.effort_limit is None and sheets:
                # precedence: the cfg's own effort_limit, then the datasheet, then the simulation's value
                self.effort_limit = self._from_sheets(sheets, "max_effort", self.effort_limit)
            for field in ENVELOPE_FIELDS[1:]:
                value = getattr(cfg, field)
                tensor = torch.full_like(self.computed_effort, _DEFAULTS[field])
                if sheets and (value is None or isinstance(value, Mapping)):
                    tensor = self._from_sheets(sheets, field, tensor)  # a dict may name some joints only
                if value is not None:
                    tensor = self._apply(field, si_value(value, field), tensor)
                setattr(self, field, tensor)
            for attribute in ENVELOPE_ATTRIBUTES:
                self._check(attribute, getattr(self, attribute))
                setattr(self, f"default_{attribute}", getattr(self, attribute).clone())
            self._joint_vel = torch.zeros_like(self.computed_effort)

        def _apply(self, field: str, value: Any, base: Any) -> Any:
            """``base`` with the cfg's value on all joints, or per regex (others keep ``base``)."""
            if not isinstance(value, Mapping):
                return torch.full_like(base, float(value))
            try:
                columns, _, values = string_utils.resolve_matching_names_values(dict(value), self.joint_names)
            except (TypeError, ValueError) as exc:  # a regex matching no joint, or a joint matched twice
                raise InputError(f"{_CFG}.{field}: {' '.join(str(exc).split())}") from None
            result = base.clone()
            result[:, columns] = torch.tensor(values, dtype=base.dtype, device=base.device)
            return result

        def _from_sheets(self, sheets: dict[str, PerformanceEnvelope], field: str, base: Any) -> Any:
            """``base`` with the datasheet value of ``field`` on each joint a datasheet names."""
            values = base.clone()
            for column, name in enumerate(self.joint_names):
                if name in sheets:
                    values[:, column] = float(getattr(sheets[name], field))
            return values

        def _check(self, attribute: str, values: Any) -> None:
            """Refuse negative or NaN values (inf only as a speed or effort limit), naming the joint."""
            finite_only = attribute in ("velocity_dependent_resistance", "speed_effort_gradient")
            bad = torch.isnan(values) | (values < 0.0)
            if finite_only:
                bad |= torch.isinf(values)
            if bool(bad.any()):
                env, column = (int(i) for i in torch.nonzero(bad)[0])
                field = "max_effort (effort_limit)" if attribute == "effort_limit" else attribute
                expected = ">= 0 and finite" if finite_only else ">= 0"
                raise InputError(
                    f"{_CFG}: {field} of joint {self.joint_names[column]!r} is "
                    f"{float(values[env, column])!r}; expected {expected}"
                )

        @property
        def envelope(self) -> Any:
            """The envelope the clip uses now: :class:`EnvelopeTensors` of ``(num_envs, num_joints)``."""
            return EnvelopeTensors(
                max_effort=self.effort_limit,
                max_actuator_velocity=self.max_actuator_velocity,
                velocity_dependent_resistance=self.velocity_dependent_resistance,
                speed_effort_gradient=self.speed_effort_gradient,
            )

        def compute(self, control_action: Any, joint_pos: Any, joint_vel: Any) -> Any:
            """PD effort towards the targets, clipped by the envelope at ``joint_vel`` (DCMotor's pattern).

            Args:
                control_action: Isaac Lab's ``ArticulationActions`` (targets and feed-forward efforts).
                joint_pos: Joint positions [rad or m], ``(num_envs, num_joints)``.
                joint_vel: Joint velocities [rad/s or m/s], ``(num_envs, num_joints)``.

            Returns:
                ``control_action`` with ``joint_efforts`` = the applied effort [N*m or N] and no
                position or velocity targets (the simulation's drive gains are 0).
            """
            self._joint_vel[:] = joint_vel
            return super().compute(control_action, joint_pos, joint_vel)

        def _clip_effort(self, effort: Any) -> Any:
            """``clip(effort, -L(v), L(v))`` at the velocity of this step's :meth:`compute`."""
            return clamp_effort(self.envelope, effort, self._joint_vel)

    @configclass
    class PerformanceEnvelopeActuatorCfg(IdealPDActuatorCfg):  # type: ignore[misc,valid-type]
        """Configuration of :class:`PerformanceEnvelopeActuator`: Isaac Lab's PD gains plus the envelope.

        ``effort_limit`` (Isaac Lab's field) is max_effort [N*m or N]. Each envelope field is a
        number, a string with units (``"300 rpm"``) or a ``{joint regex: value}`` dict, like Isaac
        Lab's own fields; ``datasheet`` (a catalog key, datasheet file or envelope file, or a
        ``{joint regex: source}`` dict) fills the four for the joints it names, and any field set
        here replaces its value. Without either: no speed limit, no slopes.
        """

        class_type: type = PerformanceEnvelopeActuator

        max_actuator_velocity: dict[str, float | str] | float | str | None = None
        """Speed cap at zero effort [rad/s or m/s] (``inf``: none). None: the datasheet's, else inf."""

        velocity_dependent_resistance: dict[str, float | str] | float | str | None = None
        """Effort lost per unit speed R [N*m*s/rad or N*s/m]. None: the datasheet's, else 0."""

        speed_effort_gradient: dict[str, float | str] | float | str | None = None
        """Speed lost per unit effort G [(rad/s)/(N*m) or (m/s)/N]. None: the datasheet's, else 0."""

        datasheet: dict[str, str] | str | None = None
        """Catalog key, datasheet or envelope file giving all four values, or ``{joint regex: source}``."""

    for cls in (PerformanceEnvelopeActuator, PerformanceEnvelopeActuatorCfg):
        cls.__module__ = "drive_envelope.isaaclab"
    return PerformanceEnvelopeActuatorCfg, PerformanceEnvelopeActuator

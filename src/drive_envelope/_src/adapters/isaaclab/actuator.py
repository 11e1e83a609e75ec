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
``default_*`` keep the configured values. The classes subclass Isaac Lab's, so they are defined
when first asked for (:func:`build`), which imports ``isaaclab.actuators``.
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Mapping
from typing import Any

from drive_envelope._src.adapters.isaaclab import compat
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import read_envelope_value

__all__ = ["ENVELOPE_ATTRIBUTES", "build", "resolve_datasheets", "set_response_from_mass_matrix", "si_value"]

ENVELOPE_ATTRIBUTES = ("effort_limit", *ENVELOPE_FIELDS[1:])
"""The actuator's envelope tensors in Isaac Lab 2.3, in the order of the envelope fields."""


def envelope_attributes() -> tuple[str, ...]:
    """The actuator's envelope tensors, in the order of the envelope fields.

    max_effort is Isaac Lab's effort limit (2.3 ``effort_limit``, 3.0 ``actuator_effort_limit``).
    """
    return (compat.api().effort_limit, *ENVELOPE_FIELDS[1:])


def _limits_in_si(cfg: Any, names: Any) -> None:
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
            where = f"{_CFG}.{attribute}"
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


def _simulated(limits: Mapping[str, Any], names: Any, like: Any) -> Any:
    """The simulation's effort limit the articulation passed (tensor or number; none: inf), as ``like``."""
    import torch

    given = limits.get(names.effort_limit)
    for name in names.deprecated_effort_limits:
        if given is None:
            given = limits.get(name)
    if isinstance(given, torch.Tensor):
        return given.to(like).expand_as(like).clone()
    return torch.full_like(like, math.inf if given is None else float(given))


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

    from drive_envelope._src.kernels.torch_clip import FreeVelocity, check_clip, clip_effort
    from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors

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
            **limits: Any,
        ) -> None:
            """Build the actuator as Isaac Lab's articulation does, with that Isaac Lab's keywords.

            ``stiffness``, ``damping`` and ``limits`` are the simulation's values for these joints
            (from the USD), passed on to Isaac Lab's ``IdealPDActuator`` unchanged: 2.3 gives
            armature, friction, dynamic_friction, viscous_friction, effort_limit and velocity_limit,
            3.0 actuator_effort_limit and actuator_velocity_limit (``compat``). The cfg's values
            replace them, Isaac Lab's rule.

            Raises:
                InputError: an envelope or limit value that is negative, NaN, of the wrong unit or
                    matches no joint, or a datasheet that cannot be read.
            """
            names = compat.api()
            _limits_in_si(cfg, names)
            try:
                super().__init__(
                    cfg,
                    joint_names,
                    joint_ids,
                    num_envs,
                    device,
                    stiffness=stiffness,
                    damping=damping,
                    **limits,
                )
            except ValueError as exc:  # Isaac Lab's parsing of a cfg value: one line naming the cfg
                raise InputError(f"{_CFG}: {' '.join(str(exc).split())}") from None
            sheets = resolve_datasheets(cfg.datasheet, joint_names) if cfg.datasheet is not None else {}
            effort = compat.cfg_value(cfg, names.effort_limit, names.deprecated_effort_limits)
            if sheets and (effort is None or isinstance(effort, Mapping)):
                # precedence per joint: the cfg's own effort limit, then the datasheet, then the
                # simulation's value (a dict names some joints only: the others keep the datasheet's)
                simulated = _simulated(limits, names, self.computed_effort)
                tensor = self._from_sheets(sheets, "max_effort", simulated)
                if effort is not None:
                    tensor = self._apply(names.effort_limit, effort, tensor)
                setattr(self, names.effort_limit, tensor)
            for field in ENVELOPE_FIELDS[1:]:
                value = getattr(cfg, field)
                tensor = torch.full_like(self.computed_effort, _DEFAULTS[field])
                if sheets and (value is None or isinstance(value, Mapping)):
                    tensor = self._from_sheets(sheets, field, tensor)  # a dict may name some joints only
                if value is not None:
                    tensor = self._apply(field, si_value(value, field), tensor)
                setattr(self, field, tensor)
            for attribute in envelope_attributes():
                self._check(attribute, getattr(self, attribute))
                setattr(self, f"default_{attribute}", getattr(self, attribute).clone())
            self._joint_vel = torch.zeros_like(self.computed_effort)
            self._init_clip(cfg)
            self._warn_speed_limit(cfg, names)

        @property
        def max_effort(self) -> Any:
            """max_effort [N*m or N], ``(num_envs, num_joints)``: Isaac Lab's effort-limit tensor.

            The same tensor as 2.3's ``effort_limit`` and 3.0's ``actuator_effort_limit``.
            """
            return getattr(self, compat.api().effort_limit)

        def _warn_speed_limit(self, cfg: Any, names: Any) -> None:
            """Warn once where the cfg's speed limit is above max_actuator_velocity (it never binds)."""
            if compat.cfg_value(cfg, names.velocity_limit, names.deprecated_velocity_limits) is None:
                return  # the simulation's joint limit: the envelope's cap below it is the point
            limit = getattr(self, names.velocity_limit)
            below = (self.max_actuator_velocity < limit)[0]
            if bool(below.any()):
                column = int(torch.nonzero(below)[0])
                joints = [name for name, low in zip(self.joint_names, below.tolist(), strict=True) if low]
                vmax = float(self.max_actuator_velocity[0, column])
                warnings.warn(
                    f"{_CFG}: max_actuator_velocity {vmax:g} is below "
                    f"{names.velocity_limit} {float(limit[0, column]):g} [rad/s or m/s] on {joints}: the "
                    f"envelope stops these joints at max_actuator_velocity, so {names.velocity_limit} "
                    "above it never binds (lower it, or check the datasheet's speed)",
                    UserWarning,
                    stacklevel=3,
                )

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
                field = f"max_effort ({attribute})" if attribute == envelope_attributes()[0] else attribute
                expected = ">= 0 and finite" if finite_only else ">= 0"
                raise InputError(
                    f"{_CFG}: {field} of joint {self.joint_names[column]!r} is "
                    f"{float(values[env, column])!r}; expected {expected}"
                )

        @property
        def envelope(self) -> Any:
            """The envelope the clip uses now: :class:`EnvelopeTensors` of ``(num_envs, num_joints)``."""
            return EnvelopeTensors(
                max_effort=self.max_effort,
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
            for name in ("joint_positions", "joint_velocities", "joint_efforts"):
                given = getattr(control_action, name, None)
                if given is not None and given.dtype != self.computed_effort.dtype:
                    kind = self.computed_effort.dtype
                    raise InputError(
                        f"{type(self).__name__}.compute: action {name} are {given.dtype}, Isaac Lab's joint "
                        f"buffers {kind}; set the targets as {kind} "
                        "(e.g. robot.set_joint_position_target(targets.float()))"
                    )
            self._joint_vel[:] = joint_vel
            return super().compute(control_action, joint_pos, joint_vel)

        def _init_clip(self, cfg: Any) -> None:
            """The clip rule, the unit response (from ``effective_inertia``) and the history it needs."""
            self.clip = check_clip(cfg.clip, f"{_CFG}.clip")
            self.physics_dt = None if cfg.physics_dt is None else _time_step(cfg.physics_dt)
            self.response = torch.full_like(self.computed_effort, math.nan)
            self.response_source = None
            """Where ``response`` comes from: ``"effective_inertia"``, ``"mass_matrix"`` or None (unset)."""
            if cfg.effective_inertia is not None:
                inertia = self._apply(
                    "effective_inertia", _inertia_value(cfg.effective_inertia), self.response
                )
                self._check_inertia(inertia, cfg.effective_inertia)
                self.response = 1.0 / inertia
                self.response_source = "effective_inertia"
            self._free_velocity = FreeVelocity(self.computed_effort)

        def _check_inertia(self, inertia: Any, given: Any) -> None:
            """Every joint needs an effective inertia > 0 and finite (a dict must name them all)."""
            bad = ~((inertia > 0.0) & (inertia < math.inf))
            if bool(bad.any()):
                column = int(torch.nonzero(bad)[0][1])
                value = float(inertia[0, column])
                what = "is not named" if math.isnan(value) else f"is {value!r}"
                raise InputError(
                    f"{_CFG}.effective_inertia: joint {self.joint_names[column]!r} {what}; expected "
                    f"> 0 and finite [kg*m^2 or kg] for every joint (got {given!r})"
                )

        def reset(self, env_ids: Any) -> None:
            """Isaac Lab's reset, and the clip forgets these environments' last step (a reset moves them)."""
            super().reset(env_ids)
            self._free_velocity.reset(env_ids)

        def _clip_effort(self, effort: Any, joint_vel: Any = None) -> Any:
            """The PD effort limited by the envelope with the cfg's ``clip`` rule.

            ``"end_of_step"``: PhysX's clamp at the end-of-step velocity, from the velocity the step
            would end with without this effort (:class:`FreeVelocity`, from the last step), fused by
            ``torch.compile`` from ``FUSE_MIN_ELEMENTS`` (4096) elements;
            ``"start_of_step"``: ``clip(effort, -L(v), L(v))`` at this step's velocity.
            """
            velocity = self._joint_vel if joint_vel is None else joint_vel
            if self.clip == "start_of_step":
                return clip_effort(self.envelope, effort, velocity, clip="start_of_step")
            if self.response_source is None:
                raise InputError(
                    f"{_CFG}.effective_inertia: not given and no mass-matrix response set; "
                    "clip='end_of_step' needs each joint's unit response: set effective_inertia "
                    "[kg*m^2 or kg] (1/(M^-1)_ii of the robot's mass matrix at a typical pose), call "
                    "drive_envelope.isaaclab.set_response_from_mass_matrix(robot) each step, or set "
                    "clip='start_of_step'"
                )
            if self.physics_dt is None:
                self.physics_dt = _simulation_dt()
            # the estimate and the clamp in one torch.compile kernel at RL scale (eager below it)
            return self._free_velocity.clip(self.envelope, effort, velocity, self.response, self.physics_dt)

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

        clip: str = "end_of_step"
        """``"end_of_step"``: PhysX's implicit clamp at the end-of-step velocity (needs the unit
        response); ``"start_of_step"``: the envelope's limit at the step's start velocity (runs away
        at the speed line)."""

        effective_inertia: dict[str, float | str] | float | str | None = None
        """Each joint's effective inertia [kg*m^2 or kg], ``1/(M^-1)_ii`` (or a ``{joint regex: value}``
        dict naming every joint): the end-of-step clip's unit response is its inverse. None: set
        the response from the mass matrix (:func:`set_response_from_mass_matrix`)."""

        physics_dt: float | None = None
        """The physics time step [s]. None: Isaac Lab's ``SimulationContext`` physics dt."""

    for cls in (PerformanceEnvelopeActuator, PerformanceEnvelopeActuatorCfg):
        cls.__module__ = "drive_envelope.isaaclab"
    return PerformanceEnvelopeActuatorCfg, PerformanceEnvelopeActuator


def _inertia_value(value: Any) -> Any:
    """The cfg's ``effective_inertia`` in SI: a number or string with units, or a regex dict of them."""
    from drive_envelope._src.values import read_joint_quantity

    where = f"{_CFG}.effective_inertia"
    if isinstance(value, Mapping):
        return {str(k): read_joint_quantity(v, "kg*m^2", "kg", f"{where}[{k!r}]") for k, v in value.items()}
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise InputError(
            f"{where}: got {value!r}; expected a number [kg*m^2 or kg], a string with units or a "
            "{joint regex: value} dict"
        )
    return read_joint_quantity(value, "kg*m^2", "kg", where)


def _time_step(value: Any) -> float:
    """The cfg's ``physics_dt`` [s], finite and > 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < float(value) < math.inf:
        raise InputError(f"{_CFG}.physics_dt: got {value!r}; expected a time step > 0 and finite [s]")
    return float(value)


def _simulation_dt() -> float:
    """Isaac Lab's physics dt [s] from its ``SimulationContext`` (InputError when there is none)."""
    try:
        from isaaclab.sim import SimulationContext

        context = SimulationContext.instance()
    except Exception:  # Isaac Sim missing or not started: say what to set instead
        context = None
    if context is None:
        raise InputError(
            f"{_CFG}.physics_dt: not set and no Isaac Lab SimulationContext to read it from; "
            "set physics_dt [s]"
        )
    return _time_step(float(context.get_physics_dt()))


def set_response_from_mass_matrix(articulation: Any) -> None:
    """Give every envelope actuator of ``articulation`` its joints' unit response ``(M^-1)_ii``.

    Reads the articulation's joint-space mass matrices from PhysX
    (``articulation.root_physx_view.get_generalized_mass_matrices()``, ``(num_envs, n, n)``; with a
    floating base ``n`` is the joint count plus 6, the base's rows first), inverts them (batched
    ``torch.linalg.inv``) and writes the diagonal at each actuator's joints to its ``response``
    [1/(kg*m^2) or 1/kg]. Call it every step (e.g. before ``env.step``'s physics steps, or as an
    interval event) for the response at the current pose, or once for a fixed one.

    Args:
        articulation: An Isaac Lab ``Articulation`` whose ``actuators`` include
            :class:`PerformanceEnvelopeActuator` s.
    """
    import torch

    _, actuator_class = build()
    matrices = articulation.root_physx_view.get_generalized_mass_matrices()
    diagonal = torch.diagonal(torch.linalg.inv(matrices), dim1=-2, dim2=-1)
    offset = diagonal.shape[-1] - int(articulation.num_joints)
    if offset not in (0, 6):
        raise InputError(
            f"set_response_from_mass_matrix: mass matrices of size {diagonal.shape[-1]} for "
            f"{articulation.num_joints} joints; expected the joint count, or it plus 6 (floating base)"
        )
    for item in articulation.actuators.values():
        if isinstance(item, actuator_class):
            actuator: Any = item
            ids = actuator.joint_indices
            columns = torch.arange(articulation.num_joints, device=diagonal.device)[ids] + offset
            actuator.response[:] = diagonal[:, columns].to(actuator.response)
            actuator.response_source = "mass_matrix"

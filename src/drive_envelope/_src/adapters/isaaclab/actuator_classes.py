"""``PerformanceEnvelopeActuator`` and its cfg themselves: imports Isaac Lab and torch at the top.

:mod:`~drive_envelope._src.adapters.isaaclab.actuator` explains the actuator and reads the cfg's
values; ``drive_envelope.isaaclab`` loads this module on the first access to either class, and the
event term and :func:`set_response_from_mass_matrix` when they run. The classes subclass Isaac
Lab's, so they are defined here at module level (once per process); their ``__module__`` names the
public facade, whose ``__getattr__`` returns these same classes, so reprs, docs and pickles use the
one public path.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any

import isaaclab.utils.string as string_utils
import torch
from isaaclab.actuators import IdealPDActuator, IdealPDActuatorCfg
from isaaclab.utils import configclass

from drive_envelope._src.adapters.isaaclab import compat
from drive_envelope._src.adapters.isaaclab.actuator import (
    CFG_NAME,
    envelope_attributes,
    inertia_value,
    limits_in_si,
    resolve_datasheets,
    si_value,
    time_step,
)
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.torch_clip import FreeVelocity, check_clip, clip_effort
from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors

_PUBLIC = "drive_envelope.isaaclab"
"""The classes' ``__module__``: the facade resolves the names to these classes (pickling by reference)."""

_DEFAULTS = {
    "max_actuator_velocity": math.inf,
    "velocity_dependent_resistance": 0.0,
    "speed_effort_gradient": 0.0,
}


def _simulated(limits: Mapping[str, Any], names: Any, like: Any) -> Any:
    """The simulation's effort limit the articulation passed (tensor or number; none: inf), as ``like``."""
    given = limits.get(names.effort_limit)
    for name in names.deprecated_effort_limits:
        if given is None:
            given = limits.get(name)
    if isinstance(given, torch.Tensor):
        return given.to(like).expand_as(like).clone()
    return torch.full_like(like, math.inf if given is None else float(given))


def _simulation_dt() -> float:
    """Isaac Lab's physics dt [s] from its ``SimulationContext`` (InputError when there is none)."""
    try:
        from isaaclab.sim import SimulationContext

        context = SimulationContext.instance()
    except Exception:  # Isaac Sim missing or not started: say what to set instead
        context = None
    if context is None:
        raise InputError(
            f"{CFG_NAME}.physics_dt: not set and no Isaac Lab SimulationContext to read it from; "
            "set physics_dt [s]"
        )
    return time_step(float(context.get_physics_dt()))


class PerformanceEnvelopeActuator(IdealPDActuator):  # type: ignore[misc,valid-type]
    """Ideal PD actuator whose effort is clipped by the PhysX drive performance envelope.

    ``computed_effort`` holds the PD law, ``applied_effort`` the clipped effort sent to the
    simulation as a joint effort (Isaac Lab sets the simulation's own drive gains to 0).
    """

    __module__ = _PUBLIC

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
        limits_in_si(cfg, names)
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
            raise InputError(f"{CFG_NAME}: {' '.join(str(exc).split())}") from None
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
                f"{CFG_NAME}: max_actuator_velocity {vmax:g} is below "
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
            raise InputError(f"{CFG_NAME}.{field}: {' '.join(str(exc).split())}") from None
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
                f"{CFG_NAME}: {field} of joint {self.joint_names[column]!r} is "
                f"{float(values[env, column])!r}; expected {expected}"
            )

    @property
    def envelope(self) -> Any:
        """The envelope the clip uses now: :class:`EnvelopeTensors` of ``(num_envs, num_joints)``.

        Built again only when one of the four attributes is a different tensor: an in-place edit
        (the randomization event's ``tensor[env_ids] = ...``) shows through the cached one, which
        holds the same tensors. Building it checks dtypes, devices and shapes: 14 us of the 330 us
        of ``compute()`` (start-of-step clip, 4096 x 12, CPU, ``benchmarks/bench_isaaclab.py``).
        """
        tensors = (
            self.max_effort,
            self.max_actuator_velocity,
            self.velocity_dependent_resistance,
            self.speed_effort_gradient,
        )
        cached = getattr(self, "_envelope_cache", None)
        if cached is None or any(a is not b for a, b in zip(cached.as_tuple(), tensors, strict=True)):
            cached = EnvelopeTensors(
                max_effort=tensors[0],
                max_actuator_velocity=tensors[1],
                velocity_dependent_resistance=tensors[2],
                speed_effort_gradient=tensors[3],
            )
            self._envelope_cache = cached
        return cached

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
        self.clip = check_clip(cfg.clip, f"{CFG_NAME}.clip")
        self.physics_dt = None if cfg.physics_dt is None else time_step(cfg.physics_dt)
        self.response = torch.full_like(self.computed_effort, math.nan)
        self.response_source = None
        """Where ``response`` comes from: ``"effective_inertia"``, ``"mass_matrix"`` or None (unset)."""
        if cfg.effective_inertia is not None:
            inertia = self._apply("effective_inertia", inertia_value(cfg.effective_inertia), self.response)
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
                f"{CFG_NAME}.effective_inertia: joint {self.joint_names[column]!r} {what}; expected "
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
                f"{CFG_NAME}.effective_inertia: not given and no mass-matrix response set; "
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

    __module__ = _PUBLIC

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

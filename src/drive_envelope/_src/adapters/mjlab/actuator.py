"""mjlab actuators with the PhysX performance envelope as their effort limit.

:class:`PerformanceEnvelopeActuator` is an mjlab :class:`~mjlab.actuator.IdealPdActuator` (a
``<motor>`` per joint, torque computed in torch every physics step) whose PD torque
``kp*(q* - q) + kd*(v* - v) + tau_ff`` (clipped to ``+-force_limit``) is limited by the envelope
with the config's ``clip`` rule (``kernels/torch_clip.py``, the names of the Isaac Lab cfg):

* ``"end_of_step"`` (default): PhysX's implicit clamp at the velocity the step will end with,
  ``v_free + response*dt*effort``. ``response`` is each target's ``(M^-1)_ii``: from the config's
  ``effective_inertia``, or (None) from the model, at its first keyframe when the actuator is
  initialized and then from MJWarp's mass matrix ``data.M`` after every physics step
  (``response.py``). ``v_free`` adds to the current velocity the last step's velocity change that
  the effort does not explain (gravity, loads, contacts, the other joints), recorded in
  :meth:`~PerformanceEnvelopeActuator.update`, which mjlab calls after each ``sim.step()``.
* ``"start_of_step"``: the envelope's limit at the current velocity, what a plain explicit
  actuator does; it runs away at the speed line (issue 22), kept by name.

Both keep mjlab's shared ``compute`` and declare their per-target tensors in ``param_names`` with
a stateless ``control_law`` (the end-of-step history lives in those tensors and is advanced by
``update``), so mjlab fuses every group of them into one batched evaluation; from 4096 elements
the end-of-step law runs as one ``torch.compile`` kernel (``FUSE_MIN_ELEMENTS``).

With ``implicit=True`` the config builds :class:`PerformanceEnvelopeImplicitActuator` instead:
the motors carry the drive's numbers in ``actuator_dynprm`` (the MuJoCo plugin's layout), the
control is the position target, and MJWarp's step solves PhysX's implicit drive and the envelope
at the end-of-step velocity for every drive of the robot together
(``drive_envelope.mjwarp.attach``). mjlab captures its CUDA graphs before it initializes
actuators: on a GPU call ``env.sim.create_graph()`` once after building the environment.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import torch
from mjlab.actuator import IdealPdActuator, IdealPdActuatorCfg
from mjlab.actuator.actuator import ActuatorCmd, TransmissionType
from mjlab.actuator.pd_actuator import pd_torque

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.envelope_values import read_envelope_values
from drive_envelope._src.kernels.torch_clip import check_clip, end_of_step_law
from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors
from drive_envelope._src.kernels.torch_ops import clamp_effort

if TYPE_CHECKING:
    from mjlab.entity import Entity

_CFG = "PerformanceEnvelopeActuatorCfg"


@dataclass(kw_only=True)
class PerformanceEnvelopeActuatorCfg(IdealPdActuatorCfg):
    """An mjlab PD actuator group limited by one performance envelope (mjlab's config style).

    Give the envelope either as ``envelope`` (a :class:`PerformanceEnvelope`, an envelope or
    datasheet file, or a catalog name) or as the four numbers (SI, or strings with units such as
    ``"300 rpm"``). ``stiffness`` [N*m/rad or N/m] and ``damping`` [N*m*s/rad or N*s/m] are mjlab's.
    """

    max_effort: float | str | None = None
    """Effort cap at zero velocity [N*m or N], ``>= 0`` and finite (unless ``envelope`` is given)."""
    max_actuator_velocity: float | str = math.inf
    """Speed limit [rad/s or m/s] (``inf``: none)."""
    velocity_dependent_resistance: float | str = 0.0
    """Effort lost per unit speed [N*m*s/rad or N*s/m]."""
    speed_effort_gradient: float | str = 0.0
    """Speed lost per unit effort [(rad/s)/(N*m) or (m/s)/N]."""
    envelope: PerformanceEnvelope | str | None = None
    """The whole envelope instead of the four numbers: an envelope, a file or a catalog name."""
    implicit: bool = False
    """Solve the drive implicitly in MJWarp's step (PhysX's semantics) instead of clipping in torch."""
    clip: str = "end_of_step"
    """The explicit clip: ``"end_of_step"`` (PhysX's clamp at the end-of-step velocity) or
    ``"start_of_step"`` (the envelope's limit at the step's start velocity; runs away at the line)."""
    effective_inertia: float | str | dict[str, float | str] | None = None
    """Each target's effective inertia [kg*m^2 or kg], ``1/(M^-1)_ii``, or a ``{target regex: value}``
    dict naming every target; the end-of-step clip's unit response is its inverse. None: from the
    model, at its first keyframe, then MJWarp's mass matrix after every step (joints only; costs a
    batched Cholesky per robot and step). ``"model"``: the first keyframe's, kept (no per-step cost)."""
    physics_dt: float | None = None
    """The physics time step [s]. None: the model's ``opt.timestep``."""

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("stiffness", "damping"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, (int, float)) and 0.0 <= value < math.inf):
                raise InputError(f"{_CFG}: {name} = {value!r}; expected a number >= 0 and finite")
        check_clip(self.clip, f"{_CFG}.clip")
        self.inertia_values()
        if self.physics_dt is not None:
            _time_step(self.physics_dt)
        if self.clip == "end_of_step" and not self.implicit:
            if self.transmission_type == TransmissionType.SITE:
                raise InputError(
                    f"{_CFG}.clip: 'end_of_step' needs a joint or tendon transmission (a site has no "
                    "velocity); set clip='start_of_step'"
                )
            if self.transmission_type == TransmissionType.TENDON and self.effective_inertia in (
                None,
                "model",
            ):
                raise InputError(
                    f"{_CFG}.effective_inertia: needed for a tendon transmission with clip='end_of_step' "
                    "(the model's response is per joint) [kg]; set it, or clip='start_of_step'"
                )
        self.resolved()  # one-line errors now, not at the first step

    def inertia_values(self) -> float | dict[str, float] | None:
        """``effective_inertia`` in SI [kg*m^2 or kg]: a number, a ``{regex: number}`` dict, or None."""
        from drive_envelope._src.values import read_joint_quantity

        value, where = self.effective_inertia, f"{_CFG}.effective_inertia"
        if value is None or value == "model":
            return None
        if isinstance(value, dict):
            items = {
                str(k): read_joint_quantity(v, "kg*m^2", "kg", f"{where}[{k!r}]") for k, v in value.items()
            }
            numbers: list[float] = list(items.values())
        elif isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise InputError(
                f"{where}: got {value!r}; expected a number [kg*m^2 or kg], a string with units or a "
                "{target regex: value} dict"
            )
        else:
            items, numbers = {}, [read_joint_quantity(value, "kg*m^2", "kg", where)]
        for number in numbers:
            if not 0.0 < number < math.inf:
                raise InputError(f"{where}: {number!r}; expected > 0 and finite [kg*m^2 or kg]")
        return items if isinstance(value, dict) else numbers[0]

    def resolved(self) -> PerformanceEnvelope:
        """The envelope this config describes (SI), validated."""
        if self.envelope is not None:
            from drive_envelope._src.datasheet.resolve import resolve_envelope

            if self.max_effort is not None:
                raise InputError(
                    f"{_CFG}: give either envelope or max_effort (and its three companions), not both"
                )
            return resolve_envelope(self.envelope, where=f"{_CFG}: envelope")
        if self.max_effort is None:
            raise InputError(f"{_CFG}: max_effort (or envelope) is required")
        values = read_envelope_values({name: getattr(self, name) for name in ENVELOPE_FIELDS}, _CFG)
        return PerformanceEnvelope(
            max_effort=float(values["max_effort"]),
            max_actuator_velocity=float(values["max_actuator_velocity"]),
            velocity_dependent_resistance=float(values["velocity_dependent_resistance"]),
            speed_effort_gradient=float(values["speed_effort_gradient"]),
        )

    def build(
        self, entity: Entity, target_ids: list[int], target_names: list[str]
    ) -> PerformanceEnvelopeActuator:
        kind: type[PerformanceEnvelopeActuator] = PerformanceEnvelopeActuator
        if self.implicit:
            kind = PerformanceEnvelopeImplicitActuator
        elif self.clip == "start_of_step":
            kind = StartOfStepEnvelopeActuator
        return kind(self, entity, target_ids, target_names)


def _time_step(value: object) -> float:
    """``physics_dt`` [s], finite and > 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < float(value) < math.inf:
        raise InputError(f"{_CFG}.physics_dt: got {value!r}; expected a time step > 0 and finite [s]")
    return float(value)


_HISTORY = ("response", "physics_dt", "velocity_prev", "effort_prev", "history")


class PerformanceEnvelopeActuator(IdealPdActuator[PerformanceEnvelopeActuatorCfg]):
    """mjlab's ideal PD actuator with PhysX's end-of-step clip (``clip="end_of_step"``; fusable).

    Per-target tensors ``(num_envs, num_targets)``: mjlab's ``stiffness``, ``damping``,
    ``force_limit``, the four envelope parameters, which :meth:`set_envelope` changes per
    environment (domain randomization; in place, so a fused group sees it), and the clip's
    ``response`` [1/(kg*m^2) or 1/kg], ``physics_dt`` [s] and last-step history
    (``velocity_prev`` [rad/s or m/s], ``effort_prev`` [N*m or N], ``history``: 1 where a step
    was recorded since the last reset).
    """

    param_names = (*IdealPdActuator.param_names, *ENVELOPE_FIELDS, *_HISTORY)

    @staticmethod
    def control_law(params: dict[str, torch.Tensor], cmd: ActuatorCmd) -> torch.Tensor:
        """The effort [N*m or N]: PhysX's clamp of clip(PD + tau_ff, +-force_limit) at the end-of-step v.

        The free end-of-step velocity is ``v + (v - velocity_prev - response*dt*effort_prev)`` where
        ``history`` is 1, else ``v``.
        """
        torque = pd_torque(params["stiffness"], params["damping"], cmd)
        limit = params["force_limit"]
        torque = torch.clamp(torque, -limit, limit)
        envelope = EnvelopeTensors(**{name: params[name] for name in ENVELOPE_FIELDS})
        history = (params["velocity_prev"], params["effort_prev"], params["history"])
        return end_of_step_law(envelope, torque, cmd.vel, params["response"], params["physics_dt"], history)

    def __init__(
        self,
        cfg: PerformanceEnvelopeActuatorCfg,
        entity: Entity,
        target_ids: list[int],
        target_names: list[str],
    ) -> None:
        super().__init__(cfg, entity, target_ids, target_names)
        self.envelope = cfg.resolved()
        """The configured envelope (SI)."""
        for name in (*ENVELOPE_FIELDS, *_HISTORY):
            setattr(self, name, None)
        self.response_source: str | None = None
        """Where ``response`` comes from: ``"effective_inertia"``, ``"model"`` (the first keyframe's) or
        ``"mass_matrix"`` (MJWarp's, every step); end of step only."""
        self._data: Any = None
        self._mass_matrix: Any = None
        self._dofs: Any = None
        self._steps = 0

    def initialize(self, mj_model: Any, model: Any, data: Any, device: str) -> None:
        super().initialize(mj_model, model, data, device)
        shape = (data.nworld, len(self._target_names))
        for name in ENVELOPE_FIELDS:
            value = getattr(self.envelope, name)
            setattr(self, name, torch.full(shape, value, dtype=torch.float, device=device))
        step = _time_step(self.cfg.physics_dt if self.cfg.physics_dt is not None else mj_model.opt.timestep)
        self.physics_dt = torch.full(shape, step, dtype=torch.float, device=device)
        self.velocity_prev = torch.zeros(shape, dtype=torch.float, device=device)
        self.effort_prev = torch.zeros(shape, dtype=torch.float, device=device)
        self.history = torch.zeros(shape, dtype=torch.float, device=device)
        self._velocity_last = torch.zeros(shape, dtype=torch.float, device=device)
        self._known_last = torch.zeros(shape, dtype=torch.float, device=device)
        self._data = data
        self.response = torch.full(shape, 1.0, dtype=torch.float, device=device)
        if self.cfg.implicit:
            return
        inertia = self.cfg.inertia_values()
        if inertia is not None:
            self.response[:] = torch.tensor(self._per_target(inertia), device=device).reciprocal()
            self.response_source = "effective_inertia"
            return
        from drive_envelope._src.adapters.mjlab.response import MassMatrixResponse, model_response

        dofs = [int(i) for i in self.entity.indexing.joint_v_adr[self.target_ids].tolist()]
        self.response[:] = torch.tensor(
            model_response(mj_model, dofs, f"{_CFG}.effective_inertia"), device=device
        )
        if self.cfg.effective_inertia == "model":
            self.response_source = "model"  # the keyframe's response, fixed: no per-step cost
            return
        self._mass_matrix = MassMatrixResponse.shared(self.entity, mj_model, device)
        self._dofs = torch.tensor(dofs, dtype=torch.long, device=device)
        self._steps = 0
        self.response_source = "mass_matrix"

    def _per_target(self, inertia: float | dict[str, float]) -> list[float]:
        """The effective inertia of each target [kg*m^2 or kg]: one number, or the regex that names it."""
        import re

        if not isinstance(inertia, dict):
            return [inertia] * len(self._target_names)
        values = []
        for name in self._target_names:
            found = [value for key, value in inertia.items() if re.fullmatch(key, name)]
            if len(found) != 1:
                what = "is not named" if not found else "is named by more than one key"
                raise InputError(
                    f"{_CFG}.effective_inertia: target {name!r} {what}; expected one key per target "
                    f"[kg*m^2 or kg] (got {self.cfg.effective_inertia!r})"
                )
            values.append(found[0])
        return values

    def update(self, dt: float) -> None:
        """After each physics step: record the step for the next free-velocity estimate, refresh ``response``.

        ``velocity_prev`` becomes the velocity the step started from, ``effort_prev`` the effort MuJoCo
        applied (``data.actuator_force``), and with the model as source ``response`` becomes
        ``(M^-1)_ii`` of MJWarp's ``data.M`` (the mass matrix of the step's start configuration).
        """
        super().update(dt)
        if self._data is None or self.cfg.implicit or self.cfg.clip != "end_of_step":
            return
        state = self.entity.data
        if self.cfg.transmission_type == TransmissionType.TENDON:
            velocity = state.tendon_vel[:, self.target_ids]
        else:
            velocity = state.joint_vel[:, self.target_ids]
        self.velocity_prev.copy_(self._velocity_last)
        self._velocity_last.copy_(velocity)
        self.effort_prev.copy_(self._data.actuator_force[:, self.global_ctrl_ids])
        self.history.copy_(self._known_last)
        self._known_last.fill_(1.0)
        if self._mass_matrix is not None:
            self._steps += 1
            diagonal = self._mass_matrix.diagonal(self._data.M, self._steps)[:, self._dofs]
            # a world whose M failed (NaN) keeps its last response: no NaN reaches the clip
            good = torch.isfinite(diagonal) & (diagonal > 0.0)
            self.response.copy_(torch.where(good, diagonal.to(self.response.dtype), self.response))

    def reset(self, env_ids: torch.Tensor | slice | None = None) -> None:
        """Reset as mjlab does; these environments forget their last steps (a reset moves them)."""
        super().reset(env_ids)
        if self.history is not None:
            rows = slice(None) if env_ids is None else env_ids
            self.history[rows] = 0.0
            self._known_last[rows] = 0.0

    def set_envelope(self, env_ids: torch.Tensor | slice, envelope: PerformanceEnvelope | str) -> None:
        """Give these environments (all targets of this group) another envelope, from the next step.

        Args:
            env_ids: Environment indices (or a slice).
            envelope: An envelope, envelope/datasheet file or catalog name.
        """
        from drive_envelope._src.datasheet.resolve import resolve_envelope

        env = resolve_envelope(envelope, where="set_envelope: argument 'envelope'")
        for name in ENVELOPE_FIELDS:
            getattr(self, name)[env_ids] = getattr(env, name)


class StartOfStepEnvelopeActuator(PerformanceEnvelopeActuator):
    """``clip="start_of_step"``: the envelope's limit at the current velocity (runs away at the line).

    Its own type, so mjlab fuses it apart from the end-of-step groups.
    """

    param_names = (*IdealPdActuator.param_names, *ENVELOPE_FIELDS)

    @staticmethod
    def control_law(params: dict[str, torch.Tensor], cmd: ActuatorCmd) -> torch.Tensor:
        """The effort [N*m or N]: clamp_effort(envelope, clip(PD + tau_ff, +-force_limit), v).

        PD = kp*(q* - q) + kd*(v* - v), clipped by the envelope at the current velocity v.
        """
        torque = pd_torque(params["stiffness"], params["damping"], cmd)
        limit = params["force_limit"]
        torque = torch.clamp(torque, -limit, limit)
        envelope = EnvelopeTensors(**{name: params[name] for name in ENVELOPE_FIELDS})
        return clamp_effort(envelope, torque, cmd.vel)


class PerformanceEnvelopeImplicitActuator(PerformanceEnvelopeActuator):
    """The implicit path: MJWarp's step solves the drive (``drive_envelope.mjwarp.attach``).

    Each target gets a ``<motor>`` without force or control range whose ``dynprm`` holds the
    drive's numbers (its gains included) and whose control is the position target; the velocity
    target and feed-forward effort of mjlab's command are not inputs of this path. Not fused (its
    ``compute`` is its own). Per-world envelopes: ``env.sim.expand_model_fields(("actuator_dynprm",))``,
    then ``drive_envelope.mjwarp.set_envelope(env.sim.wp_model, name, envelope, world=...)``.
    """

    def edit_spec(self, spec: Any, target_names: list[str]) -> None:
        from drive_envelope._src.adapters.mujoco.params import drive_dynprm

        super().edit_spec(spec, target_names)
        numbers = drive_dynprm(
            self.envelope, stiffness=self.cfg.stiffness, damping=self.cfg.damping, where=_CFG
        )
        for actuator in self._mjs_actuators:
            actuator.forcelimited = False  # the envelope limits the effort
            actuator.ctrllimited = False  # the control is a position target, not an effort
            actuator.dynprm[:] = numbers

    def initialize(self, mj_model: Any, model: Any, data: Any, device: str) -> None:
        import warp as wp

        from drive_envelope._src.adapters.mjwarp.model import attach

        super().initialize(mj_model, model, data, device)
        raw = getattr(model, "_struct", model)  # mjlab hands actuators its WarpBridge of the model
        attach(raw, mj_model, [int(i) for i in self.global_ctrl_ids.tolist()])
        target = wp.get_device(device)
        if target.is_cuda and wp.is_mempool_enabled(target):
            warnings.warn(
                "PerformanceEnvelopeActuatorCfg(implicit=True): mjlab captured its CUDA graphs before the "
                "drives were attached; call env.sim.create_graph() once after building the environment",
                stacklevel=2,
            )

    def compute(self, cmd: ActuatorCmd) -> torch.Tensor:
        """The control of each drive: its position target [rad or m]; MJWarp's step does the rest."""
        return cmd.position_target

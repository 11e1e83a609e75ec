"""mjlab actuators with the PhysX performance envelope as their effort limit.

:class:`PerformanceEnvelopeActuator` is an mjlab :class:`~mjlab.actuator.IdealPdActuator` (a
``<motor>`` per joint, torque computed in torch every physics step) whose clip is the envelope at
the current joint velocity: ``tau = clamp_effort(envelope, kp*(q* - q) + kd*(v* - v) + tau_ff, v)``,
explicit as every mjlab/Isaac Lab explicit actuator is. It keeps mjlab's shared ``compute`` and
declares its per-target tensors in ``param_names`` with a stateless ``control_law``, so mjlab fuses
every group of them into one batched evaluation.

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
from mjlab.actuator.actuator import ActuatorCmd
from mjlab.actuator.pd_actuator import pd_torque

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.envelope_values import read_envelope_values
from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors
from drive_envelope._src.kernels.torch_ops import clamp_effort

if TYPE_CHECKING:
    from mjlab.entity import Entity

__all__ = [
    "PerformanceEnvelopeActuator",
    "PerformanceEnvelopeActuatorCfg",
    "PerformanceEnvelopeImplicitActuator",
]

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

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("stiffness", "damping"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, (int, float)) and 0.0 <= value < math.inf):
                raise InputError(f"{_CFG}: {name} = {value!r}; expected a number >= 0 and finite")
        self.resolved()  # one-line errors now, not at the first step

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
        kind = PerformanceEnvelopeImplicitActuator if self.implicit else PerformanceEnvelopeActuator
        return kind(self, entity, target_ids, target_names)


class PerformanceEnvelopeActuator(IdealPdActuator[PerformanceEnvelopeActuatorCfg]):
    """mjlab's ideal PD actuator with the envelope at the current velocity as its clip (fusable).

    Per-target tensors ``(num_envs, num_targets)``: mjlab's ``stiffness``, ``damping``,
    ``force_limit``, and the four envelope parameters, which :meth:`set_envelope` changes per
    environment (domain randomization; in place, so a fused group sees it).
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
        for name in ENVELOPE_FIELDS:
            setattr(self, name, None)

    def initialize(self, mj_model: Any, model: Any, data: Any, device: str) -> None:
        super().initialize(mj_model, model, data, device)
        shape = (data.nworld, len(self._target_names))
        for name in ENVELOPE_FIELDS:
            value = getattr(self.envelope, name)
            setattr(self, name, torch.full(shape, value, dtype=torch.float, device=device))

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

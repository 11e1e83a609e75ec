"""An Isaac Lab style explicit actuator on PyTorch: a PD law whose effort is clamped by the envelope.

Isaac Lab's explicit actuators (``IdealPDActuator``, ``DCMotor``) compute, for every environment and
joint, ``effort = stiffness*(q_target - q) + damping*(v_target - v) + effort_target`` and then clip
it; :class:`EnvelopeActuator` does the same with the PhysX envelope as the clip (at the current
velocity, as every explicit actuator does). Shapes are ``(num_envs, num_joints)``; parameters are
per joint (or scalars).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors, resolve_dtype
from drive_envelope._src.kernels.torch_ops import clamp_effort
from drive_envelope._src.values import read_envelope_value

if TYPE_CHECKING:
    import torch

__all__ = ["EnvelopeActuator", "EnvelopeActuatorCfg", "JointTargets"]

PerJoint = float | str | Sequence[float | str]


class JointTargets(NamedTuple):
    """Targets of one control step, named like Isaac Lab's ``ArticulationActions`` (any may be None).

    Each is a tensor of shape ``(num_envs, num_joints)``.
    """

    joint_positions: Any = None
    """Target joint positions [rad or m]."""
    joint_velocities: Any = None
    """Target joint velocities [rad/s or m/s]."""
    joint_efforts: Any = None
    """Feed-forward efforts [N*m or N]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class EnvelopeActuatorCfg:
    """Configuration of :class:`EnvelopeActuator`; every value is a scalar or one value per joint.

    Envelope values are SI numbers or strings with units (``"300 rpm"``); gains are SI numbers.
    """

    stiffness: float | Sequence[float]
    """PD stiffness [N*m/rad or N/m], ``>= 0``."""
    damping: float | Sequence[float]
    """PD damping [N*m*s/rad or N*s/m], ``>= 0``."""
    max_effort: PerJoint
    """Effort cap at zero velocity [N*m or N], ``>= 0``, finite."""
    max_actuator_velocity: PerJoint = math.inf
    """Speed cap at zero effort [rad/s or m/s], ``>= 0`` (``inf``: none)."""
    velocity_dependent_resistance: PerJoint = 0.0
    """Effort lost per unit speed R [N*m*s/rad or N*s/m], ``>= 0``."""
    speed_effort_gradient: PerJoint = 0.0
    """Speed lost per unit effort G [(rad/s)/(N*m) or (m/s)/N], ``>= 0``."""

    def __post_init__(self) -> None:
        for name in ("stiffness", "damping", *ENVELOPE_FIELDS):
            self.values(name)  # validates

    def values(self, name: str) -> np.ndarray:
        """The SI values of field ``name`` as a 1-D float64 array (one per joint, or one for all).

        Raises:
            InputError: a negative, NaN or not allowed infinite value, or a wrong unit.
        """
        raw = getattr(self, name)
        items = [raw] if isinstance(raw, (str, int, float)) else list(raw)
        where = f"EnvelopeActuatorCfg.{name}"
        if name in ENVELOPE_FIELDS:
            array = np.array([read_envelope_value(v, name, where) for v in items], dtype=np.float64)
        else:
            if any(isinstance(v, (str, bool)) or not isinstance(v, (int, float)) for v in items):
                raise InputError(
                    f"{where}: expected SI numbers [N*m/rad, N*m*s/rad or N/m, N*s/m], got {raw!r}"
                )
            array = np.array(items, dtype=np.float64)
        finite_ok = name == "max_actuator_velocity"
        bad = np.isnan(array) | (array < 0.0) | (np.isinf(array) & (not finite_ok))
        if array.size == 0 or np.any(bad):
            shown = array[bad][0] if np.any(bad) else raw
            raise InputError(
                f"{where}: got {shown!r}; expected values >= 0{'' if finite_ok else ' and finite'}"
            )
        return array


class EnvelopeActuator:
    """PD actuator with the PhysX envelope as its effort clip, shaped like Isaac Lab's explicit actuators.

    ``compute(targets, joint_pos, joint_vel)`` returns the applied effort and keeps
    :attr:`computed_effort` (the PD law) and :attr:`applied_effort` (after the clip), as Isaac Lab's
    actuators do. Example::

        act = EnvelopeActuator(EnvelopeActuatorCfg(stiffness=40.0, damping=2.0, max_effort=12.0,
                               max_actuator_velocity="300 rpm", speed_effort_gradient=0.5),
                               num_envs=4096, num_joints=12, device="cuda:0")
        efforts = act.compute(JointTargets(joint_positions=q_des), q, qd)
    """

    def __init__(
        self,
        cfg: EnvelopeActuatorCfg,
        *,
        num_envs: int,
        num_joints: int,
        device: Any = "cpu",
        dtype: Any = None,
    ) -> None:
        """Build the per-joint parameter tensors.

        Args:
            cfg: Gains and envelope (scalars or one value per joint).
            num_envs: Number of environments (rows).
            num_joints: Number of joints driven by this actuator (columns).
            device: Torch device of every tensor.
            dtype: Float dtype (default float32).
        """
        import torch

        if num_envs < 1 or num_joints < 1:
            raise InputError(
                f"EnvelopeActuator: num_envs and num_joints must be >= 1, got {num_envs}, {num_joints}"
            )
        self.cfg = cfg
        self.num_envs, self.num_joints = num_envs, num_joints
        kind = resolve_dtype(dtype)
        self._params = {
            name: self._per_joint(cfg, name, torch.device(device), kind)
            for name in ("stiffness", "damping", *ENVELOPE_FIELDS)
        }
        self.envelope = EnvelopeTensors(**{name: self._params[name] for name in ENVELOPE_FIELDS})
        """The envelope per joint, tensors of shape ``(1, num_joints)``."""
        self.computed_effort = torch.zeros(num_envs, num_joints, dtype=kind, device=device)
        """PD effort before the clip [N*m or N], ``(num_envs, num_joints)``."""
        self.applied_effort = torch.zeros_like(self.computed_effort)
        """Effort after the envelope clip [N*m or N], ``(num_envs, num_joints)``."""

    def _per_joint(
        self, cfg: EnvelopeActuatorCfg, name: str, device: torch.device, kind: torch.dtype
    ) -> torch.Tensor:
        import torch

        values = cfg.values(name)
        if values.size not in (1, self.num_joints):
            raise InputError(f"EnvelopeActuatorCfg.{name}: {values.size} values for {self.num_joints} joints")
        row = np.broadcast_to(values, (self.num_joints,))
        return torch.as_tensor(row.copy(), dtype=kind, device=device).reshape(1, self.num_joints)

    def reset(self, env_ids: Sequence[int] | None = None) -> None:
        """Reset per-environment state: none, the actuator is stateless (kept for Isaac Lab's interface)."""

    def compute(self, targets: Any, joint_pos: torch.Tensor, joint_vel: torch.Tensor) -> torch.Tensor:
        """PD effort towards ``targets``, clipped by the envelope at ``joint_vel``.

        Args:
            targets: Object with ``joint_positions``, ``joint_velocities``, ``joint_efforts`` (any
                may be None), e.g. :class:`JointTargets` or Isaac Lab's ``ArticulationActions``.
            joint_pos: Joint positions [rad or m], ``(num_envs, num_joints)``.
            joint_vel: Joint velocities [rad/s or m/s], ``(num_envs, num_joints)``.

        Returns:
            The applied effort [N*m or N], ``(num_envs, num_joints)``.
        """
        import torch

        p = self._params
        effort = torch.zeros_like(self.computed_effort)
        target_pos = getattr(targets, "joint_positions", None)
        target_vel = getattr(targets, "joint_velocities", None)
        feedforward = getattr(targets, "joint_efforts", None)
        if target_pos is not None:
            effort.addcmul_(p["stiffness"], target_pos - joint_pos)
        # Isaac Lab's PD law damps towards the target velocity, or towards rest when there is none
        effort.addcmul_(p["damping"], (target_vel - joint_vel) if target_vel is not None else -joint_vel)
        if feedforward is not None:
            effort.add_(feedforward)
        self.computed_effort = effort
        self.applied_effort = clamp_effort(self.envelope, effort, joint_vel)
        return self.applied_effort

"""Each target's unit response ``(M^-1)_ii`` for the mjlab end-of-step clip, from MuJoCo or MJWarp.

Two sources, both with the joint's armature (part of MuJoCo's ``M``):

* at build time, the compiled ``MjModel`` at its first keyframe (mjlab's ``init_state``) or
  ``qpos0``: ``drive_envelope.mujoco.effective_inertia`` (MuJoCo's ``mj_solveM``);
* every physics step, MJWarp's own mass matrix ``data.M`` (``(nworld, nC)``, MuJoCo's CSR lower
  triangle, ``M_rowadr``/``M_colind``), filled into a dense ``(nworld, nv, nv)`` tensor and inverted
  by a batched Cholesky (``torch.linalg.cholesky`` + ``torch.cholesky_inverse``). After ``mjwarp.step``
  that ``M`` is the one of the step's start configuration: the response lags the pose by one step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import torch


def model_response(mj_model: Any, dofs: list[int], where: str) -> list[float]:
    """``(M^-1)_ii`` [1/(kg*m^2) or 1/kg] at the model's first keyframe (else ``qpos0``) for ``dofs``."""
    from drive_envelope._src.adapters.mujoco.inertia import effective_inertia

    joints = [int(mj_model.dof_jntid[dof]) for dof in dofs]
    try:
        inertia = effective_inertia(mj_model, joints=joints)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    return [1.0 / value for value in inertia.values()]


class MassMatrixResponse:
    """``(M^-1)_ii`` of every DOF from MJWarp's ``data.M`` of every world, shared by an entity's groups.

    Each actuator group asks with its own count of physics steps; the first to ask for a step
    computes the whole diagonal, the others of that step reuse it (mjlab calls every actuator's
    ``update`` once per step), so the cost is per robot and step, not per group.
    """

    def __init__(self, mj_model: Any, device: str) -> None:
        """Index maps from the model's CSR layout (host, once).

        Args:
            mj_model: The compiled model MJWarp was built from.
            device: Where MJWarp's data lives.
        """
        import torch

        rownnz = np.asarray(mj_model.M_rownnz, dtype=np.int64)
        rows = np.repeat(np.arange(mj_model.nv), rownnz)
        cols = np.asarray(mj_model.M_colind, dtype=np.int64)
        if rows.size != cols.size:
            raise InputError(f"mass-matrix response: M_rownnz sums to {rows.size}, M_colind has {cols.size}")
        self._rows = torch.as_tensor(rows, device=device)
        self._cols = torch.as_tensor(cols, device=device)
        self._nv = int(mj_model.nv)
        self._step = -1
        self._diagonal: Any = None

    def diagonal(self, packed: torch.Tensor, step: int) -> torch.Tensor:
        """``(M^-1)_ii`` of every DOF ``(nworld, nv)`` [1/(kg*m^2) or 1/kg]; NaN in a world whose M fails.

        Args:
            packed: MJWarp's ``data.M`` as a tensor, ``(nworld, nC)``.
            step: The asking group's physics-step count (a new count recomputes).
        """
        import torch

        if step != self._step:
            dense = packed.new_zeros((packed.shape[0], self._nv, self._nv))
            dense[:, self._rows, self._cols] = packed
            dense[:, self._cols, self._rows] = packed  # the upper triangle mirrors the lower
            factor, info = torch.linalg.cholesky_ex(dense)
            # M^-1 = L^-T L^-1: (M^-1)_ii is the squared norm of column i of L^-1 (one triangular solve)
            eye = torch.eye(self._nv, dtype=dense.dtype, device=dense.device).expand_as(dense)
            inverse_factor = torch.linalg.solve_triangular(factor, eye, upper=False)
            diagonal = inverse_factor.square().sum(dim=-2)
            self._diagonal = torch.where((info == 0).unsqueeze(-1), diagonal, torch.nan)
            self._step = step
        return self._diagonal  # type: ignore[no-any-return]

    @staticmethod
    def shared(entity: Any, mj_model: Any, device: str) -> MassMatrixResponse:
        """The entity's one instance (made by its first group that needs it)."""
        found = getattr(entity, "_drive_envelope_mass_response", None)
        if not isinstance(found, MassMatrixResponse):
            found = MassMatrixResponse(mj_model, device)
            entity._drive_envelope_mass_response = found  # one per robot: its groups share the solve
        return found

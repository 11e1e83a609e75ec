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

__all__ = ["MassMatrixResponse", "model_response"]


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
    """``(M^-1)_ii`` of some DOFs from MJWarp's ``data.M`` of every world, on the data's device."""

    def __init__(self, mj_model: Any, dofs: list[int], device: str) -> None:
        """Index maps from the model's CSR layout (host, once).

        Args:
            mj_model: The compiled model MJWarp was built from.
            dofs: The DOF addresses whose response is wanted, in order.
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
        self._dofs = torch.as_tensor(dofs, dtype=torch.long, device=device)
        self._nv = int(mj_model.nv)

    def __call__(self, packed: torch.Tensor, out: torch.Tensor) -> None:
        """Write ``(M^-1)_ii`` of the DOFs into ``out`` ``(nworld, len(dofs))`` [1/(kg*m^2) or 1/kg].

        Args:
            packed: MJWarp's ``data.M`` as a tensor, ``(nworld, nC)``.
            out: The response buffer, written in place (a fused group's view sees it).
        """
        import torch

        dense = packed.new_zeros((packed.shape[0], self._nv, self._nv))
        dense[:, self._rows, self._cols] = packed
        dense[:, self._cols, self._rows] = packed  # the upper triangle mirrors the lower
        factor, info = torch.linalg.cholesky_ex(dense)
        inverse = torch.cholesky_inverse(factor)
        diagonal = torch.diagonal(inverse, dim1=-2, dim2=-1)[:, self._dofs]
        # a world whose M is not positive definite (info > 0) keeps its last response: no NaN reaches the clip
        good = (info == 0).unsqueeze(-1) & torch.isfinite(diagonal) & (diagonal > 0)
        out.copy_(torch.where(good, diagonal.to(out.dtype), out))

"""The envelope in the PhysX tensor API's order, for Isaac Lab's ``root_physx_view`` at run time.

omni.physics.tensors' ``ArticulationView.get/set_dof_drive_model_properties`` (and ovphysx's
``ARTICULATION_DOF_DRIVE_MODEL`` binding) hold three values per DOF, in this order::

    [..., 0] speedEffortGradient   [..., 1] maxActuatorVelocity   [..., 2] velocityDependentResistance

which is not the order of the C++ constructor ``PxPerformanceEnvelope(maxEffort,
maxActuatorVelocity, velocityDependentResistance, speedEffortGradient)``. maxEffort is not in that
tensor: it is the drive's max force (``set_dof_max_forces``, Isaac Lab's
``write_joint_effort_limit_to_sim``). The tensor API writes PhysX's own values: SI joint side,
radians for angular DOFs, on the metre-kilogram stages Isaac Lab uses (no degrees, unlike USD).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors

DRIVE_MODEL_ORDER = ("speed_effort_gradient", "max_actuator_velocity", "velocity_dependent_resistance")
"""The three envelope values of the PhysX tensor API's drive-model tensor, last axis, in order."""


def _tensors(params: Any) -> EnvelopeTensors:
    if isinstance(params, EnvelopeTensors):
        return params
    if isinstance(params, PerformanceEnvelope) or (
        isinstance(params, Sequence) and all(isinstance(p, PerformanceEnvelope) for p in params)
    ):
        return EnvelopeTensors.from_envelopes(params, dtype="float32")
    raise InputError(
        "params: expected an EnvelopeTensors, a PerformanceEnvelope or a list of them, got "
        f"{type(params).__name__}"
    )


def drive_model_properties(params: Any) -> Any:
    """The drive-model tensor of envelopes: ``(..., 3)`` float32, in :data:`DRIVE_MODEL_ORDER`.

    Args:
        params: :class:`EnvelopeTensors` (any broadcast shape, e.g. ``(num_envs, num_joints)``), a
            :class:`PerformanceEnvelope` or a list of them (one per DOF).

    Returns:
        A float32 tensor on the parameters' device, the last axis (G, v_max, R) [SI].
    """
    import torch

    tensors = _tensors(params)
    columns = torch.broadcast_tensors(*(getattr(tensors, name) for name in DRIVE_MODEL_ORDER))
    return torch.stack(columns, dim=-1).to(torch.float32)


def envelope_from_drive_model_properties(properties: Any, max_forces: Any) -> EnvelopeTensors:
    """Read back a drive-model tensor and the DOFs' max forces as envelope tensors (the inverse).

    Args:
        properties: ``(..., 3)`` values in :data:`DRIVE_MODEL_ORDER` (a tensor or array).
        max_forces: ``(...)`` the drives' max forces, i.e. max_effort [N*m or N].

    Raises:
        InputError: a last axis that is not 3, or shapes that do not match.
    """
    import torch

    values = torch.as_tensor(properties)
    if values.ndim < 1 or values.shape[-1] != 3:
        raise InputError(
            f"properties: expected a last axis of 3 (G, v_max, R), got shape {tuple(values.shape)}"
        )
    forces = torch.as_tensor(max_forces, dtype=values.dtype, device=values.device)
    if tuple(forces.shape) != tuple(values.shape[:-1]):
        raise InputError(f"max_forces: shape {tuple(forces.shape)}; expected {tuple(values.shape[:-1])}")
    named = {name: values[..., k] for k, name in enumerate(DRIVE_MODEL_ORDER)}
    return EnvelopeTensors(max_effort=forces, **named)


def write_envelope_to_sim(
    articulation: Any, params: Any, *, joint_ids: Any = None, env_ids: Any = None
) -> None:
    """Write envelopes into a running Isaac Lab articulation, the PhysX tensor API's way.

    max_effort goes through ``articulation.write_joint_effort_limit_to_sim`` (PhysX's drive max
    force, which is the envelope's maxEffort, and Isaac Lab's own buffer), the other three through
    ``articulation.root_physx_view.set_dof_drive_model_properties`` in :data:`DRIVE_MODEL_ORDER`.
    Only the envelope values of the selected environments and joints change.

    Args:
        articulation: An Isaac Lab ``Articulation`` (initialised: it has ``root_physx_view``).
        params: :class:`EnvelopeTensors` of shape ``(len(env_ids), len(joint_ids))`` (or one that
            broadcasts to it), a :class:`PerformanceEnvelope` or a list (one per joint).
        joint_ids: Joint indices of the articulation (None: all).
        env_ids: Environment indices (None: all).
    """
    import torch

    tensors = _tensors(params)
    view = articulation.root_physx_view
    device = articulation.device
    envs = (
        torch.arange(view.count, device=device)
        if env_ids is None
        else torch.as_tensor(env_ids, device=device)
    )
    joints = slice(None) if joint_ids is None else torch.as_tensor(joint_ids, device=device)
    articulation.write_joint_effort_limit_to_sim(
        tensors.max_effort.to(device) if tensors.max_effort.ndim else float(tensors.max_effort),
        joint_ids=None if joint_ids is None else joints,
        env_ids=None if env_ids is None else envs,
    )
    current = view.get_dof_drive_model_properties()
    data = torch.as_tensor(current).to(device).clone()
    rows = envs if isinstance(joints, slice) else envs[:, None]
    data[rows, joints] = drive_model_properties(tensors).to(device)
    # as Isaac Lab writes its other DOF properties: CPU tensors, the environments as indices
    view.set_dof_drive_model_properties(data.cpu(), indices=envs.to(torch.int32).cpu())

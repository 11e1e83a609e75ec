"""Run-time functions on an articulation's envelope actuators: the event term and the mass-matrix response.

``randomize_actuator_envelope`` is an Isaac Lab event term that randomizes the envelope per
environment. It does for the envelope what Isaac Lab's ``randomize_actuator_gains``
(``isaaclab/envs/mdp/events.py``) does for the gains: for each :class:`PerformanceEnvelopeActuator`
of the asset it takes the configured values of the selected environments and joints
(``default_*``), applies the operation with a sample of the distribution and writes the result
into the actuator's tensor (``actuator.speed_effort_gradient[env_ids] = ...``), which the next
``compute`` reads. Values are clipped at 0 from below (a negative envelope value is invalid), and
``inf`` stays ``inf``. Use it as a function-style term::

    EventTermCfg(func=randomize_actuator_envelope, mode="reset", params={
        "asset_cfg": SceneEntityCfg("robot", joint_names=[".*_KFE"]),
        "speed_effort_gradient_distribution_params": (0.8, 1.2), "operation": "scale"})

``set_response_from_mass_matrix`` gives the end-of-step clip each joint's unit response from the
articulation's mass matrix. Both import Isaac Lab, torch and the actuator class when they run.
"""

from __future__ import annotations

from typing import Any

from drive_envelope._src.errors import InputError

_OPERATIONS = ("abs", "add", "scale")
_DISTRIBUTIONS = ("uniform", "log_uniform", "gaussian")


def _envelope_actuators(articulation: Any) -> list[Any]:
    """The articulation's :class:`PerformanceEnvelopeActuator` groups (this imports Isaac Lab)."""
    from drive_envelope._src.adapters.isaaclab.actuator_classes import PerformanceEnvelopeActuator

    return [a for a in articulation.actuators.values() if isinstance(a, PerformanceEnvelopeActuator)]


def _columns(actuator: Any, joint_ids: Any, device: Any) -> Any:
    """Columns of the actuator's tensors that the asset cfg selects (a slice for all of them)."""
    import torch

    if isinstance(joint_ids, slice):
        return slice(None)
    wanted = torch.as_tensor(joint_ids, device=device)
    indices = actuator.joint_indices
    if isinstance(indices, slice):  # the actuator drives every joint: columns are joint ids
        return wanted
    return torch.nonzero(torch.isin(indices.to(device), wanted)).view(-1)


def randomize_actuator_envelope(
    env: Any,
    env_ids: Any,
    asset_cfg: Any,
    max_effort_distribution_params: tuple[float, float] | None = None,
    max_actuator_velocity_distribution_params: tuple[float, float] | None = None,
    velocity_dependent_resistance_distribution_params: tuple[float, float] | None = None,
    speed_effort_gradient_distribution_params: tuple[float, float] | None = None,
    operation: str = "scale",
    distribution: str = "uniform",
) -> None:
    """Randomize the envelope of the asset's ``PerformanceEnvelopeActuator`` groups for ``env_ids``.

    Args:
        env: The Isaac Lab environment (``env.scene[asset_cfg.name]`` is the articulation).
        env_ids: Environments to randomize: indices, a slice, or None (all).
        asset_cfg: ``SceneEntityCfg`` naming the asset and its joints (``joint_ids``).
        max_effort_distribution_params: ``(low, high)`` (or ``(mean, std)``) for max_effort, Isaac
            Lab's effort limit (2.3 ``effort_limit``, 3.0 ``actuator_effort_limit``) [N*m or N, or a
            factor for ``"scale"``]; None leaves it.
        max_actuator_velocity_distribution_params: The same for max_actuator_velocity [rad/s or m/s].
        velocity_dependent_resistance_distribution_params: The same for R [N*m*s/rad or N*s/m].
        speed_effort_gradient_distribution_params: The same for G [(rad/s)/(N*m) or (m/s)/N].
        operation: ``"scale"`` (default value times the sample), ``"add"`` or ``"abs"`` (the sample).
        distribution: ``"uniform"``, ``"log_uniform"`` or ``"gaussian"``, Isaac Lab's samplers.

    Raises:
        InputError: an unknown operation or distribution, or parameters that are not two numbers.
    """
    import torch
    from isaaclab.utils import math as math_utils

    from drive_envelope._src.adapters.isaaclab.actuator import envelope_attributes

    if operation not in _OPERATIONS:
        raise InputError(
            f"randomize_actuator_envelope: operation = {operation!r}; expected one of {_OPERATIONS}"
        )
    if distribution not in _DISTRIBUTIONS:
        raise InputError(
            f"randomize_actuator_envelope: distribution = {distribution!r}; expected one of {_DISTRIBUTIONS}"
        )
    sample = getattr(math_utils, f"sample_{distribution}")
    ranges = dict(
        zip(
            envelope_attributes(),
            (
                max_effort_distribution_params,
                max_actuator_velocity_distribution_params,
                velocity_dependent_resistance_distribution_params,
                speed_effort_gradient_distribution_params,
            ),
            strict=True,
        )
    )
    for attribute, params in ranges.items():
        if params is not None and (len(params) != 2 or not all(isinstance(p, (int, float)) for p in params)):
            raise InputError(
                f"randomize_actuator_envelope: {attribute} parameters {params!r}; expected (a, b)"
            )
    for actuator in _envelope_actuators(env.scene[asset_cfg.name]):
        device = actuator.max_effort.device
        every = torch.arange(actuator.max_effort.shape[0], device=device)
        # None and slice(None) (what EventManager.apply passes without env_ids) both mean every env
        rows = every[env_ids] if isinstance(env_ids, slice) else every if env_ids is None else env_ids
        rows = torch.as_tensor(rows, device=device)
        columns = _columns(actuator, asset_cfg.joint_ids, device)
        for attribute, params in ranges.items():
            if params is None:
                continue
            default = getattr(actuator, f"default_{attribute}")[rows][:, columns]
            drawn = sample(*params, tuple(default.shape), device=device)
            value = {"abs": drawn, "add": default + drawn, "scale": default * drawn}[operation]
            current = getattr(actuator, attribute)
            block = current[rows]
            block[:, columns] = torch.where(torch.isinf(default), default, value.clamp_min(0.0))
            current[rows] = block


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

    matrices = articulation.root_physx_view.get_generalized_mass_matrices()
    diagonal = torch.diagonal(torch.linalg.inv(matrices), dim1=-2, dim2=-1)
    offset = diagonal.shape[-1] - int(articulation.num_joints)
    if offset not in (0, 6):
        raise InputError(
            f"set_response_from_mass_matrix: mass matrices of size {diagonal.shape[-1]} for "
            f"{articulation.num_joints} joints; expected the joint count, or it plus 6 (floating base)"
        )
    for actuator in _envelope_actuators(articulation):
        ids = actuator.joint_indices
        columns = torch.arange(articulation.num_joints, device=diagonal.device)[ids] + offset
        actuator.response[:] = diagonal[:, columns].to(actuator.response)
        actuator.response_source = "mass_matrix"

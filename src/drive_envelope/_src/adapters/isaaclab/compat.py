"""Where Isaac Lab 2.3 and 3.0 differ, in one place: the adapter asks :func:`api` and nothing else.

Read from the two wheels (``isaaclab==2.3.2.post1``, ``isaaclab==3.0.0``, ``isaaclab/actuators``):

=========================================  ==============================  ===============================
                                           2.3                             3.0
=========================================  ==============================  ===============================
explicit actuator's effort clip (cfg and   ``effort_limit``                ``actuator_effort_limit``
tensor on the actuator)                                                    (``effort_limit`` deprecated)
actuator's speed limit (cfg and tensor)    ``velocity_limit``              ``actuator_velocity_limit``
``IdealPDActuator.__init__`` keywords      stiffness, damping, armature,   stiffness, damping,
                                           friction, dynamic_friction,     actuator_effort_limit,
                                           viscous_friction, effort_limit, actuator_velocity_limit (and
                                           velocity_limit                  the deprecated effort_limit,
                                                                           velocity_limit)
``_clip_effort``                           ``(effort)``                    ``(effort, joint_vel)``
implicit cfg fields that become PhysX's    ``effort_limit_sim``,           ``joint_effort_limit``,
drive max force (the envelope's maxEffort) ``effort_limit``                ``effort_limit_sim``,
                                                                           ``effort_limit``
implicit cfg fields that cap the joint     ``velocity_limit_sim``          ``joint_velocity_limit``,
speed in the solver                                                        ``velocity_limit_sim``
=========================================  ==============================  ===============================

The API is told apart by the keywords of ``IdealPDActuator.__init__`` (what the adapter must pass),
not by a version string, so a 3.x that keeps those keywords keeps working. The actuator forwards
the keywords it is built with unchanged, so it takes exactly what its Isaac Lab passes.
"""

from __future__ import annotations

import functools
import inspect
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, kw_only=True, slots=True)
class IsaacLabApi:
    """The names one Isaac Lab API uses for what the adapter reads and writes."""

    name: str
    """The API's label in messages and docs: ``"2.3"`` or ``"3.0"``."""
    effort_limit: str
    """The explicit actuator's effort clip (max_effort): cfg field and ``(num_envs, num_joints)`` tensor."""
    velocity_limit: str
    """The actuator's speed limit, a cfg field and a tensor [rad/s or m/s] (not max_actuator_velocity)."""
    deprecated_effort_limits: tuple[str, ...]
    """Older cfg fields that Isaac Lab still reads as :attr:`effort_limit` (it warns)."""
    deprecated_velocity_limits: tuple[str, ...]
    """Older cfg fields that Isaac Lab still reads as :attr:`velocity_limit` (it warns)."""
    joint_effort_limits: tuple[str, ...]
    """Implicit cfg fields that Isaac Lab writes into PhysX's drive max force, newest first."""
    joint_velocity_limits: tuple[str, ...]
    """Implicit cfg fields that cap the joint's speed in the solver (PhysX's maxJointVelocity)."""
    clip_passes_velocity: bool
    """``IdealPDActuator.compute`` calls ``_clip_effort(effort, joint_vel)`` (else ``(effort)``)."""


ISAACLAB_2_3 = IsaacLabApi(
    name="2.3",
    effort_limit="effort_limit",
    velocity_limit="velocity_limit",
    deprecated_effort_limits=(),
    deprecated_velocity_limits=(),
    joint_effort_limits=("effort_limit_sim", "effort_limit"),
    joint_velocity_limits=("velocity_limit_sim",),
    clip_passes_velocity=False,
)
"""Isaac Lab 2.x (2.3.2 read)."""

ISAACLAB_3_0 = IsaacLabApi(
    name="3.0",
    effort_limit="actuator_effort_limit",
    velocity_limit="actuator_velocity_limit",
    deprecated_effort_limits=("effort_limit",),
    deprecated_velocity_limits=("velocity_limit",),
    joint_effort_limits=("joint_effort_limit", "effort_limit_sim", "effort_limit"),
    joint_velocity_limits=("joint_velocity_limit", "velocity_limit_sim"),
    clip_passes_velocity=True,
)
"""Isaac Lab 3.x (3.0.0 read)."""


@functools.cache
def api() -> IsaacLabApi:
    """The API of the installed Isaac Lab, from the keywords of ``IdealPDActuator.__init__``.

    Raises:
        ImportError: ``isaaclab.actuators`` cannot be imported.
    """
    from isaaclab.actuators import IdealPDActuator

    keywords = inspect.signature(IdealPDActuator.__init__).parameters
    return ISAACLAB_3_0 if "actuator_effort_limit" in keywords else ISAACLAB_2_3


def cfg_value(cfg: Any, current: str, deprecated: tuple[str, ...] = ()) -> Any:
    """A cfg's value under its current field name, else under a deprecated one still set (None: unset).

    Isaac Lab 3.0 moves a deprecated field into the current one when the actuator is built; reading
    both makes the answer the same before and after.
    """
    value = getattr(cfg, current, None)
    for name in deprecated:
        if value is None:
            value = getattr(cfg, name, None)
    return value

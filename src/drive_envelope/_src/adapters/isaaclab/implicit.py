"""The implicit path: PhysX applies the envelope in its solver, Isaac Lab sets it up once.

With an ``ImplicitActuatorCfg`` Isaac Lab hands the PD law to PhysX's drive. PhysX reads the
envelope from the robot's USD (``PhysxDrivePerformanceEnvelopeAPI``) and clamps the drive's effort
at the end-of-step velocity. Isaac Lab then writes each implicit actuator's limits into PhysX
(``Articulation._process_actuators_cfg``): ``effort_limit_sim`` through ``set_dof_max_forces``,
which is the envelope's maxEffort, and ``velocity_limit_sim`` through ``set_dof_max_velocities``,
PhysX's joint speed cap (``maxJointVelocity``), not max_actuator_velocity. With both left at
``None`` Isaac Lab takes them from the USD, so the authored envelope acts once and as authored
(``docs/usd.md``, "Isaac Lab" table). :func:`author_implicit_envelopes` writes the envelopes with
the USD adapter (a layer over the asset, as ``drive-envelope usd apply`` does) and returns that
``ImplicitActuatorCfg``; :func:`check_implicit_actuator` finds the settings of an existing cfg that
would override the envelope.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError

__all__ = ["ImplicitEnvelopeSetup", "author_implicit_envelopes", "check_implicit_actuator"]


@dataclass(frozen=True, kw_only=True, slots=True)
class ImplicitEnvelopeSetup:
    """What :func:`author_implicit_envelopes` wrote and the actuator cfg to use with it."""

    usd_path: Path
    """The written layer (or flat file): give it to the robot's ``UsdFileCfg(usd_path=...)``."""
    envelopes: dict[str, PerformanceEnvelope]
    """Envelope per joint name (the prim's name, which is Isaac Lab's joint name), SI."""
    actuator: Any
    """An Isaac Lab ``ImplicitActuatorCfg`` for those joints, limits left to the USD."""


def author_implicit_envelopes(
    asset: str | os.PathLike[str],
    joint_map: str | os.PathLike[str],
    output: str | os.PathLike[str],
    *,
    stiffness: float | Mapping[str, float] | None,
    damping: float | Mapping[str, float] | None,
    flatten: bool = False,
) -> ImplicitEnvelopeSetup:
    """Author the envelopes of ``joint_map`` over ``asset`` and return the matching implicit actuator.

    Args:
        asset: The robot's USD file (it is not edited).
        joint_map: A map file of joint pattern -> envelope source, or a shipped map's name
            (``usd apply --map``'s format: ``docs/usd.md``).
        output: The layer to write (``.usda``/``.usd``/``.usdc``), atomically and checked.
        stiffness: PD stiffness for PhysX's drive [N*m/rad or N/m], Isaac Lab's float or
            ``{joint regex: value}``; None keeps the USD's.
        damping: PD damping [N*m*s/rad or N*s/m], the same way.
        flatten: Write the whole composed stage as one file instead of a layer.

    Returns:
        The written file, the envelope per joint and an ``ImplicitActuatorCfg`` with
        ``joint_names_expr`` = those joints and ``effort_limit_sim`` / ``velocity_limit_sim`` left
        at None (PhysX's maxForce = max_effort as authored, and the USD's joint speed cap).

    Raises:
        InputError: an unreadable asset or map, a map pattern that matches no joint, a joint that
            cannot carry the envelope, or an output that cannot be written (nothing is written).
    """
    from isaaclab.actuators import ImplicitActuatorCfg

    from drive_envelope._src.adapters.usd.apply import apply_envelopes, map_assignments
    from drive_envelope._src.adapters.usd.joint_map import read_map
    from drive_envelope._src.adapters.usd.save import save_stage
    from drive_envelope._src.adapters.usd.stage import open_overlay

    stage = open_overlay(asset)  # the asset's own layers are never edited
    assignments, _ = map_assignments(stage, read_map(joint_map))
    applied = apply_envelopes(stage, assignments)
    written = save_stage(stage, output, flatten=flatten)
    envelopes: dict[str, PerformanceEnvelope] = {}
    for drive in applied:
        name = drive.joint_path.rsplit("/", 1)[-1]
        if envelopes.setdefault(name, drive.envelope) != drive.envelope:
            raise InputError(
                f"{joint_map}: joints named {name!r} get different envelopes; Isaac Lab names joints by "
                "prim name, so one ImplicitActuatorCfg cannot tell them apart"
            )
    actuator = ImplicitActuatorCfg(
        joint_names_expr=[re.escape(name) for name in envelopes],
        stiffness=dict(stiffness) if isinstance(stiffness, Mapping) else stiffness,
        damping=dict(damping) if isinstance(damping, Mapping) else damping,
        effort_limit_sim=None,
        velocity_limit_sim=None,
    )
    return ImplicitEnvelopeSetup(usd_path=written[0], envelopes=envelopes, actuator=actuator)


def _values_for(value: Any, joint: str) -> float | None:
    """An Isaac Lab cfg value (float or ``{regex: float}``) for one joint; None when unset there."""
    if value is None:
        return None
    if isinstance(value, Mapping):
        for pattern, item in value.items():
            if re.fullmatch(str(pattern), joint):
                return float(item)
        return None
    return float(value)


def check_implicit_actuator(actuator: Any, envelopes: Mapping[str, PerformanceEnvelope]) -> list[str]:
    """The settings of an ``ImplicitActuatorCfg`` that would change authored envelopes, one line each.

    Isaac Lab writes ``effort_limit_sim`` (or, for implicit actuators, ``effort_limit``) into
    PhysX's drive max force, i.e. the envelope's maxEffort: any value other than the authored
    max_effort replaces it. A ``velocity_limit_sim`` below max_actuator_velocity caps the joint's
    speed below the envelope's (PhysX's maxJointVelocity), which the envelope does not model.

    Args:
        actuator: An Isaac Lab ``ImplicitActuatorCfg`` (or any cfg with its fields).
        envelopes: The authored envelope per joint name (e.g. :attr:`ImplicitEnvelopeSetup.envelopes`).

    Returns:
        Problems, empty when the cfg leaves every envelope as authored.
    """
    problems = []
    patterns = list(getattr(actuator, "joint_names_expr", None) or [])
    for joint, envelope in envelopes.items():
        if patterns and not any(re.fullmatch(p, joint) for p in patterns):
            continue
        for field in ("effort_limit_sim", "effort_limit"):
            value = _values_for(getattr(actuator, field, None), joint)
            if value is not None and not math.isclose(value, envelope.max_effort, rel_tol=1e-6):
                problems.append(
                    f"{field} = {value:g} for joint {joint!r} replaces the envelope's max_effort "
                    f"{envelope.max_effort:g} in PhysX (leave it None or equal)"
                )
        speed = _values_for(getattr(actuator, "velocity_limit_sim", None), joint)
        if speed is not None and speed < envelope.max_actuator_velocity:
            problems.append(
                f"velocity_limit_sim = {speed:g} for joint {joint!r} caps the joint below the envelope's "
                f"max_actuator_velocity {envelope.max_actuator_velocity:g} rad/s (PhysX's maxJointVelocity)"
            )
    return problems

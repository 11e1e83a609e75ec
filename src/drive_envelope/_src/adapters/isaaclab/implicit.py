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
import numbers
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError


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
    envelopes: dict[str, PerformanceEnvelope] = {}
    for drive in applied:
        name = drive.joint_path.rsplit("/", 1)[-1]
        if envelopes.setdefault(name, drive.envelope) != drive.envelope:
            raise InputError(
                f"{joint_map}: joints named {name!r} get different envelopes; Isaac Lab names joints by "
                "prim name, so one ImplicitActuatorCfg cannot tell them apart"
            )
    # checked before anything is written: Isaac Lab would refuse a string or an unmatched regex
    # only when the scene is built
    gains = {
        label: _gains(value, label, unit, envelopes)
        for label, value, unit in (("stiffness", stiffness, "N*m/rad"), ("damping", damping, "N*m*s/rad"))
    }
    written = save_stage(stage, output, flatten=flatten)
    actuator = ImplicitActuatorCfg(
        joint_names_expr=[re.escape(name) for name in envelopes], **gains
    )  # the effort and speed limits stay None (2.3's and 3.0's default): Isaac Lab keeps the USD's
    return ImplicitEnvelopeSetup(usd_path=written[0], envelopes=envelopes, actuator=actuator)


def _gains(
    value: object, label: str, unit: str, envelopes: Mapping[str, PerformanceEnvelope]
) -> float | dict[str, float] | None:
    """A gain for ``ImplicitActuatorCfg`` in SI: a number, a string with units, or ``{regex: either}``.

    Each string is read in its joint type's unit (per radian on revolute joints, ``"80 N*m/deg"``
    included); each regex must match one of the joints the map equipped.
    """
    from drive_envelope._src.values import read_quantity

    where = f"author_implicit_envelopes: {label}"
    linear = {"N*m/rad": "N/m", "N*m*s/rad": "N*s/m"}[unit]

    def number(item: object, joint: str, at: str) -> float:
        if isinstance(item, str):
            revolute = envelopes[joint].joint == "revolute"
            result = read_quantity(item, unit if revolute else linear, at)
        elif isinstance(item, numbers.Real) and not isinstance(item, bool):
            result = float(item)
        else:
            raise InputError(
                f"{at}: expected a number [{unit} or {linear}] or a string with units, got {item!r}"
            )
        if not 0.0 <= result < math.inf:
            raise InputError(f"{at}: expected >= 0 and finite [{unit} or {linear}], got {item!r}")
        return result

    if value is None:
        return None
    if not isinstance(value, Mapping):
        found = {number(value, joint, where) for joint in envelopes}
        if len(found) == 1:
            return found.pop()
        # "80 N*m/deg" on revolute and prismatic joints: two SI numbers, one per joint
        return {re.escape(joint): number(value, joint, where) for joint in envelopes}
    result: dict[str, float] = {}
    for pattern, item in value.items():
        try:
            matched = [joint for joint in envelopes if re.fullmatch(str(pattern), joint)]
        except re.error as exc:
            raise InputError(f"{where}[{pattern!r}]: not a regular expression ({exc})") from None
        if not matched:
            raise InputError(
                f"{where}[{pattern!r}]: matches none of the joints the map equipped: {sorted(envelopes)}"
            )
        values = {number(item, joint, f"{where}[{pattern!r}]") for joint in matched}
        if len(values) > 1:
            result.update({re.escape(joint): number(item, joint, where) for joint in matched})
        else:
            result[str(pattern)] = values.pop()
    return result


def _patterns(actuator: Any) -> list[re.Pattern[str]]:
    """The cfg's ``joint_names_expr`` compiled (empty: every joint), or one InputError naming it."""
    given = getattr(actuator, "joint_names_expr", None)
    if given is None:
        return []
    if isinstance(given, str):
        raise InputError(
            f"joint_names_expr = {given!r}: a string; expected a list of joint regexes, as Isaac Lab "
            f"reads it (e.g. [{given!r}])"
        )
    compiled = []
    for pattern in given:
        try:
            compiled.append(re.compile(str(pattern)))
        except re.error as exc:
            raise InputError(f"joint_names_expr: {pattern!r} is not a regex ({exc})") from None
    return compiled


def _value_for(value: Any, joint: str, field: str) -> float | None:
    """An Isaac Lab cfg value (float or ``{regex: float}``) for one joint; None when unset.

    A dict that names some joints of the group gives the others 0: Isaac Lab's parser fills the
    joints a dict does not match with 0 (2.3's and 3.0's alike), and that is what it writes.
    """
    if value is None:
        return None
    if isinstance(value, Mapping):
        for pattern, item in value.items():
            try:
                if re.fullmatch(str(pattern), joint):
                    return float(item)
            except re.error as exc:
                raise InputError(f"{field}: key {pattern!r} is not a regex ({exc})") from None
        return 0.0
    return float(value)


def _explicit(actuator: Any) -> bool:
    """Whether the cfg builds an explicit actuator (its class is not an ``ImplicitActuator``)."""
    class_type = getattr(actuator, "class_type", None)
    if isinstance(class_type, type):  # 2.3 sets ImplicitActuator.is_implicit_model only once one is built
        return not any(base.__name__ == "ImplicitActuator" for base in class_type.__mro__)
    try:  # Isaac Lab 3.0 names classes by lazy strings that resolve on attribute access
        implicit = getattr(class_type, "is_implicit_model", None)
    except (ImportError, AttributeError, ValueError):
        implicit = None
    return implicit is False


def check_implicit_actuator(actuator: Any, envelopes: Mapping[str, PerformanceEnvelope]) -> list[str]:
    """The settings of an actuator cfg that would change authored envelopes, one line each.

    Isaac Lab writes an implicit actuator's effort limit (3.0 ``joint_effort_limit``, 2.3
    ``effort_limit_sim``, and the deprecated ``effort_limit``) into PhysX's drive max force, i.e.
    the envelope's maxEffort: any value other than the authored max_effort replaces it, and a dict
    that leaves a joint out gives it 0 (the drive is off). A joint speed limit (3.0
    ``joint_velocity_limit``, 2.3 ``velocity_limit_sim``) below max_actuator_velocity caps the
    joint below the envelope's speed (PhysX's maxJointVelocity), which the envelope does not model.
    An explicit cfg (an ``IdealPDActuatorCfg``, ``DCMotorCfg``, ``ActuatorNetLSTMCfg``, ...) is one
    line: Isaac Lab runs its own model and sets PhysX's drive gains to 0, so the authored envelope
    has no PhysX drive to clamp.

    Args:
        actuator: An Isaac Lab actuator cfg of 2.3 or 3.0 (or any object with its fields).
        envelopes: The authored envelope per joint name (e.g. :attr:`ImplicitEnvelopeSetup.envelopes`).

    Returns:
        Problems, empty when the cfg leaves every envelope as authored.

    Raises:
        InputError: a ``joint_names_expr`` that is a string or holds a pattern that is not a regex.
    """
    from drive_envelope._src.adapters.isaaclab.compat import ISAACLAB_3_0

    patterns = _patterns(actuator)
    joints = [j for j in envelopes if not patterns or any(p.fullmatch(j) for p in patterns)]
    if joints and _explicit(actuator):
        return [
            f"{type(actuator).__name__} is an explicit actuator: Isaac Lab computes its effort itself "
            f"and sets PhysX's drive gains to 0 on {joints}, so the envelope authored for PhysX's drive "
            "clamps no drive; use an ImplicitActuatorCfg for these joints (author_implicit_envelopes "
            "returns one) or PerformanceEnvelopeActuatorCfg for the envelope in an explicit actuator"
        ]
    problems = []
    # 3.0's field names are a superset of 2.3's: a cfg of either has the ones it reads
    for joint in joints:
        envelope = envelopes[joint]
        for field in ISAACLAB_3_0.joint_effort_limits:
            given = getattr(actuator, field, None)
            value = _value_for(given, joint, field)
            if value is None or math.isclose(value, envelope.max_effort, rel_tol=1e-6):
                continue
            unnamed = isinstance(given, Mapping) and value == 0.0
            why = (
                f"{field} names no value for joint {joint!r}: Isaac Lab writes 0 as its max force, "
                f"which turns the drive off (the envelope's max_effort is {envelope.max_effort:g}; "
                "name every joint, or leave it None)"
                if unnamed
                else f"{field} = {value:g} for joint {joint!r} replaces the envelope's max_effort "
                f"{envelope.max_effort:g} in PhysX (leave it None or equal)"
            )
            problems.append(why)
        for field in ISAACLAB_3_0.joint_velocity_limits:
            speed = _value_for(getattr(actuator, field, None), joint, field)
            if speed is not None and speed < envelope.max_actuator_velocity:
                problems.append(
                    f"{field} = {speed:g} for joint {joint!r} caps the joint below the envelope's "
                    f"max_actuator_velocity {envelope.max_actuator_velocity:g} rad/s "
                    "(PhysX's maxJointVelocity)"
                )
    return problems

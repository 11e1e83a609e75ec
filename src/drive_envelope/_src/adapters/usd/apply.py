"""Apply envelopes to a whole robot asset: one joint, or every joint a map file names.

A map file (:mod:`~drive_envelope._src.adapters.usd.joint_map`, the same format as ``mujoco apply
--map``) assigns envelope sources to joints by glob on their prim paths::

    [joints]
    "/anymal/*/*_HAA" = "actuators/anydrive.toml"     # a pattern with '/': the whole prim path
    "*_KFE" = { datasheet = "knee.toml", instance = "angular" }   # without '/': the prim's name

Joints inside instances are matched by their instance-proxy paths (what ``usd show`` lists) and
authored on their prototype's source (:mod:`~drive_envelope._src.adapters.usd.instancing`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from drive_envelope._src.adapters.usd.joint_map import (
    JointMap,
    _names,
    match_joints,
    resolve_envelopes,
)
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.validation import keyed_error

if TYPE_CHECKING:
    from pxr import Usd


@dataclass(frozen=True, kw_only=True, slots=True)
class Assignment:
    """One envelope to write on one joint."""

    joint_path: str
    """Prim path of the joint (an instance proxy's path for a joint inside an instance)."""
    envelope: PerformanceEnvelope
    """The envelope (SI, joint side)."""
    instance: str | None = None
    """Drive instance, or None for the joint type's default."""
    where: str = ""
    """Prefix for error messages (the map file and key that made this assignment), if any."""


@dataclass(frozen=True, kw_only=True, slots=True)
class AppliedDrive:
    """What one edit did, for the command's report."""

    joint_path: str
    """Prim path of the joint."""
    instance: str
    """Drive instance written."""
    envelope: PerformanceEnvelope
    """The envelope written (SI)."""
    authored_at: str = ""
    """Prim path the opinions went to: the joint, or its prototype's source for an instanced joint."""
    warnings: tuple[str, ...] = ()
    """Authoring warnings for this joint."""
    where: str = ""
    """The map key (or flag) of the assignment: reports group joints by it."""
    rated_effort: float = math.inf
    """The asset's own maxForce before the edit [N*m or N]; ``inf`` if none."""
    rated_speed: float = math.inf
    """The asset's ``physxJoint:maxJointVelocity`` [rad/s or m/s]; ``inf`` if none."""


def joint_paths(stage: Usd.Stage) -> list[str]:
    """Paths of the joints that can carry an envelope (revolute, prismatic, D6), instanced ones included."""
    from pxr import Usd, UsdPhysics

    from drive_envelope._src.adapters.usd.authoring import joint_kind

    paths = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if prim.IsA(UsdPhysics.Joint):
            try:
                joint_kind(prim)
            except InputError:
                continue  # fixed, spherical, distance joints have no drive envelope
            paths.append(str(prim.GetPath()))
    return paths


def map_assignments(stage: Usd.Stage, joint_map: JointMap) -> tuple[list[Assignment], tuple[str, ...]]:
    """The assignments a map makes on a stage's joints, and the map's warnings.

    Raises:
        InputError: a pattern that matches no joint or is never used, or a source that cannot be
            resolved, naming the map key.
    """
    match = match_joints(joint_map, joint_paths(stage))
    assignments = [
        Assignment(
            joint_path=item.joint,
            envelope=item.envelope,
            instance=item.entry.instance,
            where=item.entry.where,
        )
        for item in resolve_envelopes(match)
        if item.envelope is not None
    ]
    return assignments, match.warnings


def apply_envelopes(stage: Usd.Stage, assignments: Sequence[Assignment]) -> list[AppliedDrive]:
    """Write each assignment on the stage's edit target, collecting the warnings per joint.

    Joints of several instances that share one prototype source are authored once; giving them
    different envelopes is an error (they are one joint in the file).

    Raises:
        InputError: from :func:`~drive_envelope._src.adapters.usd.authoring.author_envelope`, with the
            map key in front when the assignment came from a map; the stage may then be partly
            edited in memory, so callers write nothing.
    """
    from drive_envelope._src.adapters.usd.articulation import articulated_joints
    from drive_envelope._src.adapters.usd.authoring import author_envelope, model_rating, resolve_joint
    from drive_envelope._src.adapters.usd.instancing import edit_site

    articulated = articulated_joints(stage)
    sites: dict[str, Assignment] = {}
    results = []
    for item in assignments:
        try:
            prim = resolve_joint(stage, item.joint_path)
            site = str(edit_site(prim).prim.GetPath())
            first = sites.setdefault(site, item)
            if first is not item:
                _check_shared(first, item, site)
                continue
            rated_effort, rated_speed = model_rating(prim, item.instance)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                inst = author_envelope(prim, item.envelope, item.instance, articulated=articulated)
        except InputError as exc:
            raise keyed_error(item.where, exc) from None
        results.append(
            AppliedDrive(
                joint_path=item.joint_path,
                instance=inst,
                envelope=item.envelope,
                authored_at=site,
                warnings=tuple(str(w.message) for w in caught),
                where=item.where or item.joint_path,
                rated_effort=rated_effort,
                rated_speed=rated_speed,
            )
        )
    return results


def rating_report(applied: Sequence[AppliedDrive]) -> list[str]:
    """Where the asset's author and the envelope's source disagree, one line per map key.

    A cap more than 10 % below the asset's maxForce, or a speed above the joint's maxJointVelocity.
    """
    groups: dict[str, list[AppliedDrive]] = {}
    for item in applied:
        groups.setdefault(item.where, []).append(item)
    lines = []
    for where, items in groups.items():
        env = items[0].envelope
        effort_unit, speed_unit = ("N*m", "rad/s") if env.joint == "revolute" else ("N", "m/s")
        low = [
            i for i in items if math.isfinite(i.rated_effort) and i.envelope.max_effort < 0.9 * i.rated_effort
        ]
        if low:
            rated = max(i.rated_effort for i in low)
            lines.append(
                f"{where}: max_effort {env.max_effort:g} {effort_unit} is "
                f"{100 * (1 - env.max_effort / rated):.0f} % below the asset's maxForce {rated:g} "
                f"{effort_unit} on {_names([i.joint_path for i in low], str)}: the envelope replaces it"
            )
        fast = [
            i
            for i in items
            if math.isfinite(i.rated_speed) and i.envelope.max_actuator_velocity > i.rated_speed
        ]
        if fast:
            limit = min(i.rated_speed for i in fast)
            lines.append(
                f"{where}: max_actuator_velocity {env.max_actuator_velocity:g} {speed_unit} is above the "
                f"joint's maxJointVelocity {limit:g} {speed_unit} on "
                f"{_names([i.joint_path for i in fast], str)}: PhysX's joint limit binds first"
            )
    return lines


def _check_shared(first: Assignment, item: Assignment, site: str) -> None:
    if (first.envelope, first.instance) != (item.envelope, item.instance):
        raise InputError(
            f"joints {first.joint_path!r} and {item.joint_path!r} are one joint of a shared prototype "
            f"({site!r}) and cannot get different envelopes"
        )

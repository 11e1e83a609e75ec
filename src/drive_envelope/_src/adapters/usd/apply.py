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

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from drive_envelope._src.adapters.usd.joint_map import (
    JointMap,
    keyed_error,
    match_joints,
    resolve_envelopes,
)
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    from pxr import Usd

__all__ = ["AppliedDrive", "Assignment", "apply_envelopes", "joint_paths", "map_assignments"]


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
    from drive_envelope._src.adapters.usd.authoring import author_envelope, resolve_joint
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
            )
        )
    return results


def _check_shared(first: Assignment, item: Assignment, site: str) -> None:
    if (first.envelope, first.instance) != (item.envelope, item.instance):
        raise InputError(
            f"joints {first.joint_path!r} and {item.joint_path!r} are one joint of a shared prototype "
            f"({site!r}) and cannot get different envelopes"
        )

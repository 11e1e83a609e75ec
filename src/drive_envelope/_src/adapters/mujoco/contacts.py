"""Neighbouring bodies whose collision geometry overlaps in the model's own poses.

MuJoCo skips contacts between a body and its parent (``filterparent``), but not where the parent is
welded to the world: a fixed arm's base and its first link are such a pair. Where their meshes
overlap at the joint (Menagerie's Kinova Gen3: base_link and shoulder_link, 12 mm, 4 contacts in
every pose), the joint grinds on its parent, lags its target and its drive saturates and lets go,
although nothing in the drive is wrong. The pairs are read from MuJoCo's own collision at ``qpos0``
and at every keyframe (``mj_forward``), as the bypass check reads transmissions.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from drive_envelope._src.adapters.mujoco.mjcf import model_poses

if TYPE_CHECKING:
    import mujoco


@dataclass(frozen=True, kw_only=True, slots=True)
class NeighbourContact:
    """A parent-child pair of bodies (through welds) in contact in the model's own poses."""

    parent: str
    """The parent body's name (or ``#id``)."""
    child: str
    """The child body's name (or ``#id``), the one the joints move."""
    joints: tuple[str, ...]
    """The joints of the child body: those that grind on the parent."""
    poses: tuple[str, ...]
    """``qpos0`` and the keyframes (``keyframe 'home'``) in which they touch."""
    contacts: int
    """The most contacts between the two in one pose."""
    depth: float
    """The deepest penetration over those poses [m] (``-dist`` of MuJoCo's contact; 0: touching)."""


def _name(model: mujoco.MjModel, kind: mujoco.mjtObj, index: int) -> str:
    import mujoco

    return mujoco.mj_id2name(model, kind, index) or f"#{index}"


def _neighbours(model: mujoco.MjModel, body1: int, body2: int) -> tuple[int, int] | None:
    """(parent, child) weld bodies when ``body1`` and ``body2`` are parent and child through welds."""
    weld1, weld2 = int(model.body_weldid[body1]), int(model.body_weldid[body2])
    if weld1 != weld2:
        if int(model.body_weldid[model.body_parentid[weld2]]) == weld1:
            return body1, weld2
        if int(model.body_weldid[model.body_parentid[weld1]]) == weld2:
            return body2, weld1
    return None


def _pose_label(model: mujoco.MjModel, key: int) -> str:
    import mujoco

    if key < 0:
        return "qpos0"
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_KEY, key)
    return f"keyframe {name!r}" if name else f"keyframe #{key}"


@dataclass(kw_only=True, slots=True)
class _Seen:
    """What one pair's contacts showed so far (mutable, while the poses are read)."""

    poses: list[str] = field(default_factory=list)
    contacts: int = 0
    depth: float = 0.0


def neighbour_contacts(model: mujoco.MjModel) -> list[NeighbourContact]:
    """Parent-child body pairs that penetrate (``dist < 0``) at ``qpos0`` or at any keyframe.

    Args:
        model: The compiled model (contacts disabled in ``opt.disableflags``: none are found).
    """
    seen: dict[tuple[int, int], _Seen] = {}
    for key, data in model_poses(model):
        counts: dict[tuple[int, int], int] = {}
        for contact in data.contact[: data.ncon]:
            bodies = (int(model.geom_bodyid[contact.geom1]), int(model.geom_bodyid[contact.geom2]))
            pair = _neighbours(model, *bodies)
            if pair is None or not contact.dist < 0:
                continue
            counts[pair] = counts.get(pair, 0) + 1
            item = seen.setdefault(pair, _Seen())
            item.depth = max(item.depth, -float(contact.dist))
        for pair, count in counts.items():
            seen[pair].poses.append(_pose_label(model, key))
            seen[pair].contacts = max(seen[pair].contacts, count)
    return [_contact(model, pair, item) for pair, item in seen.items()]


def _contact(model: mujoco.MjModel, pair: tuple[int, int], seen: _Seen) -> NeighbourContact:
    import mujoco

    parent, child = pair
    first, count = int(model.body_jntadr[child]), int(model.body_jntnum[child])
    return NeighbourContact(
        parent=_name(model, mujoco.mjtObj.mjOBJ_BODY, parent),
        child=_name(model, mujoco.mjtObj.mjOBJ_BODY, child),
        joints=tuple(_name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(first, first + count)),
        poses=tuple(seen.poses),
        contacts=seen.contacts,
        depth=seen.depth,
    )


def neighbour_contact_warnings(contacts: Sequence[NeighbourContact], driven: Sequence[str]) -> list[str]:
    """One line per pair whose child is moved by a ``driven`` joint, with the ``<exclude>`` that fixes it."""
    lines = []
    for item in contacts:
        joints = [joint for joint in item.joints if joint in driven]
        if not joints:
            continue
        poses = ", ".join(item.poses)
        lines.append(
            f"bodies {item.parent!r} and {item.child!r} (driven joint {', '.join(map(repr, joints))} between "
            f"them) overlap at {poses} ({item.contacts} contacts, {item.depth * 1e3:.3g} mm deep): MuJoCo "
            "filters parent-child contacts only where the parent is not welded to the world, so the joint "
            "grinds on its parent and its drive saturates; add <contact><exclude "
            f'body1="{item.parent}" body2="{item.child}"/></contact> if the overlap is not meant'
        )
    return lines

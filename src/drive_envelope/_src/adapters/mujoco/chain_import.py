"""An MJCF robot as chain-scenario joints: the ``[[joints]]`` entries of its hinge and slide joints.

MuJoCo compiles the file and the compiled model is read (``body_pos``, ``body_quat``,
``body_ipos``, ``body_iquat``, ``body_inertia``, ``body_mass``, ``jnt_pos``, ``jnt_axis``,
``dof_armature``), so defaults, classes and ``<inertial>`` versus geom-derived inertia are
MuJoCo's own. A body with one hinge (revolute) or slide (prismatic) joint is one entry; its link
frame is the body frame moved to the joint's ``pos`` (the chain format puts each joint at its link
frame's origin), the body ``quat`` is the frame's fixed rotation, the joint axis is in it, and the
centre of mass and principal inertia are the body's. A body with a free joint is the fixed base
(the free joint is dropped, as for a robot bolted in the air, its frame the world's); bodies
welded to the world are the base too. The entries are in MuJoCo's body order (parents first),
so a legged robot's legs are a tree on the base.

Not read: joint ranges, damping, frictionloss, actuators and contacts (the stands have none);
the caller adds each joint's drive and envelope tables.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain_frames import quat_multiply, rotate

__all__ = ["mjcf_joints"]


def mjcf_joints(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The ``[[joints]]`` entries of an MJCF robot with a fixed (or freed, then fixed) base.

    Raises:
        InputError: MuJoCo cannot compile the file, or a moving body has no joint, a ball joint,
            several joints or a free joint below the base; the message names the file and body.
    """
    import mujoco

    file = Path(path)
    try:
        model = mujoco.MjModel.from_xml_path(str(file))
    except (ValueError, OSError) as exc:
        raise InputError(f"{file}: MuJoCo cannot compile the model: {' '.join(str(exc).split())}") from None
    kinds = {int(mujoco.mjtJoint.mjJNT_HINGE): "revolute", int(mujoco.mjtJoint.mjJNT_SLIDE): "prismatic"}
    free = int(mujoco.mjtJoint.mjJNT_FREE)
    base: set[int] = {0}  # the world and every body welded or freed onto it: the fixed base
    entries: list[dict[str, Any]] = []
    entry_of: dict[int, int] = {}  # body id -> index of its entry
    shift_of: dict[int, tuple[float, float, float]] = {}  # body id -> its joint's pos in the body
    for body in range(1, model.nbody):
        parent = int(model.body_parentid[body])
        name = model.body(body).name or f"body{body}"
        where = f"{file}: body {name!r}"
        count, first = int(model.body_jntnum[body]), int(model.body_jntadr[body])
        types = [int(model.jnt_type[first + i]) for i in range(count)]
        if parent == 0 and (count == 0 or types == [free]):
            base.add(body)
            continue
        if count == 0:
            raise InputError(
                f"{where}: a body welded to a moving body (no joint) is not merged into it; expected one "
                "hinge or slide joint"
            )
        if types == [free] or count != 1 or types[0] not in kinds:
            raise InputError(
                f"{where}: expected one hinge or slide joint on a moving body, got {count} joint(s) of "
                f"type(s) {types} (0 free, 1 ball, 2 slide, 3 hinge)"
            )
        joint = first
        shift = tuple(float(v) for v in model.jnt_pos[joint])
        quat = tuple(float(v) for v in model.body_quat[body])
        moved = rotate(quat, shift)  # type: ignore[arg-type]
        parent_shift = shift_of.get(parent, (0.0, 0.0, 0.0))
        origin = [float(model.body_pos[body][i]) + moved[i] - parent_shift[i] for i in range(3)]
        if parent in base and parent != 0:  # a child of the freed base: the base frame is the world's
            parent_quat = tuple(float(v) for v in model.body_quat[parent])
            if parent_quat != (1.0, 0.0, 0.0, 0.0):
                origin = list(rotate(parent_quat, origin))  # type: ignore[arg-type]
                quat = quat_multiply(parent_quat, quat)  # type: ignore[arg-type]
        dof = int(model.jnt_dofadr[joint])
        entries.append({
            "name": model.joint(joint).name or f"joint{joint}",
            "type": kinds[types[0]],
            "parent": "base" if parent in base else entries[entry_of[parent]]["name"],
            "origin": origin,
            "quat": list(quat),
            "axis": [float(v) for v in model.jnt_axis[joint]],
            "mass": float(model.body_mass[body]),
            "com": [float(model.body_ipos[body][i]) - shift[i] for i in range(3)],
            "inertia": [float(v) for v in model.body_inertia[body]],
            "inertia_quat": [float(v) for v in model.body_iquat[body]],
            "armature": float(model.dof_armature[dof]),
        })  # fmt: skip
        entry_of[body] = len(entries) - 1
        shift_of[body] = shift  # type: ignore[assignment]
    if not entries:
        raise InputError(f"{file}: expected hinge or slide joints, found none")
    return entries

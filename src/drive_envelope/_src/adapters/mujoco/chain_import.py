"""An MJCF robot as chain-scenario joints: the ``[[joints]]`` entries of its hinge and slide joints.

MuJoCo compiles the file and the compiled model is read (``body_pos``, ``body_quat``,
``body_ipos``, ``body_iquat``, ``body_inertia``, ``body_mass``, ``jnt_pos``, ``jnt_axis``,
``dof_armature``), so defaults, classes and ``<inertial>`` versus geom-derived inertia are
MuJoCo's own. A body with one hinge (revolute) or slide (prismatic) joint is one entry; its link
frame is the body frame moved to the joint's ``pos`` (the chain format puts each joint at its link
frame's origin), the body ``quat`` is the frame's fixed rotation, the joint axis is in it, and the
centre of mass and principal inertia are the body's. A body with a free joint is the fixed base
(the free joint is dropped, as for a robot bolted in the air, its frame the world's); bodies
welded to the world are the base too, and a body welded onto a moving one is merged into its
link (mass, centre of mass and inertia by the parallel-axis theorem; the full tensor then). The
entries are in MuJoCo's body order (parents first), so a legged robot's legs are a tree on the
base.

Not read: joint ranges, damping, frictionloss, actuators and contacts (the stands have none);
the caller adds each joint's drive and envelope tables.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain_frames import (
    IDENTITY,
    Quaternion,
    full_inertia,
    quat_multiply,
    rotate,
)

Vector = tuple[float, float, float]
_Part = tuple[float, Vector, Any]  # mass [kg], centre of mass [m], inertia tensor [kg*m^2], link frame


def _vec(values: Any) -> Vector:
    return (float(values[0]), float(values[1]), float(values[2]))


def _quat(values: Any) -> Quaternion:
    return (float(values[0]), float(values[1]), float(values[2]), float(values[3]))


def _add(a: Vector, b: Vector) -> Vector:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _part(model: Any, body: int, index: int, offset: Vector, turn: Quaternion) -> _Part:
    """A body's mass, centre of mass and inertia tensor in its entry's link frame."""
    axes = quat_multiply(turn, _quat(model.body_iquat[body]))
    com = _add(offset, rotate(turn, _vec(model.body_ipos[body])))
    return float(model.body_mass[body]), com, full_inertia(_vec(model.body_inertia[body]), axes)


def _merged(parts: list[_Part]) -> dict[str, Any]:
    """Welded bodies as one link: mass, centre of mass, full tensor (parallel-axis theorem)."""
    import numpy as np

    mass = sum(part[0] for part in parts)
    com = np.sum([part[0] * np.asarray(part[1]) for part in parts], axis=0) / mass
    tensor = np.zeros((3, 3))
    for m, c, t in parts:
        d = np.asarray(c) - com
        tensor += np.asarray(t) + m * (float(d @ d) * np.eye(3) - np.outer(d, d))
    inertia = [tensor[0, 0], tensor[1, 1], tensor[2, 2], tensor[0, 1], tensor[0, 2], tensor[1, 2]]
    return {"mass": float(mass), "com": [float(v) for v in com], "inertia": [float(v) for v in inertia]}


def mjcf_joints(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The ``[[joints]]`` entries of an MJCF robot with a fixed (or freed, then fixed) base.

    Raises:
        InputError: MuJoCo cannot compile the file, or a moving body has a ball joint, several
            joints or a free joint below the base; the message names the file and body.
    """
    import mujoco

    file = Path(path)
    try:
        model = mujoco.MjModel.from_xml_path(str(file))
    except (ValueError, OSError) as exc:
        raise InputError(f"{file}: MuJoCo cannot compile the model: {' '.join(str(exc).split())}") from None
    kinds = {int(mujoco.mjtJoint.mjJNT_HINGE): "revolute", int(mujoco.mjtJoint.mjJNT_SLIDE): "prismatic"}
    free = int(mujoco.mjtJoint.mjJNT_FREE)
    entries: list[dict[str, Any]] = []
    welded: list[list[_Part]] = []  # per entry: its body and the bodies welded onto it
    # each body's frame in its entry's link frame (-1: the base frame, the world's): a point p of
    # the body is offset + R(quat) @ p there
    frame: dict[int, tuple[int, Vector, Quaternion]] = {0: (-1, (0.0, 0.0, 0.0), IDENTITY)}
    for body in range(1, model.nbody):
        parent = int(model.body_parentid[body])
        name = model.body(body).name or f"body{body}"
        where = f"{file}: body {name!r}"
        count, first = int(model.body_jntnum[body]), int(model.body_jntadr[body])
        types = [int(model.jnt_type[first + i]) for i in range(count)]
        pos = _vec(model.body_pos[body])
        quat = _quat(model.body_quat[body])
        index, offset, turn = frame[parent]
        if parent == 0 and types == [free]:  # the freed base is fixed where the world's frame is
            frame[body] = (-1, (0.0, 0.0, 0.0), quat)
            continue
        if count == 0:  # welded onto its parent: the base, or merged into the parent's link
            frame[body] = (index, _add(offset, rotate(turn, pos)), quat_multiply(turn, quat))
            if index >= 0:
                welded[index].append(_part(model, body, *frame[body]))
            continue
        if types == [free] or count != 1 or types[0] not in kinds:
            raise InputError(
                f"{where}: expected one hinge or slide joint on a moving body, got {count} joint(s) of "
                f"type(s) {types} (0 free, 1 ball, 2 slide, 3 hinge)"
            )
        joint = first
        shift = _vec(model.jnt_pos[joint])
        origin = _add(offset, rotate(turn, _add(pos, rotate(quat, shift))))
        dof = int(model.jnt_dofadr[joint])
        entries.append({
            "name": model.joint(joint).name or f"joint{joint}",
            "type": kinds[types[0]],
            "parent": "base" if index < 0 else entries[index]["name"],
            "origin": list(origin),
            "quat": list(quat_multiply(turn, quat)),
            "axis": list(_vec(model.jnt_axis[joint])),
            "mass": float(model.body_mass[body]),
            "com": [float(model.body_ipos[body][i]) - shift[i] for i in range(3)],
            "inertia": list(_vec(model.body_inertia[body])),
            "inertia_quat": list(_quat(model.body_iquat[body])),
            "armature": float(model.dof_armature[dof]),
        })  # fmt: skip
        frame[body] = (len(entries) - 1, (-shift[0], -shift[1], -shift[2]), IDENTITY)
        welded.append([_part(model, body, *frame[body])])
    for entry, parts in zip(entries, welded, strict=True):
        if len(parts) > 1:
            entry.update(_merged(parts))
            del entry["inertia_quat"]
    if not entries:
        raise InputError(f"{file}: expected hinge or slide joints, found none")
    return entries

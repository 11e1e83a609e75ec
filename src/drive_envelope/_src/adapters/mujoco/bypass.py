"""The actuators whose force reaches a joint without passing through an envelope drive.

A drive bounds only its own effort. Any other actuator whose transmission reaches a joint (a joint
actuator, a ``<motor tendon=...>`` on a fixed or spatial tendon through it, a site or body
actuator on a link below it) adds force the envelope never sees. What reaches a joint is read from
MuJoCo's own transmission, ``actuator_moment`` after ``mj_fwdPosition``, at ``qpos0`` and at every
keyframe: the joints of the DOFs with a nonzero moment in any of these configurations.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.mujoco.existing import compiled_gain_kind
from drive_envelope._src.adapters.mujoco.mjcf import model_poses

if TYPE_CHECKING:
    import mujoco

# a moment below this fraction of the largest of its row is rounding (spatial tendons, sites)
_RELATIVE_ZERO = 1e-9


@dataclass(frozen=True, kw_only=True, slots=True)
class OtherActuator:
    """An actuator that is not an envelope drive, and one joint its force reaches."""

    joint: str
    """The joint (or ``#id``) its moment reaches."""
    actuator: str
    """The actuator's name (or ``#id``)."""
    kind: str
    """``motor``, ``position``, ``velocity``, ``plugin`` or ``other``."""
    transmission: str
    """``joint``, ``joint in parent``, ``tendon 't'``, ``site 's'``, ``body 'b'``, ``slider-crank 's'``."""
    drive: str | None
    """The envelope drive on that joint, whose envelope the force bypasses; None: no drive there."""


def _transmission(model: mujoco.MjModel, i: int) -> str:
    import mujoco

    trn = mujoco.mjtTrn
    kinds = {
        int(trn.mjTRN_JOINT): ("joint", None),
        int(trn.mjTRN_JOINTINPARENT): ("joint in parent", None),
        int(trn.mjTRN_TENDON): ("tendon", mujoco.mjtObj.mjOBJ_TENDON),
        int(trn.mjTRN_SITE): ("site", mujoco.mjtObj.mjOBJ_SITE),
        int(trn.mjTRN_BODY): ("body", mujoco.mjtObj.mjOBJ_BODY),
        int(trn.mjTRN_SLIDERCRANK): ("slider-crank", mujoco.mjtObj.mjOBJ_SITE),
    }
    label, obj = kinds.get(int(model.actuator_trntype[i]), ("other", None))
    if obj is None:
        return label
    target = int(model.actuator_trnid[i, 0])
    return f"{label} {mujoco.mj_id2name(model, obj, target) or f'#{target}'!r}"


def _reached_dofs(model: mujoco.MjModel, actuators: Sequence[int]) -> dict[int, set[int]]:
    """Actuator -> the DOFs with a nonzero moment at ``qpos0`` or at any keyframe."""
    reached: dict[int, set[int]] = {i: set() for i in actuators}
    if not actuators:
        return reached
    for _key, data in model_poses(model):
        for i in actuators:
            for out in range(
                int(model.actuator_outadr[i]), int(model.actuator_outadr[i] + model.actuator_outnum[i])
            ):
                start, count = int(data.moment_rowadr[out]), int(data.moment_rownnz[out])
                values = data.actuator_moment[start : start + count]
                scale = float(abs(values).max()) if count else 0.0
                for k in range(count):
                    if scale > 0 and abs(float(values[k])) > _RELATIVE_ZERO * scale:
                        reached[i].add(int(data.moment_colind[start + k]))
    return reached


def other_actuators(model: mujoco.MjModel, drives: Sequence[Any]) -> list[OtherActuator]:
    """Every actuator that is not one of ``drives``' and each joint its force reaches, in model order.

    Args:
        model: The compiled model.
        drives: Its drives (:func:`~drive_envelope._src.adapters.mujoco.params.model_drives`).
    """
    import mujoco

    ours = {a for d in drives for a in d.actuators}
    on_joint = {d.joint: d.name for d in drives}
    others = [i for i in range(model.nu) if i not in ours]
    reached = _reached_dofs(model, others)
    found = []
    for i in others:
        kind = "plugin" if int(model.actuator_plugin[i]) >= 0 else compiled_gain_kind(model, i)[0]
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) or f"#{i}"
        joints = sorted({int(model.dof_jntid[dof]) for dof in reached[i]})
        for joint in joints:
            joint_name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) or f"#{joint}"
            found.append(
                OtherActuator(
                    joint=joint_name,
                    actuator=name,
                    kind=kind,
                    transmission=_transmission(model, i),
                    drive=on_joint.get(joint_name),
                )
            )
    return found


def bypass_warnings(others: Sequence[OtherActuator]) -> list[str]:
    """One line per actuator whose force reaches a driven joint, naming the joints and drives."""
    by_actuator: dict[str, list[OtherActuator]] = {}
    for item in others:
        if item.drive is not None:
            by_actuator.setdefault(item.actuator, []).append(item)
    lines = []
    for name, items in by_actuator.items():
        joints = ", ".join(f"{o.joint!r} (drive {o.drive!r})" for o in items)
        lines.append(
            f"actuator {name!r} ({items[0].kind} on {items[0].transmission}) also acts on driven joint(s) "
            f"{joints}: its force bypasses the envelope (a drive's 'ff' input adds effort that counts)"
        )
    return lines


def is_bypass_warning(message: str) -> bool:
    """Whether ``message`` is the plugin's own warning of an actuator acting on a driven joint."""
    return message.startswith("drive_envelope.envelope: actuator ") and " also acts on joint " in message

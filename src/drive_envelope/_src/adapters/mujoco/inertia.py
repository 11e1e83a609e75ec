"""Each joint's effective inertia in a MuJoCo model: ``1/(M^-1)_ii`` at one configuration.

An explicit actuator that clips at the end of the step (PhysX's rule; ``clip="end_of_step"`` of the
Isaac Lab and mjlab actuators) needs each DOF's unit response: the velocity change a unit impulse
on that DOF alone gives within a step, with every other DOF free. That is the diagonal of the
inverse joint-space mass matrix, ``(M^-1)_ii``; its inverse is the effective inertia
[kg*m^2 or kg]. It is smaller than ``M_ii`` wherever the joint's motion couples to the others (a
floating base, the links beyond it), and it includes MuJoCo's ``armature`` (part of ``M``).

:func:`effective_inertia` computes it with MuJoCo's own factorization (``mj_makeM``, ``mj_factorM``
and ``mj_solveM`` on each joint's unit vector) on a scratch ``MjData``, so the caller's data is never
changed. mujoco is imported inside the function.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco

_WHERE = "effective_inertia"


def _configuration(model: mujoco.MjModel, data: Any, keyframe: str | int | None) -> Any:
    """The ``qpos`` to evaluate at: ``data``'s, else the keyframe's (the first by default), else ``qpos0``."""
    import mujoco

    if data is not None:
        if keyframe is not None:
            raise InputError(f"{_WHERE}: give data or keyframe, not both")
        if not isinstance(data, mujoco.MjData):
            raise InputError(
                f"{_WHERE}: argument 'data' is a {type(data).__name__}; expected a mujoco.MjData"
            )
        return np.array(data.qpos, dtype=np.float64)
    if keyframe is None:
        return np.array(model.key_qpos[0] if model.nkey else model.qpos0, dtype=np.float64)
    if isinstance(keyframe, str):
        key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
        if key < 0:
            names = [model.key(k).name for k in range(model.nkey)]
            raise InputError(f"{_WHERE}: keyframe {keyframe!r} is not in the model; its keyframes: {names}")
    elif isinstance(keyframe, (int, np.integer)) and not isinstance(keyframe, bool):
        key = int(keyframe)
        if not 0 <= key < model.nkey:
            raise InputError(f"{_WHERE}: keyframe {key} out of range; the model has {model.nkey} keyframes")
    else:
        raise InputError(f"{_WHERE}: keyframe = {keyframe!r}; expected a keyframe name or index")
    return np.array(model.key_qpos[key], dtype=np.float64)


def _joint_ids(model: mujoco.MjModel, joints: Sequence[str | int] | str | int | None) -> list[int]:
    """The ids of the joints asked for; None: every hinge and slide (a free or ball joint has no ``ii``)."""
    import mujoco

    one_dof = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    if joints is None:
        return [j for j in range(model.njnt) if int(model.jnt_type[j]) in one_dof]
    items = [joints] if isinstance(joints, (str, int)) else list(joints)
    ids = []
    for item in items:
        if isinstance(item, str):
            joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, item)
            if joint < 0:
                raise InputError(f"{_WHERE}: joint {item!r} is not in the model")
        elif isinstance(item, (int, np.integer)) and not isinstance(item, bool) and 0 <= item < model.njnt:
            joint = int(item)
        else:
            raise InputError(
                f"{_WHERE}: joint {item!r}; expected a joint name or an index below {model.njnt}"
            )
        if int(model.jnt_type[joint]) not in one_dof:
            raise InputError(
                f"{_WHERE}: joint {model.joint(joint).name or joint!r} is a free or ball joint; "
                "expected a hinge or slide joint (one DOF)"
            )
        ids.append(joint)
    return ids


def effective_inertia(
    model: mujoco.MjModel,
    data: mujoco.MjData | None = None,
    joints: Sequence[str | int] | str | int | None = None,
    *,
    keyframe: str | int | None = None,
) -> dict[str, float]:
    """Each joint's effective inertia ``1/(M^-1)_ii`` [kg*m^2 or kg], armature included.

    The end-of-step clip's unit response is its inverse. Pass the result as Isaac Lab's
    ``PerformanceEnvelopeActuatorCfg(effective_inertia=...)`` when validating a robot in MuJoCo (a
    ``{joint: value}`` dict; Isaac Lab reads the keys as regexes, which a plain joint name matches).

    Args:
        model: The compiled model (SI).
        data: Evaluate at this data's ``qpos`` (it is not changed). None: at ``keyframe``.
        joints: Joint names or ids (hinge or slide), in the order wanted. None: every hinge and
            slide joint of the model, in model order.
        keyframe: A keyframe name or index, used when ``data`` is None. None: the model's first
            keyframe, else ``qpos0``.

    Returns:
        ``{joint name: effective inertia}`` [kg*m^2 for a hinge, kg for a slide], in ``joints``'
        order (an unnamed joint is keyed by its id as a string).

    Raises:
        InputError: an unknown joint or keyframe, a free or ball joint, both ``data`` and
            ``keyframe``, or a joint whose ``(M^-1)_ii`` is not positive and finite.
    """
    import mujoco

    if not isinstance(model, mujoco.MjModel):
        raise InputError(f"{_WHERE}: argument 'model' is a {type(model).__name__}; expected a mujoco.MjModel")
    qpos = _configuration(model, data, keyframe)
    ids = _joint_ids(model, joints)
    scratch = mujoco.MjData(model)
    scratch.qpos[:] = qpos
    # M depends on the configuration only: positions, com-based inertias, then M and its factor
    mujoco.mj_kinematics(model, scratch)
    mujoco.mj_comPos(model, scratch)
    mujoco.mj_makeM(model, scratch)
    mujoco.mj_factorM(model, scratch)
    dofs = [int(model.jnt_dofadr[j]) for j in ids]
    if not dofs:
        return {}
    units = np.zeros((len(dofs), model.nv))
    units[np.arange(len(dofs)), dofs] = 1.0
    solved = np.zeros_like(units)
    mujoco.mj_solveM(model, scratch, solved, units)  # rows: M^-1 e_i
    result: dict[str, float] = {}
    for row, (joint, dof) in enumerate(zip(ids, dofs, strict=True)):
        response = float(solved[row, dof])
        name = model.joint(joint).name or str(joint)
        if not 0.0 < response < np.inf:
            raise InputError(
                f"{_WHERE}: joint {name!r} has (M^-1)_ii = {response!r}; expected > 0 and finite "
                "(a massless chain without armature?)"
            )
        result[name] = 1.0 / response
    return result

"""The actuators a model already has on a joint: what they are, their gains, replacing them.

A second actuator on a driven joint would add force the envelope never sees, so a drive replaces
the joint's actuators (``add_drive(..., replace=True)``, ``drive-envelope mujoco apply``). The first
is converted in place into the drive's effort actuator: it keeps its name, place (so ``data.ctrl``
keeps its layout), group, delay and, where its control keeps its meaning, its control range (a
control that becomes a target position takes the joint's range), and becomes a plugin actuator of the main
default class (so no class of the robot can give it a ``forcerange`` or a ``biastype``); the others
are deleted. Keyframe controls follow: a deleted actuator's column goes, a new input's column is
added (the joint's key position for ``pos``, 0 for ``vel`` and ``ff``), and a motor's torque
becomes the joint's key position (a key without ``ctrl``, whose controls MuJoCo reads as 0, gets one
where a control changes meaning).

Gains and control ranges are read from the model MuJoCo compiled when one is given: a ``position``
actuator with ``dampratio`` has its kv only there, and an ``inheritrange`` control range is the joint's
range only there; the spec holds the ratio and the factor.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.mujoco.loader import PLUGIN_NAME
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco


@dataclass(frozen=True, kw_only=True, slots=True)
class ExistingActuator:
    """An actuator with a joint transmission on a joint that is to be driven."""

    index: int
    """Position in ``spec.actuators`` (and in ``data.ctrl`` order)."""
    name: str
    """Its name, or ``#index`` if it has none."""
    kind: str
    """``"position"`` (PD on a target position), ``"velocity"`` (damper on a target velocity),
    ``"motor"`` (force from ctrl), ``"drive"`` (already this plugin) or ``"other"``."""
    stiffness: float | None
    """Its position gain kp [N*m/rad or N/m], None if it has none."""
    damping: float | None
    """Its velocity gain kv [N*m*s/rad or N*s/m], None if it has none."""


def is_drive(spec: mujoco.MjSpec, actuator: Any) -> bool:
    """Whether an ``MjsActuator`` is an actuator of this plugin (directly or through an instance)."""
    if not actuator.plugin.active:
        return False
    if actuator.plugin.plugin_name:
        return bool(actuator.plugin.plugin_name == PLUGIN_NAME)
    return any(p.name == actuator.plugin.name and p.plugin_name == PLUGIN_NAME for p in spec.plugins)


def compiled_id(model: mujoco.MjModel | None, actuator: Any, index: int) -> int:
    """The id in ``model`` (compiled from the spec before any edit) of spec actuator ``index``, or -1."""
    import mujoco

    if model is None:
        return -1
    if actuator.name:
        return int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator.name))
    return index if index < model.nu else -1


def _kind(
    spec: mujoco.MjSpec, actuator: Any, model: mujoco.MjModel | None = None, index: int = -1
) -> tuple[str, float | None, float | None]:
    """(kind, kp, kv) of an ``MjsActuator`` from its gain and bias (MuJoCo's shortcuts' layout).

    With ``model`` (compiled from ``spec``), the compiled gain and bias are read: ``dampratio``
    becomes a kv there, and in the spec it is a positive ``biasprm[2]`` that reads as no PD.
    """
    if is_drive(spec, actuator):
        return "drive", float(actuator.dynprm[4]), float(actuator.dynprm[5])
    if actuator.plugin.active:
        return "other", None, None
    i = compiled_id(model, actuator, index)
    if model is not None and i >= 0:
        return compiled_gain_kind(model, i)
    return gain_kind(
        int(actuator.gaintype), int(actuator.biastype), list(actuator.gainprm), list(actuator.biasprm)
    )


def describe_kind(kind: str) -> str:
    """``kind`` as a phrase for messages: "a position actuator", "a motor", "not a PD actuator"."""
    return {
        "position": "a position actuator",
        "velocity": "a velocity actuator",
        "motor": "a motor",
        "drive": "an envelope drive",
    }.get(kind, "neither a motor nor a PD actuator (its gain and bias have no kp and kv to read)")


def gain_kind(
    gaintype: int, biastype: int, gainprm: list[float], biasprm: list[float]
) -> tuple[str, float | None, float | None]:
    """(kind, kp, kv) of a native actuator from its gain and bias (MuJoCo's shortcuts' layout)."""
    import mujoco

    fixed = gaintype == int(mujoco.mjtGain.mjGAIN_FIXED)
    if fixed and biastype == int(mujoco.mjtBias.mjBIAS_NONE):
        return "motor", None, None
    if fixed and biastype == int(mujoco.mjtBias.mjBIAS_AFFINE) and biasprm[0] == 0:
        kp, kv = gainprm[0], 0.0 - biasprm[2]  # not -0.0
        if kp > 0 and biasprm[1] == -kp and kv >= 0:
            return "position", kp, kv  # position, general affine PD: kp*(u - q) - kv*qdot
        if kp > 0 and biasprm[1] == 0 and kv == kp:
            return "velocity", 0.0, kp  # velocity: kv*(u - qdot)
    return "other", None, None


def compiled_gain_kind(model: mujoco.MjModel, i: int) -> tuple[str, float | None, float | None]:
    """:func:`gain_kind` of actuator ``i`` of a compiled model."""
    gainprm = [float(v) for v in model.actuator_gainprm[i]]
    biasprm = [float(v) for v in model.actuator_biasprm[i]]
    return gain_kind(int(model.actuator_gaintype[i]), int(model.actuator_biastype[i]), gainprm, biasprm)


def joint_actuators(
    spec: mujoco.MjSpec, joint: str, model: mujoco.MjModel | None = None
) -> list[ExistingActuator]:
    """The actuators of ``spec`` with a joint transmission on ``joint``, in model order.

    Args:
        spec: The model.
        joint: The joint's name.
        model: ``spec`` compiled before any edit, to read the gains MuJoCo computed (``dampratio``);
            None reads the spec's numbers.
    """
    import mujoco

    found = []
    for index, actuator in enumerate(spec.actuators):
        if actuator.target != joint or actuator.trntype not in (
            mujoco.mjtTrn.mjTRN_JOINT,
            mujoco.mjtTrn.mjTRN_JOINTINPARENT,
        ):
            continue
        kind, kp, kv = _kind(spec, actuator, model, index)
        found.append(
            ExistingActuator(
                index=index, name=actuator.name or f"#{index}", kind=kind, stiffness=kp, damping=kv
            )
        )
    return found


def primary_actuator(found: list[ExistingActuator]) -> ExistingActuator:
    """The actuator that becomes the drive: the first with gains, else the first.

    A drive comes before a position or velocity actuator; a motor beside a position actuator then
    does not take its place (it has no gains to keep).
    """
    for kinds in (("drive",), ("position", "velocity")):
        for actuator in found:
            if actuator.kind in kinds:
                return actuator
    return found[0]


def feed_forward_motor(found: list[ExistingActuator], primary: ExistingActuator) -> ExistingActuator | None:
    """A motor after ``primary`` on the same joint that can become the drive's ``ff`` input, or None.

    Its control is an effort before and after (now counted inside the envelope), so it keeps its
    name, slot and keyframe values. It must come after the drive's actuator: the plugin gives a
    joint's actuators to the inputs in order of appearance.
    """
    if primary.kind not in ("position", "velocity"):
        return None
    for actuator in found:
        if actuator.kind == "motor" and actuator.index > primary.index:
            return actuator
    return None


def convert_channel(spec: mujoco.MjSpec, index: int, *, instance: str) -> bool:
    """Turn motor ``index`` into a zero-force input channel of ``instance`` in place (keeps its name).

    Returns:
        False (nothing changed) if it cannot carry a joint-side effort: a gear other than 1 or
        activation dynamics.
    """
    import mujoco

    actuator = spec.actuators[index]
    gear = list(actuator.gear)
    if gear[0] != 1 or any(gear[1:]) or actuator.dyntype != mujoco.mjtDyn.mjDYN_NONE:
        return False
    ctrlrange, limited = [float(v) for v in actuator.ctrlrange], actuator.ctrllimited
    _make_plugin_actuator(spec, actuator, instance, [1.0] + [0.0] * 9)
    actuator.ctrllimited, actuator.ctrlrange = limited, ctrlrange
    return True


def _make_plugin_actuator(spec: mujoco.MjSpec, actuator: Any, instance: str, dynprm: list[float]) -> None:
    """Make ``actuator`` a plugin actuator of ``instance`` in the main default class, in place.

    No gain, bias or force range of its own remains (its force is the plugin's); its control range
    is the caller's to set.
    """
    import mujoco

    actuator.classname = spec.default
    actuator.plugin.plugin_name = PLUGIN_NAME
    actuator.plugin.name = instance
    actuator.plugin.active = True
    actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    actuator.gainprm = [1.0] + [0.0] * 9
    actuator.biastype = mujoco.mjtBias.mjBIAS_NONE
    actuator.biasprm = [0.0] * 10
    actuator.dynprm = dynprm
    actuator.actdim = -1
    actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_FALSE
    actuator.forcerange = [0.0, 0.0]


def _joint_range(spec: mujoco.MjSpec, joint: str) -> tuple[float, float] | None:
    """The joint's range in radians (or metres), None if it is not limited."""
    import mujoco

    element = spec.joint(joint)
    low, high = float(element.range[0]), float(element.range[1])
    if element.limited == mujoco.mjtLimited.mjLIMITED_FALSE or not low < high:
        return None
    hinge = element.type == mujoco.mjtJoint.mjJNT_HINGE
    if hinge and spec.compiler.degree:
        return math.radians(low), math.radians(high)
    return low, high


def convert_actuator(
    spec: mujoco.MjSpec,
    index: int,
    *,
    name: str,
    instance: str,
    dynprm: list[float],
    where: str,
    model: mujoco.MjModel | None = None,
    control: str = "pos",
) -> None:
    """Turn actuator ``index`` into the effort actuator of a drive on its joint, in place.

    Its control range is kept where its control keeps its meaning; a control that changes meaning
    (a motor's torque or a velocity actuator's speed becoming a target position) takes the joint's
    range for a position and no range otherwise. A ``forcerange`` tighter than the envelope's
    max_effort, which the drive replaces, is a warning.

    Args:
        spec: The model, edited in place.
        index: The actuator's position in ``spec.actuators``.
        name: The drive's name.
        instance: The plugin instance.
        dynprm: The drive's numbers.
        where: Start of error messages.
        model: ``spec`` compiled before any edit: its control range is the one kept (an
            ``inheritrange`` range exists only there), None: the spec's.
        control: The drive input this actuator's control becomes (``"pos"``, ``"vel"``, ``"ff"``).

    Raises:
        InputError: a gear other than 1 (the drive works on the joint side).
    """
    import mujoco

    actuator = spec.actuators[index]
    kind, _, _ = _kind(spec, actuator, model, index)
    gear = list(actuator.gear)
    if gear[0] != 1 or any(gear[1:]):
        raise InputError(
            f"{where}: actuator {actuator.name or index!r} has gear {gear[0]:g}; a drive works on the "
            "joint side (gear 1): scale its gains and envelope by the gear and set gear to 1 first"
        )
    if actuator.dyntype != mujoco.mjtDyn.mjDYN_NONE:
        warnings.warn(
            f"{where}: actuator {actuator.name or index!r} had activation dynamics "
            f"({str(actuator.dyntype.name).removeprefix('mjDYN_').lower()}); the drive has none",
            stacklevel=4,
        )
    ctrlrange = [float(v) for v in actuator.ctrlrange]
    limited = actuator.ctrllimited
    i = compiled_id(model, actuator, index)
    if model is not None and i >= 0:
        # the range MuJoCo uses: inheritrange and autolimits resolved
        ctrlrange = [float(v) for v in model.actuator_ctrlrange[i]]
        limited = (
            mujoco.mjtLimited.mjLIMITED_TRUE
            if bool(model.actuator_ctrllimited[i])
            else mujoco.mjtLimited.mjLIMITED_FALSE
        )
    meaning = {"position": "pos", "velocity": "vel", "motor": "ff"}.get(kind, control)
    if meaning != control:
        # its control was a force or a speed (or a position) and is now something else: a range
        # kept would clip the new control by the old one's numbers; a position gets the joint's
        joint_range = _joint_range(spec, actuator.target) if control == "pos" else None
        limited = (
            mujoco.mjtLimited.mjLIMITED_FALSE if joint_range is None else mujoco.mjtLimited.mjLIMITED_TRUE
        )
        ctrlrange = [0.0, 0.0] if joint_range is None else list(joint_range)
    _warn_tighter_force_range(spec, actuator, index, dynprm[0], where)
    _make_plugin_actuator(spec, actuator, instance, dynprm)
    actuator.name = name
    actuator.dyntype = mujoco.mjtDyn.mjDYN_NONE
    # an activation range without activation dynamics fails MuJoCo's compile (intvelocity's)
    actuator.actlimited, actuator.actrange = mujoco.mjtLimited.mjLIMITED_FALSE, [0.0, 0.0]
    actuator.ctrllimited = limited
    actuator.ctrlrange = ctrlrange
    actuator.inheritrange = 0.0  # the range is explicit now (a class's inheritrange must not redo it)


def _warn_tighter_force_range(spec: mujoco.MjSpec, actuator: Any, index: int, cap: float, where: str) -> None:
    """Warn when the replaced actuator's ``forcerange`` limited the joint more than the drive will.

    The drive replaces the actuator and its force limit (MuJoCo's clamp after the plugin would
    undo the implicit solve), so a tighter ``forcerange`` would be lost without a word. ``cap`` is
    the drive's ``dynprm[0]`` (max_effort, -1 for no limit).
    """
    import mujoco

    limited = int(actuator.forcelimited)
    low, high = (float(x) for x in actuator.forcerange)
    if limited == int(mujoco.mjtLimited.mjLIMITED_FALSE) or not low < high:
        return  # no force limit (auto with an empty range is none, as in MuJoCo's compiler)
    if limited == int(mujoco.mjtLimited.mjLIMITED_AUTO) and not spec.compiler.autolimits:
        return
    max_effort = math.inf if cap < 0 else cap
    tightest = min(abs(low), abs(high))
    if tightest < max_effort * (1.0 - 1e-9):
        slide = spec.joint(actuator.target).type == mujoco.mjtJoint.mjJNT_SLIDE
        unit = "N" if slide else "N*m"
        warnings.warn(
            f"{where}: actuator {actuator.name or index!r} had forcerange [{low:g}, {high:g}] {unit}, "
            f"tighter than the envelope's max_effort {max_effort:g} {unit}; the drive replaces it, so "
            f"the joint's limit becomes {max_effort:g} {unit} (lower max_effort to keep {tightest:g})",
            stacklevel=4,
        )


@dataclass(kw_only=True, slots=True)
class KeyPlan:
    """How the actuator list changes, to rewrite every keyframe's ``ctrl`` to match."""

    count: int
    """Number of actuators before the change."""
    deleted: set[int]
    """Positions (before the change) of deleted actuators."""
    hold: dict[int, str]
    """Positions of converted motors -> their joint (the key's position of the joint replaces the torque)."""
    appended: list[tuple[str, str]]
    """New actuators, in order: (joint, input)."""


def update_keyframes(spec: mujoco.MjSpec, model: mujoco.MjModel | None, plan: KeyPlan) -> None:
    """Rewrite every keyframe's ``ctrl`` for the new actuator list (see :class:`KeyPlan`).

    Args:
        spec: The edited spec.
        model: The model compiled before the edit (for the joints' qpos addresses), or None.
        plan: What changed.
    """
    import mujoco

    for key in spec.keys:
        ctrl = [float(v) for v in key.ctrl]
        if not ctrl and plan.count and (plan.hold or any(name == "pos" for _, name in plan.appended)):
            # MuJoCo reads a key without ctrl as zeros; where a zero changes meaning (a motor's
            # torque becomes a target position) write the key's controls out
            ctrl = [0.0] * plan.count
        if len(ctrl) != plan.count:
            continue  # no ctrl in this key (MuJoCo uses the defaults) or already inconsistent
        qpos = [float(v) for v in key.qpos]

        def position(joint: str, qpos: list[float] = qpos) -> float:
            if model is None or not qpos:
                return 0.0
            index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint)
            return qpos[int(model.jnt_qposadr[index])] if index >= 0 else 0.0

        kept = [
            position(plan.hold[i]) if i in plan.hold else v
            for i, v in enumerate(ctrl)
            if i not in plan.deleted
        ]
        added = [position(joint) if name == "pos" else 0.0 for joint, name in plan.appended]
        key.ctrl = kept + added

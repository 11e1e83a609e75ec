"""Adding PhysX drives with the envelope to a ``mujoco.MjSpec``.

MuJoCo says "units are unspecified"; drive_envelope assumes SI throughout (radians, metres,
seconds, kilograms), so a model must be written in SI for the envelope's numbers to mean what the
datasheet says. Angles in the plugin are always radians, whatever ``<compiler angle>`` says.

One drive is one hinge or slide joint, fed by one actuator per control input (``pos``, ``vel``,
``ff``, in that order, MuJoCo's pid convention). The first actuator carries the drive's total
effort (drive + feed-forward) in ``actuator_force`` and its six numbers in ``actuator_dynprm``
(:mod:`~drive_envelope._src.adapters.mujoco.params`); the others are control channels with zero
force. Drives with the same inputs and drive type share one plugin instance
(``drive_envelope_<inputs>``), whatever their envelopes: the plugin solves every drive of a model
together anyway, and one instance costs MuJoCo least.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.mujoco.existing import (
    KeyPlan,
    convert_actuator,
    convert_channel,
    feed_forward_motor,
    joint_actuators,
    primary_actuator,
    update_keyframes,
)
from drive_envelope._src.adapters.mujoco.handle import MjDrive
from drive_envelope._src.adapters.mujoco.loader import PLUGIN_NAME
from drive_envelope._src.adapters.mujoco.params import drive_dynprm, gain_units
from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import read_quantity

if TYPE_CHECKING:
    import mujoco

INPUTS = ("pos", "vel", "ff")
"""Control inputs in canonical order: target position, target velocity, feed-forward effort."""


def plugin_config(*, drive_type: DriveType = "force", inputs: Sequence[str] = ("pos",)) -> dict[str, str]:
    """The ``<config>`` attributes of a plugin instance, as MJCF strings.

    The numbers are not here: each drive has them in its actuator's ``dynprm``
    (:func:`~drive_envelope._src.adapters.mujoco.params.drive_dynprm`).

    Args:
        drive_type: ``"force"`` or ``"acceleration"``.
        inputs: Control inputs, a subset of ``("pos", "vel", "ff")``.
    """
    return {"drive_type": drive_type, "input": " ".join(inputs)}


def default_instance(drive_type: DriveType, inputs: Sequence[str]) -> str:
    """Name of the shared instance for drives with these inputs: ``drive_envelope_pos_vel`` etc."""
    suffix = "_acceleration" if drive_type == "acceleration" else ""
    return "drive_envelope_" + "_".join(inputs) + suffix


def _read_inputs(inputs: Sequence[str] | str) -> tuple[str, ...]:
    names = tuple(inputs.replace(",", " ").split()) if isinstance(inputs, str) else tuple(inputs)
    unknown = [n for n in names if n not in INPUTS]
    if not names or unknown or len(set(names)) != len(names):
        raise InputError(f"add_drive: argument 'inputs': expected a subset of {INPUTS}, got {inputs!r}")
    return tuple(n for n in INPUTS if n in names)


def _resolve_envelope(
    envelope: PerformanceEnvelope | str | None, datasheet: str | None
) -> PerformanceEnvelope:
    if (envelope is None) == (datasheet is None):
        raise InputError(
            "add_drive: give exactly one of 'envelope' (an envelope) or 'datasheet' (a file or catalog name)"
        )
    from drive_envelope._src.datasheet.resolve import resolve_envelope

    if envelope is not None:
        return resolve_envelope(envelope, where="add_drive: argument 'envelope'")
    assert datasheet is not None
    return resolve_envelope(datasheet, where="add_drive: argument 'datasheet'")


def add_drive(
    spec: mujoco.MjSpec,
    joint: str,
    *,
    stiffness: float | str,
    damping: float | str,
    envelope: PerformanceEnvelope | str | None = None,
    datasheet: str | None = None,
    drive_type: DriveType = "force",
    inputs: Sequence[str] | str = ("pos",),
    name: str | None = None,
    instance: str | None = None,
    effort_sensor: bool = True,
    replace: bool = False,
) -> MjDrive:
    """Drive ``joint`` of ``spec`` with a PhysX drive limited by a performance envelope.

    Adds one actuator per input to the plugin instance shared by drives with the same inputs (or
    ``instance``), and by default an ``actuatorfrc`` sensor named ``<name>_effort`` on the first
    actuator. Loads the plugin.

    Args:
        spec: The model being built; it must already contain ``joint`` (hinge or slide).
        joint: Joint name.
        stiffness: Drive stiffness, SI number or string with units ([N*m/rad or N/m]; [1/s^2] for
            an acceleration drive), at most 1e12 in SI.
        damping: Drive damping, SI number or string with units ([N*m*s/rad or N*s/m]; [1/s]).
        envelope: A :class:`PerformanceEnvelope`, or an envelope/datasheet file or catalog name.
        datasheet: A datasheet file or catalog name (instead of ``envelope``).
        drive_type: ``"force"`` or ``"acceleration"``.
        inputs: Control inputs, a subset of ``("pos", "vel", "ff")`` (default ``("pos",)``).
        name: Drive (first actuator) name; default the joint's name, or the name of the actuator
            it replaces.
        instance: Plugin instance name (default ``drive_envelope_<inputs>``, shared).
        effort_sensor: Whether to add the ``actuatorfrc`` sensor (needed for rollouts).
        replace: Replace the joint's existing actuators (the first is converted in place, keeping
            its name and place in ``data.ctrl``; see
            :mod:`~drive_envelope._src.adapters.mujoco.existing`). Without it an existing actuator
            on the joint is an error: its force would bypass the envelope.

    Returns:
        The :class:`MjDrive` handle.

    Raises:
        InputError: unknown joint, a joint that is not a hinge or slide, an envelope for the other
            joint type, bad gains or inputs, an existing actuator on the joint without ``replace``.
        PluginError: the plugin library is missing or stale.
    """
    drives = add_drives(
        spec,
        [joint],
        stiffness=stiffness,
        damping=damping,
        envelope=envelope,
        datasheet=datasheet,
        drive_type=drive_type,
        inputs=inputs,
        instance=instance,
        names=None if name is None else [name],
        effort_sensor=effort_sensor,
        replace=replace,
    )
    return drives[0]


def add_drives(
    spec: mujoco.MjSpec,
    joints: Sequence[str],
    *,
    stiffness: float | str,
    damping: float | str,
    envelope: PerformanceEnvelope | str | None = None,
    datasheet: str | None = None,
    drive_type: DriveType = "force",
    inputs: Sequence[str] | str = ("pos",),
    instance: str | None = None,
    names: Sequence[str] | None = None,
    effort_sensor: bool = True,
    replace: bool = False,
) -> tuple[MjDrive, ...]:
    """Drive several joints with the same drive and envelope: :func:`add_drive` for each joint.

    Args:
        spec: The model being built.
        joints: Hinge or slide joint names, at least one, no repeats.
        stiffness: See :func:`add_drive` [N*m/rad or N/m].
        damping: See :func:`add_drive` [N*m*s/rad or N*s/m].
        envelope: See :func:`add_drive`.
        datasheet: See :func:`add_drive`.
        drive_type: See :func:`add_drive`.
        inputs: See :func:`add_drive`.
        instance: See :func:`add_drive`.
        names: Drive (first actuator) names, one per joint (default: see :func:`add_drive`).
        effort_sensor: See :func:`add_drive`.
        replace: See :func:`add_drive`.

    Returns:
        One :class:`MjDrive` per joint, in the order of ``joints``.

    Raises:
        InputError: see :func:`add_drive`; also no joints, repeated joints or names of the wrong length.
        PluginError: the plugin library is missing or stale.
    """
    import mujoco

    from drive_envelope._src.adapters.mujoco.loader import load_plugin

    load_plugin()
    if not isinstance(spec, mujoco.MjSpec):  # an MjModel or XML text: a TypeError deep in the edit
        hint = (
            " (mujoco.MjSpec.from_file(path) or from_string(xml))"
            if isinstance(spec, (str, mujoco.MjModel))
            else ""
        )
        raise InputError(
            f"add_drive: argument 'spec': expected a mujoco.MjSpec{hint}, got {type(spec).__name__}"
        )
    joints = list(joints)
    labels: list[str | None] = list(names) if names is not None else [None] * len(joints)
    if not joints or len(set(joints)) != len(joints) or len(labels) != len(joints):
        raise InputError(
            f"add_drives: argument 'joints': expected distinct joint names and as many names, got {joints!r}"
        )
    where = f"add_drive(joint={joints[0]!r})"
    env = _resolve_envelope(envelope, datasheet)
    joint_type = _joint_type(spec, joints[0], env)
    for joint in joints[1:]:
        _joint_type(spec, joint, env)
    if drive_type not in ("force", "acceleration"):
        raise InputError(
            f"{where}: argument 'drive_type': expected 'force' or 'acceleration', got {drive_type!r}"
        )
    k_unit, c_unit = gain_units(joint_type, drive_type)
    k = read_quantity(stiffness, k_unit, f"{where}: argument 'stiffness'")
    c = read_quantity(damping, c_unit, f"{where}: argument 'damping'")
    for label, value, unit in (("stiffness", k, k_unit), ("damping", c, c_unit)):
        if not math.isfinite(value) or not 0.0 <= value <= 1e12:
            raise InputError(
                f"{where}: argument {label!r}: expected a number in [0, 1e12] [{unit}], got {value!r}"
            )
    dynprm = drive_dynprm(env, stiffness=k, damping=c, where=where)
    channels = _read_inputs(inputs)
    if k > 0.0 and "pos" not in channels:
        # PhysX's drive law with no target position input: the target is 0, so the spring holds
        # the joint at 0 against the velocity target (v settles at 0, q at c*v_target/k)
        warnings.warn(
            f"{where}: stiffness {k:g} {k_unit} but no 'pos' input: the drive's target position is 0, "
            "so it pulls the joint back to 0 (a velocity drive tracks its target only with stiffness 0; "
            "or add 'pos' to inputs)",
            stacklevel=3,
        )
    # the model as MuJoCo compiles it before the edit: dampratio gains, inheritrange control ranges
    # and the joints' qpos addresses for keyframes exist only there
    before = compile_copy(spec) if replace and len(spec.actuators) else None
    existing = {joint: joint_actuators(spec, joint, before) for joint in joints}
    for joint, found in existing.items():
        if found and not replace:
            first = found[0]
            raise InputError(
                f"add_drive(joint={joint!r}): joint {joint!r} already has actuator {first.name!r} "
                f"({first.kind}), whose force would bypass the envelope; pass replace=True to replace "
                "it, or add effort that counts through the drive's 'ff' input"
            )
    instance_name = instance or default_instance(drive_type, channels)
    _ensure_instance(spec, instance_name, plugin_config(drive_type=drive_type, inputs=channels), where)

    plan = KeyPlan(count=len(spec.actuators), deleted=set(), hold={}, appended=[])
    drives = []
    for joint, given in zip(joints, labels, strict=True):
        found = existing[joint]
        primary = primary_actuator(found) if found else None
        drive_name = given or (primary.name if primary and not primary.name.startswith("#") else joint)
        actuators = tuple(drive_name if i == 0 else f"{drive_name}_{n}" for i, n in enumerate(channels))
        # a motor beside the PD actuator becomes the 'ff' input in place (same slot, still an effort)
        motor = feed_forward_motor(found, primary) if primary and channels[1:] == ("ff",) else None
        if motor is not None and not convert_channel(spec, motor.index, instance=instance_name):
            motor = None
        if motor is not None:
            actuators = (actuators[0], motor.name)
        _check_free_names(spec, actuators, {a.index for a in found}, where)
        start = 0
        if primary is not None:
            convert_actuator(
                spec,
                primary.index,
                name=actuators[0],
                instance=instance_name,
                dynprm=dynprm,
                where=where,
                model=before,
                control=channels[0],
            )
            if primary.kind in ("motor", "velocity") or channels[0] != "pos":
                plan.hold[primary.index] = joint if channels[0] == "pos" else ""
            gone = [a for a in found if a is not primary and a is not motor]
            plan.deleted.update(a.index for a in gone)
            if gone:
                dropped = {a.index for a in gone}
                later = sum(1 for i in range(min(dropped) + 1, plan.count) if i not in dropped)
                shift = (
                    f"; the {later} actuator(s) after them move down {len(gone)} control slot(s)"
                    if later > 0
                    else ""
                )
                warnings.warn(
                    f"add_drive(joint={joint!r}): actuator(s) "
                    f"{', '.join(f'{a.name!r} ({a.kind})' for a in gone)} deleted: the drive replaces "
                    f"{primary.name!r} and their force would bypass the envelope{shift}",
                    stacklevel=3,
                )
            start = 2 if motor is not None else 1
        for i, actuator_name in enumerate(actuators[start:], start):
            actuator = spec.add_actuator(name=actuator_name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
            actuator.plugin.plugin_name = PLUGIN_NAME
            actuator.plugin.name = instance_name
            actuator.plugin.active = True
            if i == 0:
                actuator.dynprm = dynprm
            plan.appended.append((joint, channels[i]))
        drives.append(
            MjDrive(
                name=actuators[0],
                joint=joint,
                instance=instance_name,
                actuators=actuators,
                inputs=channels,
                envelope=env,
                stiffness=k,
                damping=c,
                drive_type=drive_type,
                effort_sensor=_effort_sensor(spec, actuators[0]) if effort_sensor else "",
                replaced=tuple(a.name for a in found),
            )
        )
    for index in sorted(plan.deleted, reverse=True):
        spec.delete(spec.actuators[index])
    update_keyframes(spec, before, plan)
    return tuple(drives)


def compile_copy(spec: mujoco.MjSpec) -> mujoco.MjModel | None:
    """``spec`` compiled as it is (a copy: the spec is not touched), None if it does not compile."""
    try:
        return spec.copy().compile()
    except ValueError:
        return None  # keyframe positions then read as 0: the model did not compile before the edit


def _ensure_instance(spec: mujoco.MjSpec, name: str, config: dict[str, str], where: str) -> None:
    """Use the instance ``name`` if it exists with the same configuration, else create it."""
    spec.activate_plugin(PLUGIN_NAME)
    for plugin in spec.plugins:
        if plugin.name != name:
            continue
        current = dict(plugin.config)
        current.setdefault("drive_type", "force")
        current.setdefault("input", "pos")
        if plugin.plugin_name != PLUGIN_NAME or current != config:
            raise InputError(
                f"{where}: argument 'instance': plugin instance {name!r} exists with another "
                f"plugin or configuration ({plugin.plugin_name}, {dict(plugin.config)})"
            )
        return
    plugin = spec.add_plugin(name=name, plugin_name=PLUGIN_NAME, active=True)
    plugin.config = config


def _check_free_names(spec: mujoco.MjSpec, names: Sequence[str], replaced: set[int], where: str) -> None:
    taken = {a.name: i for i, a in enumerate(spec.actuators) if a.name}
    for name in names:
        if name in taken and taken[name] not in replaced:
            raise InputError(
                f"{where}: an actuator named {name!r} exists already; give the drive another name"
            )


def _effort_sensor(spec: mujoco.MjSpec, actuator: str) -> str:
    """Add (or reuse) the ``actuatorfrc`` sensor ``<actuator>_effort``; returns its name."""
    import mujoco

    name = f"{actuator}_effort"
    if spec.sensor(name) is None:
        spec.add_sensor(
            name=name,
            type=mujoco.mjtSensor.mjSENS_ACTUATORFRC,
            objtype=mujoco.mjtObj.mjOBJ_ACTUATOR,
            objname=actuator,
        )
    return name


def _joint_type(spec: mujoco.MjSpec, joint: str, env: PerformanceEnvelope) -> str:
    """``"revolute"`` or ``"prismatic"`` for a hinge or slide joint of ``spec`` that fits ``env``."""
    import mujoco

    where = f"add_drive(joint={joint!r})"
    element: Any = spec.joint(joint)
    if element is None:
        raise InputError(f"{where}: the spec has no joint named {joint!r}")
    kinds = {mujoco.mjtJoint.mjJNT_HINGE: "revolute", mujoco.mjtJoint.mjJNT_SLIDE: "prismatic"}
    if element.type not in kinds:
        kind = str(element.type.name).removeprefix("mjJNT_").lower()
        raise InputError(f"{where}: joint {joint!r} is a {kind} joint; expected a hinge or slide joint")
    joint_type = kinds[element.type]
    if env.joint != joint_type:
        raise InputError(f"{where}: the envelope is for a {env.joint} joint but {joint!r} is {joint_type}")
    return joint_type

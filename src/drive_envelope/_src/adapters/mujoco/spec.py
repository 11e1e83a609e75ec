"""Adding PhysX drives with the envelope to a ``mujoco.MjSpec`` and reading them back.

MuJoCo says "units are unspecified"; drive_envelope assumes SI throughout (radians, metres,
seconds, kilograms), so a model must be written in SI for the envelope's numbers to mean what the
datasheet says. Angles in the plugin are always radians, whatever ``<compiler angle>`` says.

One drive is one hinge or slide joint of a plugin instance, fed by one actuator per control input
(``pos``, ``vel``, ``ff``, in that order, MuJoCo's pid convention). The first actuator carries the
drive's total effort (drive + feed-forward) in ``actuator_force``; the others are control channels
with zero force. Joints with the same drive and envelope can share one instance
(:func:`add_drives`), which MuJoCo steps faster than one instance per joint.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.units import to_si

if TYPE_CHECKING:
    import mujoco

__all__ = [
    "INPUTS",
    "MjDrive",
    "add_drive",
    "add_drives",
    "drive_state",
    "plugin_config",
    "rollout_operating_points",
]

INPUTS = ("pos", "vel", "ff")
"""Control inputs in canonical order: target position, target velocity, feed-forward effort."""
PLUGIN_NAME = "drive_envelope.envelope"

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, kw_only=True, slots=True)
class MjDrive:
    """A drive added by :func:`add_drive`: the names to find it in the compiled model."""

    name: str
    """Drive name: the first actuator (which carries the effort)."""
    joint: str
    """The hinge or slide joint it drives."""
    instance: str
    """The plugin instance (shared by the drives of one :func:`add_drives` call)."""
    actuators: tuple[str, ...]
    """One actuator per input, in the order of :attr:`inputs`; the first carries the effort."""
    inputs: tuple[str, ...]
    """Control inputs, a subset of ``("pos", "vel", "ff")`` in canonical order."""
    envelope: PerformanceEnvelope
    """The performance envelope (joint side, SI)."""
    stiffness: float
    """Drive stiffness [N*m/rad or N/m] (force drive) or [1/s^2] (acceleration drive)."""
    damping: float
    """Drive damping [N*m*s/rad or N*s/m] (force drive) or [1/s] (acceleration drive)."""
    drive_type: DriveType = "force"
    """``"force"`` or ``"acceleration"``."""
    effort_sensor: str = ""
    """Name of the ``actuatorfrc`` sensor on the first actuator, empty if none was added."""

    def control_index(self, model: mujoco.MjModel, name: str) -> int:
        """Index in ``data.ctrl`` of input ``name`` (``"pos"``, ``"vel"`` or ``"ff"``).

        Raises:
            InputError: the drive has no such input.
        """
        if name not in self.inputs:
            raise InputError(
                f"drive {self.name!r}: no input {name!r}; its inputs are {', '.join(self.inputs)}"
            )
        import mujoco

        actuator = self.actuators[self.inputs.index(name)]
        return int(model.actuator_ctrladr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)])

    def set_targets(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        *,
        position: float | None = None,
        velocity: float | None = None,
        effort: float | None = None,
    ) -> None:
        """Write the drive's controls; None leaves a control as it is.

        Args:
            model: The compiled model.
            data: Its data.
            position: Target position [rad or m] (input ``pos``).
            velocity: Target velocity [rad/s or m/s] (input ``vel``).
            effort: Feed-forward effort [N*m or N] (input ``ff``), counted as actuator effort.
        """
        for name, value in (("pos", position), ("vel", velocity), ("ff", effort)):
            if value is not None:
                data.ctrl[self.control_index(model, name)] = value


def _format(value: float) -> str:
    # repr round-trips a float exactly through the plugin's strtod
    return "inf" if math.isinf(value) else repr(float(value))


def plugin_config(
    envelope: PerformanceEnvelope,
    *,
    stiffness: float,
    damping: float,
    drive_type: DriveType = "force",
    inputs: Sequence[str] = ("pos",),
) -> dict[str, str]:
    """The plugin's ``<config>`` attributes for a drive, as MJCF strings.

    Args:
        envelope: The performance envelope (joint side, SI).
        stiffness: Drive stiffness [N*m/rad or N/m] (force) or [1/s^2] (acceleration), SI.
        damping: Drive damping [N*m*s/rad or N*s/m] (force) or [1/s] (acceleration), SI.
        drive_type: ``"force"`` or ``"acceleration"``.
        inputs: Control inputs, a subset of ``("pos", "vel", "ff")``.
    """
    return {
        "stiffness": _format(stiffness),
        "damping": _format(damping),
        "max_effort": _format(envelope.max_effort),
        "max_actuator_velocity": _format(envelope.max_actuator_velocity),
        "velocity_dependent_resistance": _format(envelope.velocity_dependent_resistance),
        "speed_effort_gradient": _format(envelope.speed_effort_gradient),
        "drive_type": drive_type,
        "input": " ".join(inputs),
    }


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


def _gain_units(joint: str, drive_type: DriveType) -> tuple[str, str]:
    if drive_type == "acceleration":
        return "1/s**2", "1/s"
    if joint == "revolute":
        return "N*m/rad", "N*m*s/rad"
    return "N/m", "N*s/m"


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
    effort_sensor: bool = True,
) -> MjDrive:
    """Drive ``joint`` of ``spec`` with a PhysX drive limited by a performance envelope.

    Adds one ``drive_envelope.envelope`` plugin instance, one actuator per input and (by default)
    an ``actuatorfrc`` sensor named ``<name>_effort`` on the first actuator. Loads the plugin.

    Args:
        spec: The model being built; it must already contain ``joint`` (hinge or slide).
        joint: Joint name.
        stiffness: Drive stiffness, SI number or string with units ([N*m/rad or N/m]; [1/s^2] for
            an acceleration drive).
        damping: Drive damping, SI number or string with units ([N*m*s/rad or N*s/m]; [1/s]).
        envelope: A :class:`PerformanceEnvelope`, or an envelope/datasheet file or catalog name.
        datasheet: A datasheet file or catalog name (instead of ``envelope``).
        drive_type: ``"force"`` or ``"acceleration"``.
        inputs: Control inputs, a subset of ``("pos", "vel", "ff")`` (default ``("pos",)``).
        name: Drive name (default: the joint name); also the plugin instance and actuator name.
        effort_sensor: Whether to add the ``actuatorfrc`` sensor (needed for rollouts).

    Returns:
        The :class:`MjDrive` handle.

    Raises:
        InputError: unknown joint, a joint that is not a hinge or slide, an envelope for the other
            joint type, bad gains or inputs.
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
        instance=name or joint,
        names=[name or joint],
        effort_sensor=effort_sensor,
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
) -> tuple[MjDrive, ...]:
    """Drive several joints with the same drive and envelope through ONE plugin instance.

    Same as :func:`add_drive` for each joint, but the joints share one plugin instance (one
    ``<instance>`` with one ``<config>``), which costs MuJoCo less per step than one instance per
    joint. Actuators are added joint by joint, each joint's inputs in canonical order.

    Args:
        spec: The model being built.
        joints: Hinge or slide joint names, at least one, no repeats.
        stiffness: See :func:`add_drive` [N*m/rad or N/m].
        damping: See :func:`add_drive` [N*m*s/rad or N*s/m].
        envelope: See :func:`add_drive`.
        datasheet: See :func:`add_drive`.
        drive_type: See :func:`add_drive`.
        inputs: See :func:`add_drive`.
        instance: Plugin instance name (default ``drives_<first joint>``).
        names: Drive (first actuator) names, one per joint (default: the joint names).
        effort_sensor: See :func:`add_drive`.

    Returns:
        One :class:`MjDrive` per joint, in the order of ``joints``.

    Raises:
        InputError: see :func:`add_drive`; also no joints, repeated joints or names of the wrong length.
        PluginError: the plugin library is missing or stale.
    """
    import mujoco

    from drive_envelope._src.adapters.mujoco.loader import load_plugin

    load_plugin()
    joints = list(joints)
    labels = list(names) if names is not None else joints
    if not joints or len(set(joints)) != len(joints) or len(labels) != len(joints):
        raise InputError(
            f"add_drives: argument 'joints': expected distinct joint names and as many names, got {joints!r}"
        )
    env = _resolve_envelope(envelope, datasheet)
    joint_type = _joint_type(spec, joints[0], env)
    for joint in joints[1:]:
        _joint_type(spec, joint, env)
    where = f"add_drive(joint={joints[0]!r})"
    if drive_type not in ("force", "acceleration"):
        raise InputError(
            f"{where}: argument 'drive_type': expected 'force' or 'acceleration', got {drive_type!r}"
        )
    k_unit, c_unit = _gain_units(joint_type, drive_type)
    k = to_si(stiffness, k_unit, f"{where}: argument 'stiffness'")
    c = to_si(damping, c_unit, f"{where}: argument 'damping'")
    for label, value, unit in (("stiffness", k, k_unit), ("damping", c, c_unit)):
        if not math.isfinite(value) or value < 0.0:
            raise InputError(
                f"{where}: argument {label!r}: expected a finite number >= 0 [{unit}], got {value!r}"
            )
    channels = _read_inputs(inputs)
    instance_name = instance or f"drives_{joints[0]}"

    spec.activate_plugin(PLUGIN_NAME)
    plugin = spec.add_plugin(name=instance_name, plugin_name=PLUGIN_NAME, active=True)
    plugin.config = plugin_config(env, stiffness=k, damping=c, drive_type=drive_type, inputs=channels)
    drives = []
    for joint, label in zip(joints, labels, strict=True):
        actuators = tuple(label if i == 0 else f"{label}_{n}" for i, n in enumerate(channels))
        for actuator_name in actuators:
            actuator = spec.add_actuator(name=actuator_name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
            actuator.plugin = plugin
            actuator.plugin.name = instance_name
            actuator.plugin.active = True
        sensor = ""
        if effort_sensor:
            sensor = f"{label}_effort"
            spec.add_sensor(
                name=sensor,
                type=mujoco.mjtSensor.mjSENS_ACTUATORFRC,
                objtype=mujoco.mjtObj.mjOBJ_ACTUATOR,
                objname=actuators[0],
            )
        drives.append(
            MjDrive(
                name=label,
                joint=joint,
                instance=instance_name,
                actuators=actuators,
                inputs=channels,
                envelope=env,
                stiffness=k,
                damping=c,
                drive_type=drive_type,
                effort_sensor=sensor,
            )
        )
    return tuple(drives)


def _joint_type(spec: mujoco.MjSpec, joint: str, env: PerformanceEnvelope) -> str:
    """``"revolute"`` or ``"prismatic"`` for a hinge or slide joint of ``spec`` that fits ``env``."""
    import mujoco

    where = f"add_drive(joint={joint!r})"
    element = spec.joint(joint)
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


def _ids(model: mujoco.MjModel, drive: MjDrive) -> tuple[int, int]:
    """(dof address, force address of the first actuator) of ``drive`` in ``model``."""
    import mujoco

    joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, drive.joint)
    actuator = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, drive.actuators[0])
    if joint < 0 or actuator < 0:
        raise InputError(
            f"drive {drive.name!r}: the model has no joint {drive.joint!r} or actuator {drive.actuators[0]!r}"
        )
    return int(model.jnt_dofadr[joint]), int(model.actuator_outadr[actuator])


def drive_state(model: mujoco.MjModel, data: mujoco.MjData, drive: MjDrive) -> tuple[float, float]:
    """The drive's operating point after ``mj_step``: (end-of-step velocity, step effort).

    Returns:
        ``(velocity [rad/s or m/s], total actuator effort [N*m or N])``, the point the envelope
        bounds (PhysX evaluates it at the end-of-step velocity).
    """
    dof, out = _ids(model, drive)
    return float(data.qvel[dof]), float(data.actuator_force[out])


def rollout_operating_points(
    model: mujoco.MjModel, drive: MjDrive, state: npt.ArrayLike, sensordata: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Operating points of ``drive`` from the outputs of ``mujoco.rollout.rollout``.

    Args:
        model: The compiled model.
        drive: The drive (added with ``effort_sensor=True``).
        state: Rollout states, ``(..., nstep, nstate)`` of ``mjSTATE_FULLPHYSICS``.
        sensordata: Rollout sensor data, ``(..., nstep, nsensordata)``.

    Returns:
        ``(velocity, effort)`` arrays of shape ``(..., nstep)``: the velocity after each step
        [rad/s or m/s] and that step's total actuator effort [N*m or N].
    """
    import mujoco

    if not drive.effort_sensor:
        raise InputError(f"drive {drive.name!r}: added without effort_sensor; rollouts need it")
    sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, drive.effort_sensor)
    dof, _ = _ids(model, drive)
    states = np.asarray(state, dtype=np.float64)
    sensors = np.asarray(sensordata, dtype=np.float64)
    # mjSTATE_FULLPHYSICS starts with time, qpos, qvel
    velocity = states[..., 1 + model.nq + dof]
    effort = sensors[..., int(model.sensor_adr[sensor])]
    return velocity, effort

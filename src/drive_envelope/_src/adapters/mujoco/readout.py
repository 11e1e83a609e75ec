"""Reading a drive's operating points back: after ``mj_step``, and from ``mujoco.rollout`` outputs.

Both take the drive as the model-side functions do
(:func:`~drive_envelope._src.adapters.mujoco.params.find_drive`): an :class:`MjDrive` from
``add_drive``, an :class:`MjDriveInfo` from ``model_drives``, an actuator name or index, or the
name of the driven joint.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from drive_envelope._src.adapters.mujoco.handle import MjDrive
from drive_envelope._src.adapters.mujoco.params import DriveRef, MjDriveInfo, drive_label, find_drive
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco

FloatArray = npt.NDArray[np.float64]


def _ids(model: mujoco.MjModel, info: MjDriveInfo) -> tuple[int, int]:
    """(dof address, force address of the effort actuator) of a drive of ``model``."""
    joint = int(model.actuator_trnid[info.actuator, 0])
    return int(model.jnt_dofadr[joint]), int(model.actuator_outadr[info.actuator])


def drive_state(model: mujoco.MjModel, data: mujoco.MjData, drive: DriveRef) -> tuple[float, float]:
    """The drive's operating point after ``mj_step``: (end-of-step velocity, step effort).

    Args:
        model: The compiled model.
        data: Its data, after ``mj_step``.
        drive: An :class:`MjDrive`, an :class:`MjDriveInfo`, an actuator name or index, or the
            driven joint's name.

    Returns:
        ``(velocity [rad/s or m/s], total actuator effort [N*m or N])``, the point the envelope
        bounds (PhysX evaluates it at the end-of-step velocity).

    Raises:
        InputError: ``drive`` names no drive of ``model``, or is of another type.
    """
    import mujoco

    dof, out = _ids(model, find_drive(model, drive, "drive_state", argument="drive"))
    if not isinstance(data, mujoco.MjData):
        raise InputError(f"drive_state: argument 'data': expected a mujoco.MjData, got {type(data).__name__}")
    return float(data.qvel[dof]), float(data.actuator_force[out])


def _effort_sensor(model: mujoco.MjModel, drive: object, info: MjDriveInfo) -> int:
    """Id of an ``actuatorfrc`` sensor on the drive's effort actuator."""
    import mujoco

    if isinstance(drive, MjDrive) and drive.effort_sensor:
        sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, drive.effort_sensor)
        if sensor >= 0:
            return int(sensor)
    kind = int(mujoco.mjtSensor.mjSENS_ACTUATORFRC)
    for sensor in range(model.nsensor):
        if int(model.sensor_type[sensor]) == kind and int(model.sensor_objid[sensor]) == info.actuator:
            return sensor
    raise InputError(
        f"rollout_operating_points(drive={drive_label(drive)}): drive {info.name!r} has no actuatorfrc "
        "sensor; rollouts need one (add_drive(..., effort_sensor=True) adds it)"
    )


def rollout_operating_points(
    model: mujoco.MjModel, drive: DriveRef, state: npt.ArrayLike, sensordata: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Operating points of ``drive`` from the outputs of ``mujoco.rollout.rollout``.

    Args:
        model: The compiled model.
        drive: The drive, as for :func:`drive_state`; its effort actuator needs an ``actuatorfrc``
            sensor (``add_drive(..., effort_sensor=True)``, the default).
        state: Rollout states, ``(..., nstep, nstate)`` of ``mjSTATE_FULLPHYSICS``.
        sensordata: Rollout sensor data, ``(..., nstep, nsensordata)``.

    Returns:
        ``(velocity, effort)`` arrays of shape ``(..., nstep)``: the velocity after each step
        [rad/s or m/s] and that step's total actuator effort [N*m or N].

    Raises:
        InputError: ``drive`` names no drive with an ``actuatorfrc`` sensor; ``state`` is not
            this model's ``mjSTATE_FULLPHYSICS`` layout or ``sensordata`` not its sensor data
            (the two swapped, say); or their leading ``(..., nstep)`` shapes differ.
    """
    import mujoco

    info = find_drive(model, drive, "rollout_operating_points", argument="drive")
    sensor = _effort_sensor(model, drive, info)
    dof, _ = _ids(model, info)
    states = np.asarray(state, dtype=np.float64)
    sensors = np.asarray(sensordata, dtype=np.float64)
    # a state of another layout (mjSTATE_PHYSICS has no time) or the two arrays swapped would be
    # read at the wrong offsets: wrong numbers, not an error
    where = "rollout_operating_points"
    nstate = int(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    if states.ndim == 0 or states.shape[-1] != nstate:
        raise InputError(
            f"{where}: argument 'state' has shape {states.shape}; expected (..., nstep, {nstate}): "
            "mjSTATE_FULLPHYSICS states of this model, as mujoco.rollout.rollout returns them"
        )
    if sensors.ndim == 0 or sensors.shape[-1] != model.nsensordata:
        raise InputError(
            f"{where}: argument 'sensordata' has shape {sensors.shape}; expected (..., nstep, "
            f"{model.nsensordata}): this model's sensor data, as mujoco.rollout.rollout returns it"
        )
    if states.shape[:-1] != sensors.shape[:-1]:
        raise InputError(
            f"{where}: 'state' {states.shape} and 'sensordata' {sensors.shape} differ in their "
            "leading (..., nstep) shape; expected the two outputs of one rollout"
        )
    # mjSTATE_FULLPHYSICS starts with time, qpos, qvel
    velocity = states[..., 1 + model.nq + dof]
    effort = sensors[..., int(model.sensor_adr[sensor])]
    return velocity, effort

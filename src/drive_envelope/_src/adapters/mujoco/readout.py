"""Reading a drive's operating points back: after ``mj_step``, and from ``mujoco.rollout`` outputs."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from drive_envelope._src.adapters.mujoco.spec import MjDrive
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco

__all__ = ["drive_state", "rollout_operating_points"]

FloatArray = npt.NDArray[np.float64]


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

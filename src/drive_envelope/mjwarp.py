"""MuJoCo Warp (MJWarp): the MuJoCo plugin's envelope drives, batched over worlds on the device.

:func:`put_model` is ``mujoco_warp.put_model`` for the MJCF that runs in C MuJoCo with
``drive_envelope.envelope`` actuators (pass its ``mujoco.MjSpec`` or file: MJWarp 4.0 cannot take a
compiled model with plugin instances). The drives get the plugin's law each step, in Warp kernels
over (nworld, drives) installed as ``Model.callback.act_bias``: PhysX's implicit PD drive and the
envelope clamp, every drive of a world solved together with the block of ``(M + h*D')^-1`` over the
driven DOFs. Their numbers live in ``m.actuator_dynprm`` (the plugin's layout), per world when the
model is put with ``batch_sizes={"actuator_dynprm": nworld}``: :func:`set_envelope` and
:func:`set_gains` change them for one world or all. :func:`attach` drives a plugin-free model
(e.g. one mjlab built). :func:`constraint_sizes` measures the ``nconmax`` / ``njmax`` to give
``mujoco_warp.make_data`` (its defaults are too small for a robot on the floor). Importing this
module loads neither Warp nor MuJoCo.

SI units, as in ``drive_envelope.mujoco``: efforts [N*m or N], velocities [rad/s or m/s].
"""

from __future__ import annotations

from drive_envelope._src.adapters.mjwarp.drives import EnvelopeDrives
from drive_envelope._src.adapters.mjwarp.model import attach, envelope_drives, put_model, spec_without_plugin
from drive_envelope._src.adapters.mjwarp.params import get_envelope, get_gains, set_envelope, set_gains
from drive_envelope._src.adapters.mjwarp.sizing import ConstraintSizes, constraint_sizes

__all__ = [
    "ConstraintSizes",
    "EnvelopeDrives",
    "attach",
    "constraint_sizes",
    "envelope_drives",
    "get_envelope",
    "get_gains",
    "put_model",
    "set_envelope",
    "set_gains",
    "spec_without_plugin",
]

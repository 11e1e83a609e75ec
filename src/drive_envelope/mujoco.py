"""MuJoCo: the native actuator plugin ``drive_envelope.envelope`` and helpers to use it.

The plugin gives any MuJoCo model PhysX's implicit drive limited by the performance envelope. Load
it once per process with :func:`load_plugin` (after building it with
``python -m drive_envelope._src.adapters.mujoco.build``, part of ``make setup``), then either
write ``<plugin plugin="drive_envelope.envelope">`` actuators in MJCF or call :func:`add_drive` on a
``mujoco.MjSpec``. mujoco itself is imported only inside these functions.

MuJoCo's units are unspecified; drive_envelope assumes the model is SI (rad, m, s, kg): efforts in
[N*m or N], velocities in [rad/s or m/s]. Use the Euler integrator (see ``plugin/mujoco/README.md``).
"""

from __future__ import annotations

from drive_envelope._src.adapters.mujoco.build import BUILD_COMMAND, PluginError, build_plugin
from drive_envelope._src.adapters.mujoco.loader import PLUGIN_NAME, load_plugin, plugin_library_path
from drive_envelope._src.adapters.mujoco.spec import (
    INPUTS,
    MjDrive,
    add_drive,
    add_drives,
    drive_state,
    plugin_config,
    rollout_operating_points,
)
from drive_envelope._src.adapters.mujoco.stand import stand_spec

__all__ = [
    "BUILD_COMMAND",
    "INPUTS",
    "PLUGIN_NAME",
    "MjDrive",
    "PluginError",
    "add_drive",
    "add_drives",
    "build_plugin",
    "drive_state",
    "load_plugin",
    "plugin_config",
    "plugin_library_path",
    "rollout_operating_points",
    "stand_spec",
]

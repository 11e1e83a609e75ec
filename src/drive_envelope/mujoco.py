"""MuJoCo: the native actuator plugin ``drive_envelope.envelope`` and helpers to use it.

The plugin gives any MuJoCo model PhysX's implicit drive limited by the performance envelope,
solving every drive of the model together each step. Load it once per process with
:func:`load_plugin` (after building it with ``python -m drive_envelope._src.adapters.mujoco.build``,
part of ``make setup``), then either write ``<plugin plugin="drive_envelope.envelope">`` actuators
in MJCF, call :func:`add_drive` on a ``mujoco.MjSpec``, or run ``drive-envelope mujoco apply``.
A drive's numbers live in the model (``actuator_dynprm``, :data:`DYNPRM_SLOTS`):
:func:`set_envelope` and :func:`set_gains` change them between steps; :func:`set_solver` chooses
the exact coupled solve (the default) or PhysX's PGS/TGS iteration over the drives.
:func:`effective_inertia` gives each joint's ``1/(M^-1)_ii`` [kg*m^2 or kg] at a configuration, the
unit response an explicit actuator's end-of-step clip needs (Isaac Lab's and mjlab's
``effective_inertia``). mujoco itself is imported only inside these functions.

MuJoCo's units are unspecified; drive_envelope assumes the model is SI (rad, m, s, kg): efforts in
[N*m or N], velocities in [rad/s or m/s]. Integrators: ``plugin/mujoco/README.md``.
"""

from __future__ import annotations

from drive_envelope._src.adapters.mujoco.build import BUILD_COMMAND, PluginError, build_plugin
from drive_envelope._src.adapters.mujoco.chain_import import mjcf_joints
from drive_envelope._src.adapters.mujoco.inertia import effective_inertia
from drive_envelope._src.adapters.mujoco.loader import PLUGIN_NAME, load_plugin, plugin_library_path
from drive_envelope._src.adapters.mujoco.mjcf import write_mjcf
from drive_envelope._src.adapters.mujoco.params import (
    DYNPRM_SLOTS,
    NO_LIMIT,
    PARAM_BOUND,
    MjDriveInfo,
    drive_dynprm,
    get_envelope,
    get_gains,
    model_drives,
    set_envelope,
    set_gains,
)
from drive_envelope._src.adapters.mujoco.readout import drive_state, rollout_operating_points
from drive_envelope._src.adapters.mujoco.solver import (
    SOLVER_NUMERIC,
    SOLVERS,
    MjSolver,
    get_solver,
    set_solver,
)
from drive_envelope._src.adapters.mujoco.spec import INPUTS, MjDrive, add_drive, add_drives, plugin_config
from drive_envelope._src.adapters.mujoco.stand import stand_spec
from drive_envelope._src.adapters.mujoco.stats import SolverStats, solver_stats

__all__ = [
    "BUILD_COMMAND",
    "DYNPRM_SLOTS",
    "INPUTS",
    "NO_LIMIT",
    "PARAM_BOUND",
    "PLUGIN_NAME",
    "SOLVERS",
    "SOLVER_NUMERIC",
    "MjDrive",
    "MjDriveInfo",
    "MjSolver",
    "PluginError",
    "SolverStats",
    "add_drive",
    "add_drives",
    "build_plugin",
    "drive_dynprm",
    "drive_state",
    "effective_inertia",
    "get_envelope",
    "get_gains",
    "get_solver",
    "load_plugin",
    "mjcf_joints",
    "model_drives",
    "plugin_config",
    "plugin_library_path",
    "rollout_operating_points",
    "set_envelope",
    "set_gains",
    "set_solver",
    "solver_stats",
    "stand_spec",
    "write_mjcf",
]

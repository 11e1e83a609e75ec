"""The plugin solver's diagnostics of its last computation, read from the instance itself.

They are not MuJoCo state: the drives are a function of the model and the physics state, so the
plugin has no ``plugin_state`` (as MuJoCo's own ``pid`` actuator), and a saved
``mjSTATE_FULLPHYSICS`` restores the physics alone. The leader instance (the lowest of the plugin,
which solves every drive) keeps the numbers and ``drive_envelope_solver_stats`` (``exports.cc``)
hands them out.
"""

from __future__ import annotations

import ctypes
from typing import TYPE_CHECKING, NamedTuple

from drive_envelope._src.adapters.mujoco.build import BUILD_COMMAND, PluginError
from drive_envelope._src.adapters.mujoco.loader import PLUGIN_NAME, plugin_library, plugin_slot
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco


class SolverStats(NamedTuple):
    """What the plugin's drive solve took at the last ``mj_step`` / ``mj_forward`` of an ``MjData``."""

    iterations: int
    """Newton steps plus Gauss-Seidel sweeps (0: the linear solve was inside every envelope;
    ``set_solver`` pgs/tgs: the sweeps PhysX runs) [-]."""
    solves: int
    """Drive solves (clamp evaluations) they took [-]."""


def solver_stats(model: mujoco.MjModel, data: mujoco.MjData) -> SolverStats:
    """The plugin's diagnostics of its last computation on ``data``.

    Args:
        model: A model with drives (:func:`add_drive`), loaded with the plugin.
        data: Its data, after at least one ``mj_step`` or ``mj_forward`` (zeros before, and after
            ``mj_resetData``).

    Raises:
        InputError: the model has no instance of the plugin.
    """
    slot = plugin_slot()
    leaders = [j for j in range(model.nplugin) if int(model.plugin[j]) == slot]
    if not leaders:
        raise InputError(f"model: no instance of the {PLUGIN_NAME!r} plugin (add drives with add_drive)")
    try:
        function = plugin_library().drive_envelope_solver_stats
    except AttributeError:  # a build from before this entry point: same MuJoCo, older sources
        raise PluginError(
            f"the plugin build predates solver_stats; rebuild it with `{BUILD_COMMAND} --force`"
        ) from None
    function.restype = ctypes.c_int
    function.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_int)]
    iterations, solves = ctypes.c_int(0), ctypes.c_int(0)
    if function(int(data.plugin_data[leaders[0]]), ctypes.byref(iterations), ctypes.byref(solves)) != 0:
        raise InputError("data: the plugin instance is not initialised (make the MjData from this model)")
    return SolverStats(iterations=iterations.value, solves=solves.value)

"""The ``mujoco`` engine: the test stand as a one-DOF MJCF model driven by the native plugin.

See :mod:`drive_envelope._src.adapters.mujoco.stand` for the model. It needs the ``mujoco`` extra
and the built plugin (``python -m drive_envelope._src.adapters.mujoco.build``).
"""

from __future__ import annotations

from drive_envelope._src.scenario.chain import ChainScenario
from drive_envelope._src.scenario.chain_trajectory import ChainTrajectory
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

LOADS = ("pendulum", "friction", "armature")
"""The bench loads this engine represents (see :mod:`drive_envelope._src.teststand.engines`)."""


def simulate(scenario: Scenario, schedule: DriveSchedule | None = None) -> Trajectory:
    """Run ``scenario`` in MuJoCo with the ``drive_envelope.envelope`` plugin.

    ``schedule`` gives per-step drive targets and power state (or None).

    Raises:
        PluginError: the plugin is not built or was built for another MuJoCo version (a
            :class:`~drive_envelope.errors.DriveEnvelopeError`: the CLI prints one line).
    """
    from drive_envelope._src.adapters.mujoco.stand import simulate as run

    return run(scenario, schedule=schedule)


def simulate_chain(scenario: ChainScenario) -> ChainTrajectory:
    """Run a chain scenario in MuJoCo: the plugin on every joint, iterating as the scenario's PhysX solver."""
    from drive_envelope._src.adapters.mujoco.stand import simulate_chain as run

    return run(scenario)

"""The ``newton`` engine: the test stand as a one-DOF Newton model on ``SolverFeatherstone``.

See :mod:`drive_envelope._src.adapters.newton.stand` for the model: the drive computed as the
scenario's PhysX solver (PGS or TGS, its iteration counts) iterates it, in a Warp kernel, and
applied as joint effort, with a ``[pendulum]`` and ``joint.armature``; ``[friction]`` and drive
schedules are refused. It needs the ``newton`` extra.
"""

from __future__ import annotations

from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory
from drive_envelope._src.teststand.engines import ProgressCallback

LOADS = ("pendulum", "armature")
"""The bench loads this engine represents (``[friction]`` has no Featherstone counterpart)."""


def simulate(scenario: Scenario, progress: ProgressCallback | None = None) -> Trajectory:
    """Run ``scenario`` in Newton (float32: the reference to float32 precision, PGS and TGS)."""
    from drive_envelope._src.adapters.newton.stand import simulate as run

    return run(scenario, progress=progress)

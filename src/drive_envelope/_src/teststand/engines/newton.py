"""The ``newton`` engine: the test stand as a one-DOF Newton model (Featherstone, implicit actuator).

See :mod:`drive_envelope._src.adapters.newton.stand` for the model: Newton's ``DrivePD`` clamped by
``ClampingPerformanceEnvelope`` in Newton's implicit effort mode, with a ``[pendulum]`` and
``joint.armature``; ``[friction]`` and drive schedules are refused. It needs the ``newton`` extra.
"""

from __future__ import annotations

from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory
from drive_envelope._src.teststand.engines import ProgressCallback

__all__ = ["LOADS", "simulate"]

LOADS = ("pendulum", "armature")
"""The bench loads this engine represents (``[friction]`` has no Featherstone counterpart)."""


def simulate(scenario: Scenario, progress: ProgressCallback | None = None) -> Trajectory:
    """Run ``scenario`` in Newton (float32: agreement with ``reference`` to float32 precision on PGS)."""
    from drive_envelope._src.adapters.newton.stand import simulate as run

    return run(scenario, progress=progress)

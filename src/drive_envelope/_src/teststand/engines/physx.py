"""The ``physx`` engine: the test stand on real PhysX through ovphysx (CPU).

See :mod:`drive_envelope._src.adapters.physx.stand` for the stage and the stepping. It needs the
``physx`` extra (``ovphysx`` >= 0.7, ``usd-core``, ``physx-usd-schemas``).
"""

from __future__ import annotations

from collections.abc import Sequence

from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

__all__ = ["LOADS", "simulate", "simulate_many"]

LOADS = ("pendulum", "friction", "armature")
"""The bench loads this engine represents (see :mod:`drive_envelope._src.teststand.engines`)."""


def simulate(scenario: Scenario, schedule: DriveSchedule | None = None) -> Trajectory:
    """Run ``scenario`` on PhysX (float32: agreement with ``reference`` to float32 precision).

    ``schedule`` gives per-step drive targets and power state (or None).
    """
    return simulate_many([scenario], schedules=[schedule])[0]


def simulate_many(
    scenarios: Sequence[Scenario], schedules: Sequence[DriveSchedule | None] | None = None
) -> list[Trajectory]:
    """Run several scenarios on one PhysX instance (ovphysx's set-up, about 1 s, is paid once)."""
    from drive_envelope._src.adapters.physx.stand import simulate_many as run

    return run(scenarios, schedules=schedules)

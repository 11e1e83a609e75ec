"""The ``physx`` engine: the test stand on real PhysX through ovphysx (CPU).

See :mod:`drive_envelope._src.adapters.physx.stand` for the stage and the stepping. It needs the
``physx`` extra (``ovphysx`` >= 0.7, ``usd-core``, ``physx-usd-schemas``).
"""

from __future__ import annotations

from collections.abc import Sequence

from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

__all__ = ["simulate", "simulate_many"]


def simulate(scenario: Scenario) -> Trajectory:
    """Run ``scenario`` on PhysX (float32: agreement with ``reference`` to float32 precision)."""
    return simulate_many([scenario])[0]


def simulate_many(scenarios: Sequence[Scenario]) -> list[Trajectory]:
    """Run several scenarios on one PhysX instance (ovphysx's set-up, about 1 s, is paid once)."""
    from drive_envelope._src.adapters.physx.stand import simulate_many as run

    return run(scenarios)

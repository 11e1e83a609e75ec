"""The ``physx`` engine: the test stand on real PhysX through ovphysx (CPU).

See :mod:`drive_envelope._src.adapters.physx.stand` for the stage and the stepping. It needs the
``physx`` extra (``ovphysx`` >= 0.7, ``usd-core``, ``physx-usd-schemas``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from drive_envelope._src.scenario.chain import ChainScenario
from drive_envelope._src.scenario.chain_trajectory import ChainTrajectory
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

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


def simulate_chain(scenario: ChainScenario) -> ChainTrajectory:
    """Run a chain scenario on PhysX; the effort columns are recovered from the states.

    ovphysx 0.7 has no drive-force read and the projected joint force carries the links' weight
    and motion, so each step's drive effort is found from PhysX's own states by
    :func:`drive_efforts` (``metadata["effort_source"]`` says so).
    """
    import dataclasses

    from drive_envelope._src.adapters.physx.chain import simulate_chain as run

    result = run(scenario)
    metadata = dict(result.metadata)
    metadata["effort_source"] = (
        "drive + applied (+ friction) effort recovered from PhysX's joint states: "
        "M(q0)*(v1 - v0)/dt + h(q0, v0) - external effort, M and h at the start of each step"
    )
    return dataclasses.replace(result, effort=drive_efforts(scenario, result), metadata=metadata)


def drive_efforts(scenario: ChainScenario, trajectory: ChainTrajectory) -> np.ndarray:
    """The step-average actuator (+ friction) effort of every joint, from the recorded states [N*m or N].

    PhysX's articulation changes the joint velocities over a step by
    ``M(q0)^-1*(drive + applied + friction + external - h(q0, v0))*dt`` (PGS; TGS splits the same
    terms over its substeps with the start-of-step inertia), so the actuator and friction effort
    is ``M(q0)*(v1 - v0)/dt + h(q0, v0) - external``: the same for any engine that records joint
    states, to the engine's precision.
    """
    from drive_envelope._src.teststand.engines.chain_dynamics import ChainModel

    model = ChainModel(scenario)
    dt = scenario.simulation.dt
    external = np.array([joint.load.external_effort for joint in scenario.joints])
    effort = np.zeros_like(trajectory.velocity)
    for i in range(len(trajectory) - 1):
        kin = model.kinematics(trajectory.position[i])
        change = (trajectory.velocity[i + 1] - trajectory.velocity[i]) / dt
        effort[i + 1] = model.mass_matrix(kin) @ change + model.bias(kin, trajectory.velocity[i]) - external
    return effort

"""The test stand on real PhysX (the ``ovphysx`` 0.7 wheel, CPU): the ``physx`` engine's work.

The scenario is authored as a USD stage (a fixed-base articulation with one revolute or prismatic
joint, drive + PhysxDrivePerformanceEnvelopeAPI written by :mod:`drive_envelope.usd`, the
scenario's solver type and iteration counts, zero link damping, ``cfmScale`` 0, no gravity) and
stepped by PhysX in this process (see :mod:`drive_envelope._src.adapters.physx.runner`). The CSV has
the same columns as the reference engine's: row 0 the initial state, then per step the joint
position and velocity and PhysX's projected joint force (``jointProjectedForce``; ovphysx 0.7
exposes no drive force of its own). On this stand, whose link has its centre of mass on the joint
axis, that is the total actuator effort (drive + applied), which the parity tests confirm step by
step; the trajectory's ``metadata["effort_source"]`` says so.

PhysX computes in float32: expect agreement with ``reference`` to float32 precision. Needs the
``physx`` extra (``ovphysx`` >= 0.7, ``usd-core``, ``physx-usd-schemas``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from drive_envelope._src.adapters.physx.runner import PhysxJob, PhysxResult, run_jobs
from drive_envelope._src.adapters.physx.scene import build_teststand_stage
from drive_envelope._src.adapters.usd.scale import StageUnits
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

__all__ = ["EFFORT_SOURCE", "simulate", "simulate_many"]

EFFORT_SOURCE = (
    "PhysX jointProjectedForce: the joint force projected on the DOF; equal to the drive + applied "
    "effort here because the stand's link has its centre of mass on the joint axis"
)
"""What the ``effort`` column of a physx run holds (ovphysx 0.7 has no drive-force read)."""


def simulate(scenario: Scenario) -> Trajectory:
    """Run one scenario on PhysX; see :func:`simulate_many`."""
    return simulate_many([scenario])[0]


def simulate_many(scenarios: Sequence[Scenario], *, units: StageUnits | None = None) -> list[Trajectory]:
    """Run several scenarios on one PhysX instance (ovphysx's set-up, about 1 s, is paid once).

    Args:
        scenarios: The scenarios (SI).
        units: Stage units for the authored stages (SI by default); results are SI either way.

    Returns:
        One trajectory per scenario, in order, ``engine = "physx"``.

    Raises:
        InputError: a scenario PhysX cannot represent (a time step below 2**-32 s, an envelope on
            an unlimited drive), or ovphysx >= 0.7 / physx-usd-schemas missing.
        DriveEnvelopeError: PhysX itself failed.
    """
    units = units or StageUnits()
    jobs = []
    for scenario in scenarios:
        _check(scenario)
        stage = build_teststand_stage(scenario, units=units)
        inst = "angular" if scenario.joint.type == "revolute" else "linear"
        jobs.append(
            PhysxJob(
                usda=stage.GetRootLayer().ExportToString(),
                joint=scenario.joint.type,
                solver=scenario.simulation.solver,
                dt=scenario.simulation.dt,
                steps=scenario.simulation.steps,
                initial_position=scenario.joint.initial_position,
                initial_velocity=scenario.joint.initial_velocity,
                applied_effort=scenario.load.applied_effort,
                external_effort=scenario.load.external_effort,
                effort_scale=units.effort(inst),
                length_scale=units.length(),
            )
        )
    results = run_jobs(jobs)
    return [_trajectory(scenario, result) for scenario, result in zip(scenarios, results, strict=True)]


def _check(scenario: Scenario) -> None:
    sim = scenario.simulation
    if not 1.0 / sim.dt < 2**32:
        raise InputError(f"{scenario.name or 'scenario'}: simulation.dt {sim.dt!r} is too small for PhysX")
    if math.isinf(scenario.drive.max_effort) and scenario.envelope is not None:
        raise InputError(f"{scenario.name or 'scenario'}: an envelope needs a finite drive.max_effort")


def _trajectory(scenario: Scenario, result: PhysxResult) -> Trajectory:
    sim = scenario.simulation
    time = np.arange(sim.steps + 1, dtype=np.float64) * sim.dt
    return Trajectory(
        time=time,
        position=result.position,
        velocity=result.velocity,
        effort=result.effort,
        joint=scenario.joint.type,
        engine="physx",
        name=scenario.name,
        metadata={
            "solver": sim.solver,
            "dt": sim.dt,
            "position_iterations": sim.position_iterations,
            "velocity_iterations": sim.velocity_iterations,
            "precision": "float32",
            "effort_source": EFFORT_SOURCE,
            "engine_version": _ovphysx_version(),
        },
    )


def _ovphysx_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ovphysx")
    except PackageNotFoundError:
        return "unknown"

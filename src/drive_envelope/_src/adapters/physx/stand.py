"""The test stand on real PhysX (the ``ovphysx`` 0.7 wheel, CPU): the ``physx`` engine's work.

The scenario is authored as a USD stage (a fixed-base articulation with one revolute or prismatic
joint, drive + PhysxDrivePerformanceEnvelopeAPI written by :mod:`drive_envelope.usd`, the
scenario's solver type and iteration counts, zero link damping, ``cfmScale`` 0, no gravity) and
stepped by PhysX in this process (see :mod:`drive_envelope._src.adapters.physx.runner`). The CSV has
the same columns as the reference engine's: row 0 the initial state, then per step the joint
position and velocity and an effort derived from PhysX's projected joint force
(``jointProjectedForce``; ovphysx 0.7 exposes no drive force of its own). That force is what the
joint passes to the link: the link's share of the joint-space effort (armature takes the rest),
less the external load and gravity, with PhysX's own mix of start- and end-of-step geometry on a
pendulum. The effort column undoes that (:func:`_joint_effort`): it is the drive + applied effort,
plus the joint friction when the scenario has friction (ovphysx cannot tell the two apart without
a drive-force read); the parity tests confirm it step by step, and the trajectory's
``metadata["effort_source"]`` says so.

PhysX computes in float32: expect agreement with ``reference`` to float32 precision. Needs the
``physx`` extra (``ovphysx`` >= 0.7, ``usd-core``, ``physx-usd-schemas``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from drive_envelope._src.adapters.physx.runner import PhysxJob, PhysxResult, run_jobs
from drive_envelope._src.adapters.physx.scene import build_teststand_stage, drive_gains
from drive_envelope._src.adapters.usd.scale import StageUnits
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain import ChainScenario
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory, stand_run

EFFORT_SOURCE = (
    "PhysX jointProjectedForce: the joint force projected on the DOF, which is the drive + applied "
    "effort when the link has its centre of mass on the joint axis and no armature; a pendulum's "
    "off-axis mass, gravity, the external load and armature's share are undone: the drive + applied effort"
)
"""What the ``effort`` column of a physx run holds (ovphysx 0.7 has no drive-force read)."""
EFFORT_SOURCE_FRICTION = EFFORT_SOURCE.replace(
    "the drive + applied effort", "the drive + applied effort PLUS the joint friction"
)
"""The same for a scenario with joint friction, which the projected force includes."""


def simulate(scenario: Scenario) -> Trajectory:
    """Run one scenario on PhysX; see :func:`simulate_many`."""
    return simulate_many([scenario])[0]


def simulate_many(
    scenarios: Sequence[Scenario],
    *,
    units: StageUnits | None = None,
    schedules: Sequence[DriveSchedule | None] | None = None,
) -> list[Trajectory]:
    """Run several scenarios on one PhysX instance (ovphysx's set-up, about 1 s, is paid once).

    Args:
        scenarios: The scenarios (SI).
        units: Stage units for the authored stages (SI by default); results are SI either way.
        schedules: Per scenario, per-step drive targets and power state (or None): the runner
            writes the targets and the gains (0 while unpowered) before each step.

    Returns:
        One trajectory per scenario, in order, ``engine = "physx"``.

    Raises:
        InputError: a scenario PhysX cannot represent (a time step below 2**-32 s, an envelope on
            an unlimited drive), a schedule of the wrong length, or ovphysx >= 0.7 /
            physx-usd-schemas missing.
        DriveEnvelopeError: PhysX itself failed.
    """
    units = units or StageUnits()
    plans = list(schedules) if schedules is not None else [None] * len(scenarios)
    if len(plans) != len(scenarios):
        raise InputError(f"physx: {len(plans)} drive schedules for {len(scenarios)} scenarios")
    jobs = []
    for scenario, schedule in zip(scenarios, plans, strict=True):
        check_time_step(scenario)
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
                **_schedule_columns(scenario, schedule, units, inst),
            )
        )
    results = run_jobs(jobs)
    return [_trajectory(scenario, result) for scenario, result in zip(scenarios, results, strict=True)]


def _schedule_columns(
    scenario: Scenario, schedule: DriveSchedule | None, units: StageUnits, inst: str
) -> dict[str, np.ndarray]:
    """The per-step writes of a schedule in ovphysx's units (targets, and gains 0 while unpowered)."""
    if schedule is None:
        return {}
    schedule.check_steps(scenario.simulation.steps, f"scenario {scenario.name!r}")
    stiffness, damping = drive_gains(scenario.drive, inst, units)  # as the stage authors them
    powered = schedule.enabled.astype(np.float64)
    return {
        "target_position": schedule.target_position * units.position(inst),
        "target_velocity": schedule.target_velocity * units.velocity(inst),
        "stiffness": powered * stiffness,
        "damping": powered * damping,
    }


def check_time_step(scenario: Scenario | ChainScenario) -> None:
    """Refuse a time step PhysX cannot take (its step rate is a 32-bit count per second)."""
    sim = scenario.simulation
    if not 1.0 / sim.dt < 2**32:
        raise InputError(f"{scenario.name or 'scenario'}: simulation.dt {sim.dt!r} is too small for PhysX")


def _joint_effort(scenario: Scenario, result: PhysxResult) -> np.ndarray:
    """The joint-space effort (drive + applied, + friction) from PhysX's projected joint force.

    PhysX forms the link's incoming joint force from the start-of-step spatial inertia, gravity
    and centripetal acceleration and the step's velocity change, then moves it to the joint frame
    with the END-of-step lever arm (``copyInternalStateToCache``, ``eLINK_INCOMING_JOINT_FORCE``).
    About the axis of a link with inertia ``I_c`` about its centre of mass, ``m*d^2`` off the axis,
    that is ``F = (I_c + m*d^2*cos(dq))*a + m*d^2*v0^2*sin(dq) - external - gravity(q1)``, with
    ``a = (v1 - v0)/dt`` and ``dq = q1 - q0``. Solved for ``a``, the joint-space effort is
    ``effective_inertia*a - external - gravity(q0)``; without a pendulum it is ``F*effective_inertia
    / inertia`` (armature's share added back).
    """
    projected = result.effort
    external = scenario.load.external_effort
    pendulum = scenario.pendulum
    position, velocity = result.position, result.velocity
    if pendulum is None:
        gravity, lever = np.zeros_like(position), 0.0
    else:
        gravity, lever = pendulum.gravity_effort(position, scenario.simulation.gravity), pendulum.inertia
    turn = np.diff(position)
    centripetal = lever * velocity[:-1] ** 2 * np.sin(turn)
    acceleration = (projected[1:] + external + gravity[1:] - centripetal) / (
        scenario.joint.inertia + lever * np.cos(turn)
    )
    effort = np.zeros_like(projected)
    effort[1:] = scenario.effective_inertia * acceleration - external - gravity[:-1]
    return effort


def _trajectory(scenario: Scenario, result: PhysxResult) -> Trajectory:
    source = EFFORT_SOURCE_FRICTION if scenario.friction.active else EFFORT_SOURCE
    columns = (result.position, result.velocity, _joint_effort(scenario, result))
    return stand_run(
        scenario,
        "physx",
        *columns,
        precision="float32",
        effort_source=source,
        engine_version=_ovphysx_version(),
    )


def _ovphysx_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ovphysx")
    except PackageNotFoundError:
        return "unknown"

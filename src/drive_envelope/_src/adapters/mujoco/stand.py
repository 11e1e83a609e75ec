"""The test stand in MuJoCo: one hinge or slide joint on a fixed base, driven through the plugin.

The scenario's rigid inertia becomes one body whose inertia about the joint axis is
``joint.inertia`` (no gravity, no geoms, Euler integrator), so the DOF's unit response is exactly
``1/inertia``. The drive is the ``drive_envelope.envelope`` plugin with all three inputs: the
target position, the target velocity and the scenario's applied effort (PhysX's joint force,
which counts as actuator effort). The external effort goes to ``qfrc_applied``: it is not
actuator effort, so the envelope does not limit it.

MuJoCo takes one step per ``dt`` with one implicit drive solve, which is what PhysX's PGS solver
does for an isolated DOF. PhysX's TGS integrates and clamps per substep; a TGS scenario still runs
here (same model, one solve per step) and its metadata says so.
"""

from __future__ import annotations

import math
import sys
from typing import TYPE_CHECKING

import numpy as np

from drive_envelope._src.adapters.mujoco.spec import MjDrive, add_drive
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory

if TYPE_CHECKING:
    import mujoco

__all__ = ["UNLIMITED_EFFORT", "stand_spec", "simulate"]

UNLIMITED_EFFORT = sys.float_info.max * 1e-10
"""Stand-in for an unlimited ``max_effort`` [N*m or N]: PhysX skips the clamp, the plugin's clamp
then never binds (the impulse ``max_effort*dt`` stays finite for any sane ``dt``)."""


def _plugin_envelope(scenario: Scenario) -> tuple[PerformanceEnvelope, float, float]:
    """Envelope, stiffness and damping the plugin gets for the scenario's drive.

    PhysX's drive with ``maxForce = 0`` is off and leaves the applied effort unlimited: the plugin
    gets zero gains and no limit, so its output is the feed-forward alone.
    """
    drive = scenario.drive
    if drive.max_effort == 0.0:
        return PerformanceEnvelope(max_effort=UNLIMITED_EFFORT, joint=scenario.joint.type), 0.0, 0.0
    envelope = scenario.effective_envelope()
    if envelope is None:
        envelope = PerformanceEnvelope(max_effort=UNLIMITED_EFFORT, joint=scenario.joint.type)
    return envelope, drive.stiffness, drive.damping


def stand_spec(scenario: Scenario) -> tuple[mujoco.MjSpec, MjDrive]:
    """The scenario's test stand as an ``MjSpec`` (one body, one DOF) and its drive handle."""
    import mujoco

    spec = mujoco.MjSpec()
    spec.modelname = scenario.name or "teststand"
    spec.option.timestep = scenario.simulation.dt
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    inertia = scenario.joint.inertia
    body = spec.worldbody.add_body(name="load", explicitinertial=True)
    if scenario.joint.type == "revolute":
        body.mass, body.inertia = 1.0, [inertia, inertia, inertia]
        joint_type = mujoco.mjtJoint.mjJNT_HINGE
    else:
        body.mass, body.inertia = inertia, [1.0, 1.0, 1.0]
        joint_type = mujoco.mjtJoint.mjJNT_SLIDE
    body.add_joint(name="joint", type=joint_type, axis=[0.0, 0.0, 1.0])
    envelope, stiffness, damping = _plugin_envelope(scenario)
    drive = add_drive(
        spec,
        "joint",
        envelope=envelope,
        stiffness=stiffness,
        damping=damping,
        drive_type=scenario.drive.type,
        inputs=("pos", "vel", "ff"),
        name="drive",
        effort_sensor=False,
    )
    return spec, drive


def simulate(scenario: Scenario) -> Trajectory:
    """Run the scenario in MuJoCo with the plugin; ``steps + 1`` rows, row 0 the initial state."""
    import mujoco

    spec, drive = stand_spec(scenario)
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[0] = scenario.joint.initial_position
    data.qvel[0] = scenario.joint.initial_velocity
    data.qfrc_applied[0] = scenario.load.external_effort
    drive.set_targets(
        model,
        data,
        position=scenario.drive.target_position,
        velocity=scenario.drive.target_velocity,
        effort=scenario.load.applied_effort,
    )
    count = scenario.simulation.steps
    time = np.arange(count + 1, dtype=np.float64) * scenario.simulation.dt
    position, velocity, effort = np.empty(count + 1), np.empty(count + 1), np.zeros(count + 1)
    position[0], velocity[0] = data.qpos[0], data.qvel[0]
    for i in range(1, count + 1):
        mujoco.mj_step(model, data)
        position[i], velocity[i], effort[i] = data.qpos[0], data.qvel[0], data.actuator_force[0]
    return Trajectory(
        time=time,
        position=position,
        velocity=velocity,
        effort=effort,
        joint=scenario.joint.type,
        engine="mujoco",
        name=scenario.name,
        metadata=_metadata(scenario),
    )


def _metadata(scenario: Scenario) -> dict[str, object]:
    import mujoco

    sim = scenario.simulation
    note = "one implicit drive solve per step (PhysX PGS for an isolated DOF)"
    if sim.solver == "tgs":
        note += "; PhysX TGS integrates and clamps per substep, so transients differ"
    return {
        "solver": sim.solver,
        "dt": sim.dt,
        "mujoco_version": str(mujoco.__version__),
        "integrator": "Euler",
        "plugin": "drive_envelope.envelope",
        "note": note,
        "unlimited_effort": math.isinf(scenario.drive.max_effort),
    }

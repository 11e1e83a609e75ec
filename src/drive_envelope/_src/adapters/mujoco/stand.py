"""The test stand in MuJoCo: one hinge or slide joint on a fixed base, driven through the plugin.

The scenario's rigid inertia becomes one body whose inertia about the joint axis is
``joint.inertia`` (no geoms, Euler integrator), so the DOF's unit response is exactly
``1/effective_inertia``: ``joint.armature`` is MuJoCo's ``armature`` (added to the joint-space
inertia, as in PhysX). A ``[pendulum]`` gives the body the point mass at its centre of mass,
``distance`` from the hinge (Z) and ``angle_offset`` from straight down, and the model gravity
along -Y; without one there is no gravity. The drive is the ``drive_envelope.envelope`` plugin with
all three inputs: the target position, the target velocity and the scenario's applied effort
(PhysX's joint force, which counts as actuator effort). The external effort goes to
``qfrc_applied``: it is not actuator effort, so the envelope does not limit it. A drive schedule
writes the targets every step and zeroes the gains (``set_gains``) while the drive is unpowered.

The plugin iterates the drive as the scenario's PhysX solver does (``set_solver(spec, solver,
position_iterations=, velocity_iterations=)``, as the chain stand): PGS's position sweeps and at
least one velocity sweep; TGS's substeps of ``dt/position_iterations``, each applying the loads
over the substep and clamping its own impulse, then the velocity sweeps that re-clamp the step's
total; and the position PhysX integrates (the plugin shifts MuJoCo's ``q + h*v1`` to it). On every
shipped scenario, PGS and TGS, that is the reference to 1e-11 (``docs/parity.md``).

Joint friction is where the models differ. MuJoCo has one Coulomb friction, ``frictionloss``, so
it needs ``static_friction == dynamic_friction`` (PhysX's break-away above sliding friction cannot
be represented and is refused); it is a constraint, made hard here (``solreffriction = (2*dt, 1)``,
``solimpfriction`` 0.9999) so a stopping joint sticks as in PhysX. Viscous friction becomes
MuJoCo's joint ``damping`` (linear term), which the plugin solves implicitly in each drive row.
MuJoCo solves the actuators first and the frictionloss constraint after, once: a joint without a
powered drive (a coasting or swinging load) matches PhysX PGS 1/0 to ~1e-11
(``tests/test_mujoco_teststand.py``). PhysX's drive sees the friction of the sweep before and
answers it within the step, and even at 0 velocity iterations it runs one more sweep; MuJoCo's
drive never sees the frictionloss, so a drive against Coulomb friction differs (a damping drive at
5 rad/s against 0.2 N*m: 3.8 rad/s here, 4.8 in PhysX).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from drive_envelope._src.adapters.mujoco.loader import PLUGIN_NAME
from drive_envelope._src.adapters.mujoco.mjcf import mujoco_warnings
from drive_envelope._src.adapters.mujoco.params import NO_LIMIT, PARAM_BOUND
from drive_envelope._src.adapters.mujoco.spec import MjDrive, add_drive
from drive_envelope._src.envelope.model import NO_LIMIT_FIELDS, JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain import ChainJoint, ChainScenario
from drive_envelope._src.scenario.chain_trajectory import ChainTrajectory, chain_run
from drive_envelope._src.scenario.loads import FrictionSpec
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import DriveSpec, JointSpec, Scenario
from drive_envelope._src.scenario.trajectory import Trajectory, stand_run

if TYPE_CHECKING:
    import mujoco

MIN_INERTIA = 1e-15
"""Smallest inertia [kg*m^2 or kg] MuJoCo accepts for a moving body (its ``mjMINVAL``)."""
_WARNINGS = ("mjWARN_INERTIA", "mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC", "mjWARN_BADCTRL")


def _plugin_envelope(
    drive: DriveSpec, envelope: PerformanceEnvelope | None, joint: JointType
) -> tuple[PerformanceEnvelope, float, float, bool]:
    """Envelope, stiffness, damping and "no effort limit" the plugin gets for a stand's drive.

    PhysX's drive with ``maxForce = 0`` is off and leaves the applied effort unlimited: the plugin
    gets zero gains and no limit, so its output is the feed-forward alone. Without an effort limit
    (``envelope`` None: PhysX skips the clamp) the plugin gets ``max_effort = -1`` (no limit).
    """
    unlimited = PerformanceEnvelope(max_effort=0.0, joint=joint)
    if drive.max_effort == 0.0:
        return unlimited, 0.0, 0.0, True
    if envelope is None:
        return unlimited, drive.stiffness, drive.damping, True
    return envelope, drive.stiffness, drive.damping, False


def _add_stand_drive(
    spec: mujoco.MjSpec,
    joint: str,
    name: str,
    drive: DriveSpec,
    envelope: PerformanceEnvelope | None,
    joint_type: JointType,
) -> MjDrive:
    """The plugin drive of a stand's ``joint`` with all three inputs, as :func:`_plugin_envelope` says."""
    limit, k, c, unlimited = _plugin_envelope(drive, envelope, joint_type)
    added = add_drive(spec, joint, envelope=limit, stiffness=k, damping=c, drive_type=drive.type,
                      inputs=("pos", "vel", "ff"), name=name, effort_sensor=False)  # fmt: skip
    if unlimited:
        actuator = spec.actuator(added.name)
        actuator.dynprm = [NO_LIMIT, *list(actuator.dynprm)[1:]]
    return added


def _where(scenario: Scenario | ChainScenario) -> str:
    return f"scenario {scenario.name!r}" if scenario.name else "scenario"


def _check(scenario: Scenario) -> None:
    """Refuse what MuJoCo or the plugin cannot run, with the scenario key (before compiling)."""
    where = _where(scenario)
    inertia = scenario.joint.inertia
    if inertia < MIN_INERTIA:
        raise InputError(
            f"{where}: key 'joint.inertia' = {inertia!r}: the mujoco engine needs at least "
            f"{MIN_INERTIA:g} (MuJoCo's smallest inertia of a moving body)"
        )
    friction = scenario.friction
    if friction.static_friction != friction.dynamic_friction:
        raise InputError(
            f"{where}: key 'friction.static_friction' = {friction.static_friction!r}: the mujoco engine "
            f"has one Coulomb friction (frictionloss) and needs it equal to friction.dynamic_friction "
            f"({friction.dynamic_friction!r})"
        )
    drive = scenario.drive
    for key, value in (("drive.stiffness", drive.stiffness), ("drive.damping", drive.damping)):
        if value > PARAM_BOUND:
            raise InputError(f"{where}: key {key!r} = {value!r}: the mujoco engine takes at most 1e12 (SI)")
    envelope = scenario.effective_envelope()
    if envelope is not None:
        for field in ("velocity_dependent_resistance", "speed_effort_gradient"):
            value = getattr(envelope, field)
            if value > PARAM_BOUND:
                raise InputError(f"{where}: {field} = {value!r}: the mujoco engine takes at most 1e12 (SI)")
        for field in NO_LIMIT_FIELDS:  # inf is the plugin's -1, no limit
            value = getattr(envelope, field)
            if math.isfinite(value) and value > PARAM_BOUND:
                raise InputError(
                    f"{where}: {field} = {value!r}: the mujoco engine takes at most 1e12 or inf (SI)"
                )


def stand_spec(scenario: Scenario) -> tuple[mujoco.MjSpec, MjDrive]:
    """The scenario's test stand as an ``MjSpec`` (one body, one DOF, PhysX's solver) and its drive."""
    import mujoco

    from drive_envelope._src.adapters.mujoco.solver import set_solver

    spec = mujoco.MjSpec()
    spec.modelname = scenario.name or "teststand"
    spec.option.timestep = scenario.simulation.dt
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    inertia = scenario.joint.inertia
    body = spec.worldbody.add_body(name="load", explicitinertial=True)
    pendulum = scenario.pendulum
    if scenario.joint.type == "revolute":
        body.mass, body.inertia = 1.0, [inertia, inertia, inertia]
    else:
        body.mass, body.inertia = inertia, [1.0, 1.0, 1.0]
    if pendulum is not None:  # straight down (-Y, along gravity) at position = -angle_offset
        offset, distance = pendulum.angle_offset, pendulum.distance
        body.mass = pendulum.mass
        body.ipos = [distance * math.sin(offset), -distance * math.cos(offset), 0.0]
        spec.option.gravity = [0.0, -scenario.simulation.gravity, 0.0]
    _add_joint(body, "joint", [0.0, 0.0, 1.0], scenario.joint, scenario.friction, scenario.simulation.dt)
    envelope = scenario.effective_envelope()
    drive = _add_stand_drive(spec, "joint", "drive", scenario.drive, envelope, scenario.joint.type)
    sim = scenario.simulation
    set_solver(spec, sim.solver, position_iterations=sim.position_iterations,
               velocity_iterations=sim.velocity_iterations)  # fmt: skip
    return spec, drive


def _add_joint(
    body: Any,
    name: str,
    axis: list[float],
    joint: JointSpec | ChainJoint,
    friction: FrictionSpec,
    dt: float,
) -> None:
    """A hinge or slide (``joint.type``) along ``axis`` with the joint's armature and ``friction``.

    Viscous friction is the linear ``damping``; Coulomb friction the ``frictionloss`` constraint,
    made hard (``solreffriction = (2*dt, 1)``) so that a stopping joint sticks as in PhysX.
    """
    import mujoco

    kind = mujoco.mjtJoint.mjJNT_HINGE if joint.type == "revolute" else mujoco.mjtJoint.mjJNT_SLIDE
    added = body.add_joint(name=name, type=kind, axis=axis)
    added.armature = joint.armature
    added.damping = [friction.viscous_friction, 0.0, 0.0]  # MuJoCo 4: linear, then higher-order terms
    added.frictionloss = friction.dynamic_friction
    added.solref_friction = [2.0 * dt, 1.0]
    added.solimp_friction = [0.9999, 0.9999, 0.001, 0.5, 2.0]


def simulate(scenario: Scenario, *, schedule: DriveSchedule | None = None) -> Trajectory:
    """Run the scenario in MuJoCo with the plugin; ``steps + 1`` rows, row 0 the initial state.

    Args:
        scenario: The scenario (SI).
        schedule: Per-step drive targets and power state, or None for the scenario's targets.

    Raises:
        InputError: a scenario MuJoCo cannot represent, a schedule of the wrong length, or a
            diverging simulation.
    """
    import mujoco

    _check(scenario)
    if schedule is not None:
        schedule.check_steps(scenario.simulation.steps, _where(scenario))
    spec, drive = stand_spec(scenario)
    model = _compile(spec, f"{_where(scenario)}: MuJoCo cannot build the test stand")
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
    position, velocity, effort = np.empty(count + 1), np.empty(count + 1), np.zeros(count + 1)
    position[0], velocity[0] = data.qpos[0], data.qvel[0]
    with mujoco_warnings(_drop):
        for i in range(1, count + 1):
            if schedule is not None:
                _command(model, data, drive, scenario, schedule, i - 1)
            mujoco.mj_step(model, data)
            _raise_on_warning(_where(scenario), data, i)
            position[i], velocity[i], effort[i] = data.qpos[0], data.qvel[0], data.actuator_force[0]
    return stand_run(scenario, "mujoco", position, velocity, effort, **_metadata(scenario))


def _command(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    drive: MjDrive,
    scenario: Scenario,
    schedule: DriveSchedule,
    index: int,
) -> None:
    """Write step ``index``'s targets, and the drive's gains (0 while unpowered)."""
    from drive_envelope._src.adapters.mujoco.params import get_gains, set_gains

    drive.set_targets(
        model,
        data,
        position=float(schedule.target_position[index]),
        velocity=float(schedule.target_velocity[index]),
    )
    powered = bool(schedule.enabled[index])
    if (get_gains(model, drive.name) != (0.0, 0.0)) != powered:
        gains = _plugin_envelope(scenario.drive, scenario.effective_envelope(), scenario.joint.type)[1:3]
        set_gains(model, drive.name, stiffness=gains[0] * powered, damping=gains[1] * powered)


def _compile(spec: mujoco.MjSpec, failure: str) -> mujoco.MjModel:
    """``spec`` compiled to stop at a diverging step; a compile error is ``failure: MuJoCo's message``."""
    import mujoco

    # MuJoCo resets a diverging simulation (|v| > 1e10) and goes on: stop with an error instead
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    try:
        return spec.compile()
    except ValueError as exc:
        raise InputError(f"{failure}: {' '.join(str(exc).split())}") from None


def _drop(message: str) -> None:
    """Keep MuJoCo from printing its own warning line: the per-step check reports it as one error."""


def _raise_on_warning(where: str, data: mujoco.MjData, step: int) -> None:
    """Stop at the first step MuJoCo flagged (a NaN or a value above 1e10 in its state)."""
    import mujoco

    for name in _WARNINGS:
        stat = data.warning[int(getattr(mujoco.mjtWarning, name))]
        if stat.number > 0:
            text = mujoco.mju_warningText(int(getattr(mujoco.mjtWarning, name)), int(stat.lastinfo))
            raise InputError(
                f"{where}: MuJoCo stopped at step {step} (t = {data.time:.6g} s): "
                f"{text.rstrip('.')} (the state diverged: check dt, inertia, gains and loads)"
            )


def _metadata(scenario: Scenario) -> dict[str, object]:
    """What a one-joint run's metadata adds to the solver settings (:func:`stand_run` puts them first)."""
    import mujoco

    return {
        "plugin_solver": scenario.simulation.solver,
        "mujoco_version": str(mujoco.__version__),
        "integrator": "Euler",
        "plugin": PLUGIN_NAME,
        "unlimited_effort": math.isinf(scenario.drive.max_effort),
    }


# -- chains -------------------------------------------------------------------------------------------


def chain_spec(scenario: ChainScenario) -> tuple[mujoco.MjSpec, list[MjDrive]]:
    """A chain scenario as an ``MjSpec``: nested bodies, a plugin drive on every joint, PhysX's solver.

    Each joint's body sits at its ``origin`` in its parent's body, turned by the joint's ``quat``
    (the body ``quat``), with the link's mass, centre of mass and principal inertia along
    ``inertia_quat`` (the inertial ``quat``); the joint's axis is in the body's frame, as the
    scenario's is; gravity is along -Z; Euler integration. The plugin iterates the
    drives as the scenario's PhysX solver does (``set_solver(spec, solver, position_iterations=,
    velocity_iterations=)``).
    """
    import mujoco

    from drive_envelope._src.adapters.mujoco.solver import set_solver

    spec = mujoco.MjSpec()
    spec.modelname = scenario.name or "chain"
    sim = scenario.simulation
    spec.option.timestep = sim.dt
    spec.option.gravity = [0.0, 0.0, -sim.gravity]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    bodies: list[Any] = []
    drives = []
    for joint in scenario.joints:
        parent = spec.worldbody if joint.parent < 0 else bodies[joint.parent]
        body = parent.add_body(name=joint.name, pos=list(joint.origin), quat=list(joint.quat),
                               explicitinertial=True)  # fmt: skip
        body.mass, body.ipos, body.inertia = joint.mass, list(joint.com), list(joint.inertia)
        body.iquat = list(joint.inertia_quat)
        bodies.append(body)
        if joint.friction.static_friction != joint.friction.dynamic_friction:
            raise InputError(
                f"joint {joint.name!r}: key 'friction.static_friction': the mujoco engine has one Coulomb "
                "friction (frictionloss) and needs it equal to friction.dynamic_friction"
            )
        _add_joint(body, joint.name, list(joint.axis_vector), joint, joint.friction, sim.dt)
        envelope = joint.effective_envelope()
        drives.append(
            _add_stand_drive(spec, joint.name, f"{joint.name}_drive", joint.drive, envelope, joint.type)
        )
    set_solver(spec, sim.solver, position_iterations=sim.position_iterations,
               velocity_iterations=sim.velocity_iterations)  # fmt: skip
    return spec, drives


def simulate_chain(scenario: ChainScenario) -> ChainTrajectory:
    """Run a chain scenario in MuJoCo with the plugin on every joint; row 0 the initial state.

    Raises:
        InputError: a scenario MuJoCo cannot represent, or a diverging simulation.
    """
    import mujoco

    spec, drives = chain_spec(scenario)
    model = _compile(spec, f"{_where(scenario)}: MuJoCo cannot build the chain")
    data = mujoco.MjData(model)
    joints = scenario.joints
    qpos = [int(model.jnt_qposadr[model.joint(j.name).id]) for j in joints]
    dof = [int(model.jnt_dofadr[model.joint(j.name).id]) for j in joints]
    for joint, qi, di, drive in zip(joints, qpos, dof, drives, strict=True):
        data.qpos[qi], data.qvel[di] = joint.initial_position, joint.initial_velocity
        data.qfrc_applied[di] = joint.load.external_effort
        drive.set_targets(model, data, position=joint.drive.target_position,
                          velocity=joint.drive.target_velocity, effort=joint.load.applied_effort)  # fmt: skip
    count, n = scenario.simulation.steps, len(joints)
    position, velocity, effort = np.zeros((count + 1, n)), np.zeros((count + 1, n)), np.zeros((count + 1, n))
    position[0], velocity[0] = data.qpos[qpos], data.qvel[dof]
    actuators = [model.actuator(drive.name).id for drive in drives]
    with mujoco_warnings(_drop):
        for i in range(1, count + 1):
            mujoco.mj_step(model, data)
            _raise_on_warning(_where(scenario), data, i)
            position[i], velocity[i], effort[i] = (
                data.qpos[qpos],
                data.qvel[dof],
                data.actuator_force[actuators],
            )
    return chain_run(
        scenario, "mujoco", position, velocity, effort, mujoco_version=str(mujoco.__version__),
        integrator="Euler", plugin=PLUGIN_NAME, plugin_solver=scenario.simulation.solver,
        effort_source="the plugin's actuator force (drive + applied effort)",
    )  # fmt: skip

"""drive_envelope.mjlab in real mjlab: a tiny scene stepping mjlab's Unitree Go1 on CPU.

These tests need mjlab, which pins MuJoCo 3.11: they run in their own virtual environment
(``scripts/test_mjlab.sh``, part of ``make test``) and skip elsewhere. Two environments, the Go1
from mjlab's asset zoo with one actuator group for the hips and thighs and one for the knees
(the Go1's own limits: 23.7 N*m / 30.1 rad/s, 35.55 N*m / 20.06 rad/s), squatting fast enough to
saturate. The explicit actuator, with either clip rule, is checked against the float64 NumPy
reference (an independent implementation; for the end-of-step clip with every input rebuilt from
MuJoCo's outputs); the implicit one against the envelope and the PD law at the end-of-step velocity.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

# mjlab.actuator, not mjlab: without mjlab, this folder itself is importable as a namespace "mjlab"
pytest.importorskip("mjlab.actuator", reason="needs mjlab in its own environment: run scripts/test_mjlab.sh")


from drive_envelope import InputError, PerformanceEnvelope, clamp_effort

NUM_ENVS = 2
HIP = {"max_effort": 23.7, "max_actuator_velocity": 30.1, "speed_effort_gradient": 0.5}
KNEE = {"max_effort": 35.55, "max_actuator_velocity": 20.06, "velocity_dependent_resistance": 0.1}


def _scene(implicit: bool, clip: str = "end_of_step") -> tuple[Any, Any, Any]:
    """(scene, simulation, robot) of the Go1 with envelope actuators, contacts and limits off if implicit."""
    import warp as wp
    from mjlab.asset_zoo.robots.unitree_go1 import go1_constants as go1
    from mjlab.entity import EntityArticulationInfoCfg
    from mjlab.scene import Scene, SceneCfg
    from mjlab.sim import MujocoCfg, Simulation, SimulationCfg
    from mjlab.terrains import TerrainEntityCfg

    from drive_envelope.mjlab import PerformanceEnvelopeActuatorCfg

    wp.config.quiet = True
    common = {"stiffness": 40.0, "damping": 1.0, "implicit": implicit, "clip": clip}
    hip = PerformanceEnvelopeActuatorCfg(
        target_names_expr=(".*_hip_joint", ".*_thigh_joint"),
        armature=go1.HIP_ACTUATOR.reflected_inertia,
        **common,
        **HIP,
    )
    knee = PerformanceEnvelopeActuatorCfg(
        target_names_expr=(".*_calf_joint",), armature=go1.KNEE_ACTUATOR.reflected_inertia, **common, **KNEE
    )
    robot = go1.get_go1_robot_cfg()
    robot.articulation = EntityArticulationInfoCfg(actuators=(hip, knee))
    # the implicit law is exact where no constraint acts after the actuators: no contacts, no limits
    terrain = None if implicit else TerrainEntityCfg(terrain_type="plane")
    flags = ("contact", "limit") if implicit else ()
    scene = Scene(SceneCfg(num_envs=NUM_ENVS, entities={"robot": robot}, terrain=terrain), device="cpu")
    cfg = SimulationCfg(mujoco=MujocoCfg(disableflags=flags))
    sim = Simulation(num_envs=NUM_ENVS, cfg=cfg, spec=scene.spec, device="cpu")
    scene.initialize(sim.mj_model, sim.model, sim.data)
    return scene, sim, scene["robot"]


def _squat(robot: Any, step: int, dt: float) -> Any:
    """Joint targets: every joint 0.8 rad around its default at 14 rad/s, beyond what the motors follow."""
    import torch

    home = robot.data.default_joint_pos
    return home + 0.8 * np.sin(14 * step * dt) * torch.ones_like(home)


@pytest.fixture(scope="module")
def explicit() -> tuple[Any, Any, Any]:
    return _scene(implicit=False, clip="start_of_step")


@pytest.fixture(scope="module")
def implicit() -> tuple[Any, Any, Any]:
    return _scene(implicit=True)


def test_mjlab_fuses_the_envelope_actuators(explicit: Any) -> None:
    """Batch both groups in mjlab's fused path (param_names + control_law), none left to compute alone."""
    _, _, robot = explicit
    assert robot._custom_actuators == ()  # every actuator of ours went into a fused group
    assert len(robot.actuators) == 2
    assert all(type(a).__name__ == "StartOfStepEnvelopeActuator" for a in robot.actuators)


def test_start_of_step_efforts_are_the_envelope_clip_at_the_current_velocity(explicit: Any) -> None:
    """clip='start_of_step': the float64 reference clamp_effort(envelope, PD, v), within float32 noise."""
    scene, sim, robot = explicit
    dt = sim.cfg.mujoco.timestep
    worst, saturated, total = 0.0, 0, 0
    for step in range(150):
        target = _squat(robot, step, dt)
        robot.set_joint_position_target(target)
        q0, v0 = robot.data.joint_pos.clone(), robot.data.joint_vel.clone()
        scene.write_data_to_sim()
        sim.step()
        scene.update(dt)
        tau = sim.data.actuator_force.clone()
        for actuator in robot.actuators:
            ids, ctrl = actuator.target_ids, actuator.global_ctrl_ids
            pd = (40.0 * (target[:, ids] - q0[:, ids]) - 1.0 * v0[:, ids]).double().numpy()
            reference = clamp_effort(actuator.envelope, pd, v0[:, ids].double().numpy())
            worst = max(worst, float(np.abs(tau[:, ctrl].double().numpy() - reference).max()))
            saturated += int((np.abs(reference) < np.abs(pd) - 1e-9).sum())
            total += reference.size
    assert worst < 1e-4
    assert saturated > 0.05 * total


@pytest.fixture(scope="module")
def end_of_step() -> tuple[Any, Any, Any]:
    return _scene(implicit=False, clip="end_of_step")


def test_end_of_step_efforts_are_physx_clamp_at_the_estimated_free_velocity(end_of_step: Any) -> None:
    """Equal NumPy's clamp_effort_implicit at v + (v - v_prev - r*dt*e_prev), r from MuJoCo's mj_solveM.

    The reference rebuilds every input in float64 from what MuJoCo reports: the velocities and
    applied efforts of the two last steps, and the response (M^-1)_ii at the configuration the last
    step started from (drive_envelope.mujoco.effective_inertia on a MuJoCo MjData), which the
    actuator read from MJWarp's own mass matrix. Both groups stay fused.
    """
    import mujoco

    from drive_envelope import clamp_effort_implicit
    from drive_envelope.mujoco import effective_inertia

    scene, sim, robot = end_of_step
    assert robot._custom_actuators == () and len(robot.actuators) == 2
    assert all(a.response_source == "mass_matrix" for a in robot.actuators)
    model, dt = sim.mj_model, sim.cfg.mujoco.timestep
    scratch = mujoco.MjData(model)
    past: list[Any] = []  # (qpos, v, tau) at each control time, tau the effort applied in that step
    worst, saturated, total = 0.0, 0, 0
    for step in range(120):
        target = _squat(robot, step, dt)
        robot.set_joint_position_target(target)
        qpos = sim.data.qpos[:].double().numpy().copy()
        q0, v0 = robot.data.joint_pos.double().numpy().copy(), robot.data.joint_vel.double().numpy().copy()
        scene.write_data_to_sim()
        sim.step()
        scene.update(dt)
        tau = sim.data.actuator_force.double().numpy().copy()
        if len(past) >= 2:
            qpos_prev, v_prev, tau_prev = past[-1]
            for actuator in robot.actuators:
                ids, ctrl = actuator.target_ids.tolist(), actuator.global_ctrl_ids.tolist()
                dofs = robot.indexing.joint_v_adr[actuator.target_ids].tolist()
                for w in range(NUM_ENVS):
                    scratch.qpos[:] = qpos_prev[w]
                    joints = [int(model.dof_jntid[d]) for d in dofs]
                    r = 1.0 / np.array(list(effective_inertia(model, scratch, joints).values()))
                    v = v0[w, ids]
                    free = v + (v - v_prev[w, ids] - r * dt * tau_prev[w, ctrl])
                    pd = 40.0 * (target[w, ids].double().numpy() - q0[w, ids]) - 1.0 * v
                    reference = clamp_effort_implicit(actuator.envelope, pd, free, r, dt)
                    worst = max(
                        worst, float(np.abs(tau[w, ctrl] - reference).max()) / actuator.envelope.max_effort
                    )
                    saturated += int((np.abs(reference) < np.abs(pd) - 1e-6).sum())
                    total += len(ids)
        past.append((qpos, v0, tau))
    assert worst < 1e-3  # float32 buffers against float64 (a clamp near the line amplifies rounding)
    assert saturated > 0.05 * total


def test_set_envelope_changes_one_environment(explicit: Any) -> None:
    """Cap one environment's knees lower with set_envelope; the other keeps the Go1's."""
    import torch

    scene, sim, robot = explicit
    knees = robot.actuators[1]
    knees.set_envelope(torch.tensor([1]), PerformanceEnvelope(max_effort=5.0))
    peak = torch.zeros(NUM_ENVS)
    try:
        for step in range(60):
            robot.set_joint_position_target(_squat(robot, step, sim.cfg.mujoco.timestep))
            scene.write_data_to_sim()
            sim.step()
            tau = sim.data.actuator_force[:, knees.global_ctrl_ids].abs().amax(dim=1)
            peak = torch.maximum(peak, tau.cpu())
        assert float(peak[1]) <= 5.0 + 1e-5 < float(peak[0])
    finally:
        knees.set_envelope(slice(None), PerformanceEnvelope(**KNEE))


def test_implicit_drives_stay_inside_at_the_end_of_step_velocity(implicit: Any) -> None:
    """Keep every drive inside (or released) at the velocity MJWarp integrated, the PD law exact inside."""
    from drive_envelope.mjwarp import envelope_drives

    scene, sim, robot = implicit
    drives = envelope_drives(sim.wp_model)
    assert drives.count == 12
    stats = drives.track(NUM_ENVS)
    dt = sim.cfg.mujoco.timestep
    samples = outside = boundary = 0
    law_error, most = 0.0, 0
    for step in range(200):
        target = _squat(robot, step, dt)
        robot.set_joint_position_target(target)
        q0 = robot.data.joint_pos.clone().double().numpy()
        scene.write_data_to_sim()
        sim.step()
        scene.update(dt)
        v1 = robot.data.joint_vel.clone().double().numpy()
        tau = sim.data.actuator_force.clone().double().numpy()
        most = max(most, int(stats.numpy()[:, 0].max()))
        for actuator in robot.actuators:
            env = actuator.envelope
            for joint, ctrl in zip(
                actuator.target_ids.tolist(), actuator.global_ctrl_ids.tolist(), strict=True
            ):
                v, f = v1[:, joint], tau[:, ctrl]
                law = 40.0 * (target[:, joint].double().numpy() - q0[:, joint] - dt * v) - 1.0 * v
                for w in range(NUM_ENVS):
                    effort_margin, velocity_margin = env.margins(v[w], f[w])
                    relative = min(
                        effort_margin / env.max_effort, velocity_margin / env.max_actuator_velocity
                    )
                    samples += 1
                    if f[w] == 0.0 and abs(v[w]) > env.no_load_velocity():
                        continue  # released: driven above the no-load speed by the others (PhysX lets go)
                    if relative < -1e-6:
                        outside += 1
                    elif relative > 1e-6:
                        law_error = max(law_error, abs(law[w] - f[w]) / env.max_effort)
                    else:
                        boundary += 1
    assert outside == 0
    assert boundary > 0
    assert law_error < 1e-4
    assert most <= 8


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"max_effort": -3.0}, r"max_effort = .*-3\.0"),
        ({}, "max_effort \\(or envelope\\) is required"),
        ({"max_effort": 2.0, "envelope": "tmotor-ak80-6"}, "not both"),
        ({"max_effort": "12 furlongs"}, "max_effort"),
        ({"envelope": "no-such-actuator"}, "no-such-actuator"),
        ({"max_effort": 2.0, "stiffness": -1.0}, "stiffness = -1.0"),
    ],
)
def test_bad_configs_are_one_line_errors(fields: dict[str, Any], match: str) -> None:
    """Refuse bad numbers when the config is made, naming the field and the value."""
    from drive_envelope.mjlab import PerformanceEnvelopeActuatorCfg

    given = {"target_names_expr": (".*",), "stiffness": 1.0, "damping": 0.1, **fields}
    with pytest.raises(InputError, match=match) as info:
        PerformanceEnvelopeActuatorCfg(**given)
    assert "\n" not in str(info.value)


def test_a_catalog_envelope_is_read_with_units() -> None:
    """Take the envelope from the catalog, or the four numbers as strings with units."""
    from drive_envelope.mjlab import PerformanceEnvelopeActuatorCfg

    by_name = PerformanceEnvelopeActuatorCfg(
        target_names_expr=(".*",), stiffness=1, damping=0, envelope="tmotor-ak80-6"
    )
    assert by_name.resolved().max_effort == pytest.approx(12.0)
    by_units = PerformanceEnvelopeActuatorCfg(
        target_names_expr=(".*",), stiffness=1, damping=0, max_effort="2 N*m", max_actuator_velocity="300 rpm"
    )
    assert by_units.resolved().max_actuator_velocity == pytest.approx(300 * 2 * np.pi / 60)

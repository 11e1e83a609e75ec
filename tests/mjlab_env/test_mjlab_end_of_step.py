"""drive_envelope.mjlab's end-of-step clip (issue 22) in real mjlab on CPU: the one-joint stand and the G1.

The stand is issue 22's: one hinge of 0.05 kg*m^2 (no gravity, no damping, Euler), dt = 5 ms,
from rest to a 1 rad target with the catalog Franka shoulder, Go2 calf and G1 knee envelopes and
gains that reach each speed line, with no load and with a constant load holding the joint back
(``qfrc_applied``). Each world of one mjlab scene is one case (envelopes and gains per world). The
golden trajectory is computed independently: the PD request clamped by the PhysX-exact NumPy
``clamp_drive_impulse`` at the end-of-step velocity (what PhysX's implicit drive does), integrated
by hand. The response comes from the model (MJWarp's mass matrix): no effective_inertia is given.

The G1 from mjlab's asset zoo (29 joints on the floor, its actuator groups replaced by envelope
actuators with the G1's own limits and gains; the knees with the catalog's 7520-22 envelope and the
stand's gains) steps its knee targets by 2.1 rad: the share of knee samples where the PD law asks for
effort and gets 0, start-of-step against end-of-step.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

pytest.importorskip("mjlab.actuator", reason="needs mjlab in its own environment: run scripts/test_mjlab.sh")

import drive_envelope as de
from drive_envelope import InputError
from drive_envelope.datasheet import resolve_envelope

INERTIA, DT, STEPS = 0.05, 0.005, 600  # kg*m^2, s
STANDS = [  # gains that reach each speed line from rest (critically damped on 0.05 kg*m^2)
    ("franka-panda-joint1-4", 80.0, 4.0),
    ("unitree-go2-calf", 400.0, 9.0),
    ("unitree-g1-7520-22", 400.0, 9.0),
]
LOADS = (0.0, -0.2)  # share of max_effort, against the motion
CASES = [(stand, load) for stand in STANDS for load in LOADS]


def _stand_spec() -> Any:
    import mujoco

    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="arm")
    body.add_joint(name="joint", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0])
    body.mass = 1.0
    body.inertia = [INERTIA, INERTIA, INERTIA]
    body.explicitinertial = True
    return spec


def _stand_scene(clip: str, envs: int, inertia: Any = None) -> tuple[Any, Any, Any]:
    import warp as wp
    from mjlab.entity import EntityArticulationInfoCfg, EntityCfg
    from mjlab.scene import Scene, SceneCfg
    from mjlab.sim import MujocoCfg, Simulation, SimulationCfg

    from drive_envelope.mjlab import PerformanceEnvelopeActuatorCfg

    wp.config.quiet = True
    # the first stand's envelope and gains; every world gets its own below
    source, kp, kd = STANDS[0]
    drive = PerformanceEnvelopeActuatorCfg(
        target_names_expr=("joint",),
        stiffness=kp,
        damping=kd,
        envelope=source,
        clip=clip,
        effective_inertia=inertia,
    )
    robot = EntityCfg(spec_fn=_stand_spec, articulation=EntityArticulationInfoCfg(actuators=(drive,)))
    scene = Scene(SceneCfg(num_envs=envs, entities={"robot": robot}), device="cpu")
    cfg = SimulationCfg(mujoco=MujocoCfg(timestep=DT, integrator="euler", gravity=(0.0, 0.0, 0.0)))
    sim = Simulation(num_envs=envs, cfg=cfg, spec=scene.spec, device="cpu")
    scene.initialize(sim.mj_model, sim.model, sim.data)
    return scene, sim, scene["robot"]


def _run_stand(clip: str, cases: list[Any]) -> tuple[Any, Any, Any]:
    """Step the cases (one per world) from rest to 1 rad: positions, velocities (steps, worlds), actuator."""
    import torch

    scene, sim, robot = _stand_scene(clip, len(cases))
    actuator = robot.actuators[0]
    loads = []
    for world, ((source, kp, kd), share) in enumerate(cases):
        ids = torch.tensor([world])
        actuator.set_envelope(ids, source)
        actuator.set_gains(ids, torch.tensor([kp]), torch.tensor([kd]))
        loads.append(share * resolve_envelope(source).max_effort)
    dof = int(robot.indexing.joint_v_adr[0])
    qs, vs = [], []
    for _ in range(STEPS):
        robot.set_joint_position_target(torch.ones((len(cases), 1)))
        sim.data.qfrc_applied[:, dof] = torch.tensor(loads, dtype=torch.float)
        scene.write_data_to_sim()
        sim.step()
        scene.update(DT)
        qs.append(robot.data.joint_pos[:, 0].double().numpy().copy())
        vs.append(robot.data.joint_vel[:, 0].double().numpy().copy())
    return np.array(qs), np.array(vs), actuator


def _reference(source: str, kp: float, kd: float, load: float) -> tuple[Any, Any]:
    """PhysX's implicit drive on the stand: the PD request clamped at the end-of-step velocity, by hand."""
    envelope = resolve_envelope(source)
    q = v = 0.0
    qs, vs = [], []
    for _ in range(STEPS):
        request = kp * (1.0 - q) - kd * v
        v0 = v + DT * load / INERTIA  # the load is in the velocity before the drive is clamped
        impulse = de.clamp_drive_impulse(
            v0,
            0.0,
            request * DT,
            1.0 / INERTIA,
            envelope.max_actuator_velocity,
            envelope.max_effort * DT,
            envelope.speed_effort_gradient / DT,
            envelope.velocity_dependent_resistance * DT,
            physx_exact=True,
        )
        v = v0 + float(impulse) / INERTIA
        q += v * DT
        qs.append(q)
        vs.append(v)
    return np.array(qs), np.array(vs)


@pytest.fixture(scope="module")
def end_of_step() -> tuple[Any, Any, Any]:
    return _run_stand("end_of_step", CASES)


def test_response_comes_from_the_model_mass_matrix(end_of_step: Any) -> None:
    """No effective_inertia given: the response is 1/0.05 from MJWarp's M (float32), every world."""
    _, _, actuator = end_of_step
    assert actuator.response_source == "mass_matrix"
    assert actuator.response.flatten().tolist() == pytest.approx([1.0 / INERTIA] * len(CASES), rel=1e-6)


@pytest.mark.parametrize(
    ("inertia", "source", "response"),
    [("model", "model", 1.0 / INERTIA), ({"j.*": "0.1 kg*m^2"}, "effective_inertia", 10.0)],
)
def test_response_from_the_keyframe_or_the_config(inertia: Any, source: str, response: float) -> None:
    """effective_inertia='model' keeps the keyframe's (M^-1)_ii; a regex dict with units is read as given."""
    _, _, robot = _stand_scene("end_of_step", 1, inertia)
    actuator = robot.actuators[0]
    assert actuator.response_source == source
    assert actuator.response.flatten().tolist() == pytest.approx([response], rel=1e-6)


def test_effective_inertia_dict_must_name_every_target() -> None:
    """A dict that misses a target is refused at initialize, naming the target."""
    with pytest.raises(InputError, match=r"effective_inertia: target '.*joint' is not named"):
        _stand_scene("end_of_step", 1, {"elbow": 0.1})


@pytest.mark.parametrize("case", range(len(CASES)), ids=[f"{s[0]}-load{share}" for s, share in CASES])
def test_end_of_step_follows_physx_rule_on_the_stand(end_of_step: Any, case: int) -> None:
    """Within 0.05 rad of PhysX's clamp, ends at the PD rest, at most 1 % of steps above 1.05x the line."""
    (source, kp, kd), share = CASES[case]
    envelope = resolve_envelope(source)
    load = share * envelope.max_effort
    q_ref, v_ref = _reference(source, kp, kd, load)
    qs, vs, _ = end_of_step
    q, v = qs[:, case], vs[:, case]
    assert np.max(np.abs(q - q_ref)) <= 0.05
    assert abs(q[-1] - (1.0 + load / kp)) < 0.01  # the PD law's rest position under the load
    assert np.mean(np.abs(v) > 1.05 * envelope.max_actuator_velocity) <= 0.01
    assert np.max(np.abs(v_ref)) >= 0.999 * envelope.max_actuator_velocity  # the stand reaches the line


def test_start_of_step_runs_away_on_the_stand() -> None:
    """clip='start_of_step' (today's explicit rule, kept by name): past the line after one step, then 0."""
    qs, _, actuator = _run_stand("start_of_step", [(stand, 0.0) for stand in STANDS])
    assert type(actuator).__name__ == "StartOfStepEnvelopeActuator"
    assert np.all(qs[-1] > 10.0)


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"clip": "implicit"}, r"clip = 'implicit'; expected one of 'end_of_step', 'start_of_step'"),
        ({"effective_inertia": -0.1}, r"effective_inertia: -0\.1; expected > 0 and finite"),
        ({"effective_inertia": "2 N*m"}, "effective_inertia"),
        ({"effective_inertia": [0.1]}, r"effective_inertia: got \[0\.1\]; expected a number"),
        ({"physics_dt": 0.0}, r"physics_dt: got 0\.0; expected a time step > 0"),
        ({"transmission_type": "site"}, r"clip: 'end_of_step' needs a joint or tendon transmission"),
        ({"transmission_type": "tendon"}, r"effective_inertia: needed for a tendon transmission"),
    ],
)
def test_bad_clip_fields_are_one_line_errors(fields: dict[str, Any], match: str) -> None:
    """Refuse a bad rule, inertia, time step or transmission when the config is made, in one line."""
    from mjlab.actuator.actuator import TransmissionType

    from drive_envelope.mjlab import PerformanceEnvelopeActuatorCfg

    if "transmission_type" in fields:
        fields = {**fields, "transmission_type": TransmissionType(fields["transmission_type"])}
    given = {"target_names_expr": (".*",), "stiffness": 1.0, "damping": 0.1, "max_effort": 2.0, **fields}
    with pytest.raises(InputError, match=match) as info:
        PerformanceEnvelopeActuatorCfg(**given)
    assert "\n" not in str(info.value)


# -- the G1 from mjlab's asset zoo: requests answered with 0 ------------------------------------


G1_ENVS, G1_STEPS = 2, 200


def _g1_scene(clip: str) -> tuple[Any, Any, Any]:
    """The zoo's G1 on a plane, each of its six actuator groups an envelope actuator with its own numbers."""
    import warp as wp
    from mjlab.asset_zoo.robots.unitree_g1 import g1_constants as g1
    from mjlab.entity import EntityArticulationInfoCfg
    from mjlab.scene import Scene, SceneCfg
    from mjlab.sim import MujocoCfg, Simulation, SimulationCfg
    from mjlab.terrains import TerrainEntityCfg

    from drive_envelope.mjlab import PerformanceEnvelopeActuatorCfg

    wp.config.quiet = True
    speeds = {  # each group's motor speed limit [rad/s] (g1_constants' ElectricActuator)
        id(g1.G1_ACTUATOR_5020): g1.ACTUATOR_5020.velocity_limit,
        id(g1.G1_ACTUATOR_7520_14): g1.ACTUATOR_7520_14.velocity_limit,
        id(g1.G1_ACTUATOR_7520_22): g1.ACTUATOR_7520_22.velocity_limit,
        id(g1.G1_ACTUATOR_4010): g1.ACTUATOR_4010.velocity_limit,
        id(g1.G1_ACTUATOR_WAIST): g1.ACTUATOR_5020.velocity_limit,
        id(g1.G1_ACTUATOR_ANKLE): g1.ACTUATOR_5020.velocity_limit,
    }
    groups = [
        PerformanceEnvelopeActuatorCfg(
            target_names_expr=tuple(n for n in group.target_names_expr if "knee" not in n),
            stiffness=group.stiffness,
            damping=group.damping,
            armature=group.armature,
            max_effort=group.effort_limit,
            max_actuator_velocity=speeds[id(group)],
            clip=clip,
        )
        for group in g1.G1_ARTICULATION.actuators
    ]
    # the knees: the catalog's G1 7520-22 envelope (139 N*m, 20 rad/s) and the stand's stiff gains
    knee = g1.G1_ACTUATOR_7520_22
    groups.append(
        PerformanceEnvelopeActuatorCfg(
            target_names_expr=(".*_knee_joint",),
            stiffness=400.0,
            damping=9.0,
            armature=knee.armature,
            envelope="unitree-g1-7520-22",
            clip=clip,
        )
    )
    robot = g1.get_g1_robot_cfg()
    robot.articulation = EntityArticulationInfoCfg(actuators=tuple(groups))
    scene = Scene(
        SceneCfg(num_envs=G1_ENVS, entities={"robot": robot}, terrain=TerrainEntityCfg(terrain_type="plane")),
        device="cpu",
    )
    sim = Simulation(
        num_envs=G1_ENVS, cfg=SimulationCfg(mujoco=MujocoCfg(timestep=DT)), spec=scene.spec, device="cpu"
    )
    scene.initialize(sim.mj_model, sim.model, sim.data)
    return scene, sim, scene["robot"]


def _zero_share(clip: str) -> tuple[float, int, Any]:
    """Knee samples whose PD request is above 1 % of max_effort and whose effort is 0."""
    scene, sim, robot = _g1_scene(clip)
    home = robot.data.default_joint_pos.clone()
    asked = starved = 0
    knees = robot.actuators[-1]
    columns = knees.target_ids
    for step in range(G1_STEPS):
        target = home.clone()
        target[:, columns] = 2.2 if (step // 50) % 2 else 0.1  # knee targets jump 2.1 rad every 0.25 s
        robot.set_joint_position_target(target)
        q0, v0 = robot.data.joint_pos.clone(), robot.data.joint_vel.clone()
        scene.write_data_to_sim()
        sim.step()
        scene.update(DT)
        tau = sim.data.actuator_force[:, knees.global_ctrl_ids]
        pd = knees.stiffness * (target[:, columns] - q0[:, columns]) - knees.damping * v0[:, columns]
        asks = pd.abs() > 0.01 * knees.max_effort
        asked += int(asks.sum())
        starved += int((asks & (tau == 0.0)).sum())
    return starved / max(asked, 1), asked, robot


def test_g1_end_of_step_answers_what_start_of_step_starves() -> None:
    """Knee targets jumping 2.1 rad: start-of-step gives 0 to many requests, end-of-step to few."""
    start, asked_start, _ = _zero_share("start_of_step")
    end, asked_end, robot = _zero_share("end_of_step")
    print(
        f"G1 {G1_STEPS} steps x {G1_ENVS} worlds: requests given 0: start_of_step {start:.1%} of "
        f"{asked_start}, end_of_step {end:.1%} of {asked_end}"
    )
    assert all(a.response_source == "mass_matrix" for a in robot.actuators)
    assert start > 0.05
    assert end < 0.5 * start

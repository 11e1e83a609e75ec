"""mjlab's Unitree Go1 with the performance envelope on every joint, explicit or implicit.

Builds a two-environment mjlab scene of the Go1 from mjlab's asset zoo, its hips and thighs one
``PerformanceEnvelopeActuatorCfg`` group and its knees another (the Go1's own limits), squats it
for a second on CPU and prints each group's peak effort and speed. ``--implicit`` solves the drives
in MJWarp's step (PhysX's implicit drive, every drive together) instead of clipping the PD torque
in torch (PhysX's clamp at the end-of-step velocity, the explicit default; docs/mjlab.md). Needs
mjlab (MuJoCo 3.11): run it with ``.venv-mjlab`` (see ``scripts/test_mjlab.sh``).

    .venv-mjlab/bin/python examples/mjlab/go1_envelope.py [--implicit]
"""

from __future__ import annotations

import argparse
import logging

import numpy as np

from drive_envelope.mjlab import PerformanceEnvelopeActuatorCfg


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--implicit", action="store_true", help="solve the drives in MJWarp's step")
    args = parser.parse_args()
    import torch
    import warp as wp
    from mjlab.asset_zoo.robots.unitree_go1 import go1_constants as go1
    from mjlab.entity import EntityArticulationInfoCfg
    from mjlab.scene import Scene, SceneCfg
    from mjlab.sim import Simulation, SimulationCfg
    from mjlab.terrains import TerrainEntityCfg

    wp.config.log_level = logging.WARNING  # stdout: only what the example prints
    hips = PerformanceEnvelopeActuatorCfg(
        target_names_expr=(".*_hip_joint", ".*_thigh_joint"),
        stiffness=40.0,
        damping=1.0,
        max_effort=23.7,
        max_actuator_velocity=30.1,
        speed_effort_gradient=0.5,
        armature=go1.HIP_ACTUATOR.reflected_inertia,
        implicit=args.implicit,
    )
    knees = PerformanceEnvelopeActuatorCfg(
        target_names_expr=(".*_calf_joint",),
        stiffness=40.0,
        damping=1.0,
        max_effort=35.55,
        max_actuator_velocity=20.06,
        velocity_dependent_resistance=0.1,
        armature=go1.KNEE_ACTUATOR.reflected_inertia,
        implicit=args.implicit,
    )
    robot_cfg = go1.get_go1_robot_cfg()
    robot_cfg.articulation = EntityArticulationInfoCfg(actuators=(hips, knees))
    scene = Scene(
        SceneCfg(num_envs=2, entities={"robot": robot_cfg}, terrain=TerrainEntityCfg()), device="cpu"
    )
    sim = Simulation(num_envs=2, cfg=SimulationCfg(), spec=scene.spec, device="cpu")
    scene.initialize(sim.mj_model, sim.model, sim.data)
    # on a GPU with the implicit path, re-capture mjlab's graphs now that the drives are attached:
    # sim.create_graph()
    robot = scene["robot"]
    dt = sim.cfg.mujoco.timestep
    peaks = {id(a): [0.0, 0.0] for a in robot.actuators}
    for step in range(int(1.0 / dt)):
        home = robot.data.default_joint_pos
        robot.set_joint_position_target(home + 0.8 * np.sin(14 * step * dt) * torch.ones_like(home))
        scene.write_data_to_sim()
        sim.step()
        scene.update(dt)
        for actuator in robot.actuators:
            effort = float(sim.data.actuator_force[:, actuator.global_ctrl_ids].abs().max())
            speed = float(robot.data.joint_vel[:, actuator.target_ids].abs().max())
            peak = peaks[id(actuator)]
            peak[0], peak[1] = max(peak[0], effort), max(peak[1], speed)
    mode = "implicit (MJWarp step)" if args.implicit else "explicit (torch clip)"
    print(f"Go1, 2 environments, {mode}:")
    for actuator in robot.actuators:
        env = actuator.envelope
        effort, speed = peaks[id(actuator)]
        print(
            f"  {actuator.target_names[0]:>14s} ...: max_effort {env.max_effort:.2f} N*m, peak {effort:.2f}; "
            f"max_actuator_velocity {env.max_actuator_velocity:.2f} rad/s, peak {speed:.2f}"
        )


if __name__ == "__main__":
    main()

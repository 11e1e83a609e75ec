"""A real Isaac Lab 3.0 ``Articulation`` on the Newton backend (MuJoCo Warp solver), on the CPU.

Newton's cartpole asset (``../shared/data/newton-assets/cartpole.usda``: a prismatic rail joint and
two revolute pole joints), two environments cloned by Isaac Lab's cloner, stepped by Isaac Lab's
``SimulationContext`` with ``PerformanceEnvelopeActuatorCfg`` on every joint. Isaac Lab 3.0 runs
explicit actuator models in Isaac Lab only with ``use_newton_actuators=False`` (its default, True,
authors ``NewtonActuator`` prims and refuses configs it cannot author, ours included). Each step's
applied effort is checked against the float64 NumPy clamp at the velocity the step starts from.
First run about 90 s (Warp compiles MuJoCo Warp's kernels), about 15 s with Warp's kernel cache.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("isaaclab_newton.assets", reason="needs Isaac Lab 3.x: scripts/test_isaaclab3.sh")

CARTPOLE = Path(__file__).resolve().parents[3] / "shared" / "data" / "newton-assets" / "cartpole.usda"
ENVELOPE: dict[str, Any] = {"max_effort": 5.0, "max_actuator_velocity": 3.0, "speed_effort_gradient": 0.2}
NUM_ENVS, DT, STEPS = 2, 1.0 / 120.0, 60


@pytest.mark.skipif(not CARTPOLE.is_file(), reason=f"needs {CARTPOLE} (Newton's example assets)")
def test_cartpole_steps_on_newton_cpu_with_the_envelope_actuator() -> None:
    """Step a real Articulation: every applied effort is the envelope's clip of the PD effort."""
    import isaaclab.sim as sim_utils
    import torch
    from isaaclab.assets import ArticulationCfg
    from isaaclab.cloner import CloneCfg, clone_plan_from_env_0, replicate
    from isaaclab.sim import SimulationCfg, build_simulation_context
    from isaaclab_newton.assets import Articulation
    from isaaclab_newton.physics import MJWarpSolverCfg, NewtonCfg

    import drive_envelope as de
    from drive_envelope.isaaclab import PerformanceEnvelopeActuator, PerformanceEnvelopeActuatorCfg

    physics = NewtonCfg(
        solver_cfg=MJWarpSolverCfg(njmax=50, nconmax=50, integrator="implicitfast"),
        num_substeps=1,
        use_cuda_graph=False,
    )
    sim_cfg = SimulationCfg(dt=DT, physics=physics, use_newton_actuators=False, device="cpu")
    actuator_cfg = PerformanceEnvelopeActuatorCfg(
        joint_names_expr=[".*"],
        stiffness=50.0,
        damping=2.0,
        actuator_effort_limit=ENVELOPE["max_effort"],
        max_actuator_velocity=ENVELOPE["max_actuator_velocity"],
        speed_effort_gradient=ENVELOPE["speed_effort_gradient"],
        clip="start_of_step",
    )
    envelope = de.PerformanceEnvelope(**ENVELOPE)
    with build_simulation_context(
        device="cpu", gravity_enabled=True, add_ground_plane=False, sim_cfg=sim_cfg
    ) as sim:
        sim._app_control_on_stop_handle = None  # as Isaac Lab's own tests do without Kit
        sim_utils.create_prim("/World/Env_0", "Xform")
        robot_cfg = ArticulationCfg(
            prim_path="/World/Env_[^/]*/Robot",
            spawn=sim_utils.UsdFileCfg(usd_path=str(CARTPOLE)),
            actuators={"all": actuator_cfg},
        )
        positions = np.asarray([(3.0 * i, 0.0, 0.0) for i in range(NUM_ENVS)])
        clone_plan_from_env_0(
            CloneCfg(clone_template="/World/Env_{}"), (robot_cfg,), NUM_ENVS, 3.0, positions=positions
        )
        robot = Articulation(robot_cfg)
        replicate(sim.get_clone_plan())
        sim.reset()
        assert robot.joint_names == ["railCartJoint", "cartPoleJoint", "polePoleJoint"]
        actuator = robot.actuators["all"]
        assert isinstance(actuator, PerformanceEnvelopeActuator)
        robot.actuators.target_command.set_position_index(value=torch.full((NUM_ENVS, 3), 1.0))
        saturated = 0
        for _ in range(STEPS):
            start = robot.data.joint_vel.torch.clone()
            robot.write_data_to_sim()
            sim.step()
            robot.update(DT)
            applied = actuator.applied_effort.numpy().astype(np.float64)
            reference = de.clamp_effort(
                envelope,
                actuator.computed_effort.numpy().astype(np.float64),
                start.numpy().astype(np.float64),
            )
            np.testing.assert_allclose(applied, reference, rtol=1e-5, atol=1e-4)
            saturated += int((np.abs(actuator.computed_effort.numpy()) > np.abs(applied) + 1e-3).sum())
        assert saturated > 0  # the envelope bound, so the check above is not vacuous
        moved = robot.data.joint_pos.torch
        assert bool(torch.isfinite(moved).all()) and float(moved[:, 0].abs().max()) > 0.05

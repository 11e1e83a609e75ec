"""Isaac Lab 3.0's Newton-actuator route: the envelope as a Newton clamping stage, on CPU.

With ``use_newton_actuators=True`` (3.0's default) Isaac Lab authors ``NewtonActuator`` prims from
its own cfgs and Newton runs them. ``PerformanceEnvelopeArticulationCfg`` (its ``_post_spawn`` calls
``author_envelope_clamping``) adds ``DriveEnvelopeClampingAPI`` to the prims Isaac Lab authored
for an ``IdealPDActuatorCfg``; Newton's ``ModelBuilder.add_usd`` builds
our ``ClampingPerformanceEnvelope`` into ``model.actuators``. Newton's cartpole (two environments,
MuJoCo Warp solver, CPU) steps; every applied effort Isaac Lab reports equals the float64 NumPy
clamp (``drive_envelope.clamp_effort``) of the PD effort Newton computed, at the velocity the step
starts from (Newton's actuators run in explicit mode: they read ``State.joint_qd`` before the solve).
First run about 90 s (Warp compiles), about 15 s with Warp's kernel cache.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("isaaclab_newton.assets", reason="needs Isaac Lab 3.x: scripts/test_isaaclab3.sh")

# registered before any USD stage exists: USD builds its schema registry once, on first use
from drive_envelope.isaaclab import PerformanceEnvelopeArticulationCfg, register_envelope_clamping

register_envelope_clamping()

CARTPOLE = Path(__file__).resolve().parents[3] / "shared" / "data" / "newton-assets" / "cartpole.usda"
# float32-exact values: USD stores them as float, the reference clamps the same numbers in float64
ENVELOPE: dict[str, Any] = {"max_effort": 5.0, "max_actuator_velocity": 3.0, "speed_effort_gradient": 0.25}
NUM_ENVS, DT, STEPS = 2, 1.0 / 120.0, 60


def _newton_sim_cfg(use_newton_actuators: bool) -> Any:
    from isaaclab.sim import SimulationCfg
    from isaaclab_newton.physics import MJWarpSolverCfg, NewtonCfg

    physics = NewtonCfg(
        solver_cfg=MJWarpSolverCfg(njmax=50, nconmax=50, integrator="implicitfast"),
        num_substeps=1,
        use_cuda_graph=False,
    )
    return SimulationCfg(dt=DT, physics=physics, use_newton_actuators=use_newton_actuators, device="cpu")


@pytest.mark.skipif(not CARTPOLE.is_file(), reason=f"needs {CARTPOLE} (Newton's example assets)")
def test_cartpole_steps_with_the_envelope_as_newton_clamping_stage() -> None:
    """Isaac Lab 3.0 + Newton actuators: our clamping stage in model.actuators bounds every effort."""
    import isaaclab.sim as sim_utils
    import torch
    from isaaclab.actuators import IdealPDActuatorCfg
    from isaaclab.cloner import CloneCfg, clone_plan_from_env_0, replicate
    from isaaclab.sim import build_simulation_context
    from isaaclab_newton.assets import Articulation
    from isaaclab_newton.physics import NewtonManager

    import drive_envelope as de
    from drive_envelope.newton import ClampingPerformanceEnvelope

    envelope = de.PerformanceEnvelope(**ENVELOPE)
    with build_simulation_context(
        device="cpu", gravity_enabled=True, add_ground_plane=False, sim_cfg=_newton_sim_cfg(True)
    ) as sim:
        sim._app_control_on_stop_handle = None  # as Isaac Lab's own tests do without Kit
        sim_utils.create_prim("/World/Env_0", "Xform")
        robot_cfg = PerformanceEnvelopeArticulationCfg(
            prim_path="/World/Env_[^/]*/Robot",
            spawn=sim_utils.UsdFileCfg(usd_path=str(CARTPOLE)),
            # Isaac Lab authors NewtonPDControlAPI + NewtonMaxEffortClampingAPI (10 >= the envelope's cap)
            actuators={
                "all": IdealPDActuatorCfg(
                    joint_names_expr=[".*"], stiffness=50.0, damping=2.0, actuator_effort_limit=10.0
                )
            },
            envelope_clamping={"all": ENVELOPE},
        )
        positions = np.asarray([(3.0 * i, 0.0, 0.0) for i in range(NUM_ENVS)])
        clone_plan_from_env_0(
            CloneCfg(clone_template="/World/Env_{}"), (robot_cfg,), NUM_ENVS, 3.0, positions=positions
        )
        robot = Articulation(robot_cfg)
        prims = [p for p in sim.stage.Traverse() if p.GetTypeName() == "NewtonActuator"]
        assert len(prims) == 3 and all(p.HasAPI("DriveEnvelopeClampingAPI") for p in prims)
        replicate(sim.get_clone_plan())
        sim.reset()
        assert robot.joint_names == ["railCartJoint", "cartPoleJoint", "polePoleJoint"]
        stages = [type(c) for act in NewtonManager.get_model().actuators for c in (act.clamping or [])]
        assert any(issubclass(s, ClampingPerformanceEnvelope) for s in stages), stages
        robot.actuators.target_command.set_position_index(value=torch.full((NUM_ENVS, 3), 1.0))
        saturated = 0
        for _ in range(STEPS):
            start = robot.data.joint_vel.torch.clone()
            robot.write_data_to_sim()
            sim.step()
            robot.update(DT)
            computed = robot.actuators.computed_effort.torch.numpy().astype(np.float64)
            applied = robot.actuators.applied_effort.torch.numpy().astype(np.float64)
            reference = de.clamp_effort(envelope, computed, start.numpy().astype(np.float64))
            np.testing.assert_allclose(applied, reference, rtol=1e-5, atol=1e-4)
            saturated += int((np.abs(computed) > np.abs(applied) + 1e-3).sum())
        assert saturated > 0  # the envelope bound, so the check above is not vacuous
        moved = robot.data.joint_pos.torch
        assert bool(torch.isfinite(moved).all()) and float(moved[:, 0].abs().max()) > 0.05


@pytest.mark.skipif(not CARTPOLE.is_file(), reason=f"needs {CARTPOLE} (Newton's example assets)")
def test_envelope_clamping_needs_newton_actuators() -> None:
    """With use_newton_actuators=False Isaac Lab authors no NewtonActuator prims: one-line InputError."""
    import isaaclab.sim as sim_utils
    from isaaclab.actuators import IdealPDActuatorCfg
    from isaaclab.sim import build_simulation_context
    from isaaclab_newton.assets import Articulation

    from drive_envelope import InputError

    cfg = IdealPDActuatorCfg(joint_names_expr=[".*"], stiffness=50.0, damping=2.0)
    with build_simulation_context(
        device="cpu", gravity_enabled=True, add_ground_plane=False, sim_cfg=_newton_sim_cfg(False)
    ) as sim:
        sim._app_control_on_stop_handle = None
        sim_utils.create_prim("/World/Env_0", "Xform")
        spawn = sim_utils.UsdFileCfg(usd_path=str(CARTPOLE))
        off = PerformanceEnvelopeArticulationCfg(
            prim_path="/World/Env_0/Robot",
            spawn=spawn,
            actuators={"all": cfg},
            envelope_clamping={"all": ENVELOPE},
        )
        with pytest.raises(
            InputError, match=r"envelope_clamping: needs SimulationCfg\(use_newton_actuators=True\)"
        ):
            Articulation(off)
        typo = off.replace(prim_path="/World/Env_1/Robot", envelope_clamping={"legs": ENVELOPE})
        with pytest.raises(
            InputError, match=r"group 'legs' is not a key of actuators \(expected one of \['all'\]\)"
        ):
            Articulation(typo)

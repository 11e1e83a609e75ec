"""MJWarp reads the model's ``set_solver`` setting and runs PhysX's PGS / TGS iteration as the C plugin does.

The reference is the C plugin (float64, itself held to real PhysX on this arm in
tests/test_mujoco_solver.py): from the same state every step, MJWarp's float32 step must give the
plugin's velocities within float32 noise (``1e-5 + 5e-5*max|v|``). Positions are compared nowhere:
MJWarp integrates them with the end-of-step velocity, the plugin as PhysX does.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import PerformanceEnvelope
from test_mujoco_solver import _ARM, _box

pytestmark = [pytest.mark.mujoco, pytest.mark.warp]


@pytest.fixture(scope="module")
def env() -> Any:
    mujoco = mujoco_with_plugin()
    mjw = pytest.importorskip("mujoco_warp")
    import warp as wp

    wp.config.quiet = True  # type: ignore[attr-defined]
    return mujoco, mjw


def _arm(mujoco: Any) -> Any:
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec()
    spec.option.timestep = 1 / 240
    spec.option.gravity = [0.0, 0.0, -9.81]
    parent = spec.worldbody
    for index, (name, mass, *_rest) in enumerate(_ARM):
        body = parent.add_body(
            name=f"{name}_link", pos=[0.4 if index else 0.0, 0.0, 0.0], explicitinertial=True
        )
        body.mass, body.ipos, body.inertia = mass, [0.2, 0.0, 0.0], list(_box(mass))
        body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 1.0, 0.0])
        parent = body
    for name, _mass, max_effort, vmax, stiffness, damping, _target in _ARM:
        envelope = PerformanceEnvelope(max_effort=max_effort, max_actuator_velocity=vmax)
        add_drive(spec, name, envelope=envelope, stiffness=stiffness, damping=damping)
    return spec


def _worst(env: Any, spec: Any, steps: int = 120, switch: tuple[Any, int, int] | None = None) -> float:
    """Largest velocity difference of one MJWarp step from the plugin's state, over a run."""
    from drive_envelope.mjwarp import envelope_drives, put_model
    from drive_envelope.mujoco import set_solver

    mujoco, mjw = env
    mjm = spec.compile()
    mjd = mujoco.MjData(mjm)
    m = put_model(spec)
    d = mjw.make_data(mjm, nworld=1)
    targets = np.array([row[6] for row in _ARM])
    mjd.ctrl[:] = targets
    d.ctrl.assign(targets[None].astype(np.float32))
    worst, peak = 0.0, 0.0
    for step in range(steps):
        if switch is not None and step == steps // 2:
            solver, position, velocity = switch
            set_solver(mjm, solver, position_iterations=position, velocity_iterations=velocity)
            set_solver(
                envelope_drives(m).mj_model,
                solver,
                position_iterations=position,
                velocity_iterations=velocity,
            )
        d.qpos.assign(mjd.qpos[None].astype(np.float32))
        d.qvel.assign(mjd.qvel[None].astype(np.float32))
        mujoco.mj_step(mjm, mjd)
        mjw.step(m, d)
        worst = max(worst, float(np.abs(d.qvel.numpy()[0] - mjd.qvel).max()))
        peak = max(peak, float(np.abs(mjd.qvel).max()))
    return worst / (1e-5 + 5e-5 * peak)


@pytest.mark.parametrize(("solver", "position", "velocity"), [("pgs", 1, 0), ("tgs", 4, 1), ("tgs", 2, 0)])
def test_mjwarp_steps_the_arm_as_the_plugin(env: Any, solver: Any, position: int, velocity: int) -> None:
    from drive_envelope.mujoco import set_solver

    spec = _arm(env[0])
    set_solver(spec, solver, position_iterations=position, velocity_iterations=velocity)
    assert _worst(env, spec) <= 1.0


def test_the_host_models_setting_is_read_at_every_step(env: Any) -> None:
    from drive_envelope.mujoco import set_solver

    spec = _arm(env[0])
    set_solver(spec, "exact")
    assert _worst(env, spec, switch=("tgs", 4, 1)) <= 1.0

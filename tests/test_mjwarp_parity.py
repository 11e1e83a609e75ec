"""MJWarp on Warp's CPU device against C MuJoCo with the plugin: the same drives, step by step.

The reference is the C plugin (float64) stepping the same MJCF; MJWarp integrates in float32, so
velocities agree within float32 noise, ``1e-5 + 5e-5*max|v|`` (the issue's bound). On the fixed-base
Menagerie Go2 driven into saturation the check is independent of both solvers: after each step
every drive is inside its envelope at the velocity MJWarp integrated (or released above its
no-load speed), and where strictly inside the implicit PD law holds.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import PerformanceEnvelope
from drive_envelope.mujoco import solver_stats

pytestmark = [pytest.mark.mujoco, pytest.mark.warp]

GO2 = Path(__file__).resolve().parents[2] / "shared" / "data" / "menagerie" / "go2.xml"

HINGE = """<mujoco><option timestep="0.01" integrator="Euler"/>
<extension><plugin plugin="drive_envelope.envelope"/></extension>
<worldbody><body><joint name="j" axis="0 1 0" damping="0.2"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="0.5"/></body></worldbody>
<actuator><plugin name="a" joint="j" plugin="drive_envelope.envelope" dynprm="2 6 0.05 0.3 60 1"/></actuator>
</mujoco>"""

# a pos/vel/ff drive whose inputs are delayed, next to a motor whose force the drive sees coming
INPUTS = """<mujoco><option timestep="0.005" integrator="Euler"/>
<extension><plugin plugin="drive_envelope.envelope">
<instance name="pvf"><config key="input" value="pos vel ff"/></instance></plugin></extension>
<worldbody><body><joint name="j" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="0.5"/>
<body pos="0.3 0 0"><joint name="k" axis="0 1 0" damping="0.05"/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.2"/></body></body></worldbody>
<actuator><plugin name="a" joint="j" instance="pvf" dynprm="3 8 0 0.2 40 1" delay="0.02" nsample="8"/>
<plugin name="a_vel" joint="j" instance="pvf" delay="0.02" nsample="8"/>
<plugin name="a_ff" joint="j" instance="pvf" delay="0.02" nsample="8"/>
<motor name="m" joint="k" gear="1"/></actuator></mujoco>"""


@pytest.fixture(scope="module")
def env() -> Any:
    """(mujoco, mujoco_warp) with the plugin loaded and Warp quiet."""
    mujoco = mujoco_with_plugin()
    mjw = pytest.importorskip("mujoco_warp")
    import warp as wp

    wp.config.quiet = True
    return mujoco, mjw


def _pair(env: Any, spec: Any, nworld: int = 1) -> tuple[Any, Any, Any, Any, Any]:
    """(C model, C data, MJWarp model, MJWarp data, stats) of one spec."""
    from drive_envelope.mjwarp import envelope_drives, put_model

    mujoco, mjw = env
    mjm = spec.compile()
    m = put_model(spec)
    return mjm, mujoco.MjData(mjm), m, mjw.make_data(mjm, nworld=nworld), envelope_drives(m).track(nworld)


def test_one_hinge_matches_c_mujoco_every_step(env: Any) -> None:
    """Match the C plugin's velocity and effort every step on one damped hinge, saturating or not."""
    mujoco, mjw = env
    mjm, mjd, m, d, stats = _pair(env, mujoco.MjSpec.from_string(HINGE))
    velocity, reference, iterations = [], [], []
    for step in range(300):
        target = 1.5 * np.sin(3 * mjd.time) + (2.0 if step > 100 else 0.0)  # a jump into saturation
        mjd.ctrl[0] = target
        d.ctrl.assign(np.array([[target]], dtype=np.float32))
        mujoco.mj_step(mjm, mjd)
        mjw.step(m, d)
        velocity.append(d.qvel.numpy()[0, 0])
        reference.append(mjd.qvel[0])
        iterations.append((int(stats.numpy()[0, 0]), solver_stats(mjm, mjd).iterations))
        assert d.actuator_force.numpy()[0, 0] == pytest.approx(mjd.actuator_force[0], abs=1e-4)
    velocity, reference = np.array(velocity), np.array(reference)
    assert np.abs(velocity - reference).max() <= 1e-5 + 5e-5 * np.abs(reference).max()
    assert any(c > 0 for _, c in iterations)  # saturated: the solve iterated
    assert all(w == c for w, c in iterations)  # and took the plugin's iterations


def test_delayed_inputs_and_other_actuators_match_c_mujoco(env: Any) -> None:
    """Read delayed pos/vel/ff controls from MJWarp's history and see a motor's force coming, as C does."""
    mujoco, mjw = env
    mjm, mjd, m, d, _ = _pair(env, mujoco.MjSpec.from_string(INPUTS))
    worst, peak = 0.0, 0.0
    for step in range(200):
        t = step * mjm.opt.timestep
        ctrl = np.array(
            [0.8 * np.sign(np.sin(6 * t)), 2.0 * np.cos(6 * t), 0.5 * np.sin(11 * t), 0.3 * np.sin(5 * t)]
        )
        mjd.ctrl[:] = ctrl
        d.ctrl.assign(ctrl[None].astype(np.float32))
        mujoco.mj_step(mjm, mjd)
        mjw.step(m, d)
        worst = max(worst, float(np.abs(d.qvel.numpy()[0] - mjd.qvel).max()))
        peak = max(peak, float(np.abs(mjd.qvel).max()))
    assert worst <= 1e-5 + 5e-5 * peak


def test_plugin_free_attach_gives_the_same_steps(env: Any) -> None:
    """Drive a plugin-free model's motor with attach exactly as put_model drives the plugin's actuator."""
    mujoco, mjw = env
    from drive_envelope.mjwarp import attach

    spec = mujoco.MjSpec.from_string(HINGE)
    _, _, m, d, _ = _pair(env, spec)
    plain = HINGE.replace('<extension><plugin plugin="drive_envelope.envelope"/></extension>', "")
    plain = plain.replace(
        '<plugin name="a" joint="j" plugin="drive_envelope.envelope"', '<motor name="a" joint="j"'
    )
    free = mujoco.MjSpec.from_string(plain.replace(' dynprm="2 6 0.05 0.3 60 1"', ""))
    free.actuators[0].dynprm[:6] = [2, 6, 0.05, 0.3, 60, 1]
    mjm = free.compile()
    m2, d2 = mjw.put_model(mjm), mjw.make_data(mjm, nworld=1)
    attach(m2, mjm, ["a"])
    for step in range(120):
        target = np.array([[np.sin(0.05 * step) + (2.0 if step > 60 else 0.0)]], dtype=np.float32)
        d.ctrl.assign(target)
        d2.ctrl.assign(target)
        mjw.step(m, d)
        mjw.step(m2, d2)
        np.testing.assert_array_equal(d.qvel.numpy(), d2.qvel.numpy())


@pytest.fixture(scope="module")
def go2(env: Any) -> tuple[Any, list[str], list[PerformanceEnvelope]]:
    """The Menagerie Go2 without its free joint and contacts, one drive per hinge (kp 300, kv 3)."""
    if not GO2.is_file():
        pytest.skip(f"needs the Menagerie Go2 at {GO2} (../shared/data, not part of a user's clone)")
    mujoco, _ = env
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec.from_file(str(GO2))
    for joint in list(spec.body("base").joints):
        spec.delete(joint)
    for key in list(spec.keys):
        spec.delete(key)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(
        mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS | mujoco.mjtDisableBit.mjDSBL_LIMIT
    )
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    joints = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    hip = PerformanceEnvelope(max_effort=23.7, max_actuator_velocity=30.1, speed_effort_gradient=0.5)
    knee = PerformanceEnvelope(
        max_effort=35.55, max_actuator_velocity=20.07, velocity_dependent_resistance=0.1
    )
    envelopes = [knee if "calf" in j else hip for j in joints]
    for joint, envelope in zip(joints, envelopes, strict=True):
        add_drive(spec, joint, envelope=envelope, stiffness=300, damping=3, replace=True, effort_sensor=False)
    return spec, joints, envelopes


def test_menagerie_go2_fixed_base_stays_inside_in_mjwarp(env: Any, go2: Any) -> None:
    """Keep the squatting Go2 inside its envelopes in MJWarp (<= 0.1 % outside), PD law and C MuJoCo kept."""
    mujoco, mjw = env
    spec, joints, envelopes = go2
    nworld = 2
    mjm, mjd, m, d, stats = _pair(env, spec, nworld)
    ids = [mjm.joint(j).id for j in joints]
    dof, qadr = mjm.jnt_dofadr[ids], mjm.jnt_qposadr[ids]
    actuators = [int(np.flatnonzero(mjm.actuator_trnid[:, 0] == j)[0]) for j in ids]
    home = np.array([0.0, 0.9, -1.8] * 4)
    qpos = np.tile(mjm.qpos0, (nworld, 1))
    qpos[:, qadr] = home
    d.qpos.assign(qpos.astype(np.float32))
    mjd.qpos[qadr] = home
    h = mjm.opt.timestep
    samples = outside = boundary = 0
    law_error, parity, peak, most = 0.0, 0.0, 0.0, 0
    for step in range(600):
        ramp = min(step * h / 0.2, 1.0)
        t = step * h
        target = home + ramp * np.tile(
            [0.4 * np.sin(9 * t), 0.8 * np.sin(14 * t), 0.9 * np.sin(14 * t + 1)], 4
        )
        ctrl = np.zeros((nworld, mjm.nu), dtype=np.float32)
        ctrl[:, mjm.actuator_ctrladr[actuators]] = target
        q0 = d.qpos.numpy()[:, qadr].astype(np.float64)
        d.ctrl.assign(ctrl)
        mjd.ctrl[mjm.actuator_ctrladr[actuators]] = target
        mjw.step(m, d)
        mujoco.mj_step(mjm, mjd)
        v1 = d.qvel.numpy()[:, dof].astype(np.float64)
        tau = d.actuator_force.numpy()[:, actuators].astype(np.float64)
        parity = max(parity, float(np.abs(v1[0] - mjd.qvel[dof]).max()))
        peak = max(peak, float(np.abs(mjd.qvel[dof]).max()))
        most = max(most, int(stats.numpy()[:, 0].max()))
        law = 300 * (target - q0 - h * v1) - 3 * v1
        for w in range(nworld):
            for i, envelope in enumerate(envelopes):
                effort_margin, velocity_margin = envelope.margins(v1[w, i], tau[w, i])
                relative = min(
                    effort_margin / envelope.max_effort, velocity_margin / envelope.max_actuator_velocity
                )
                samples += 1
                if relative < -1e-6:
                    outside += 1
                elif relative > 1e-6:
                    law_error = max(law_error, abs(law[w, i] - tau[w, i]) / envelope.max_effort)
                else:
                    boundary += 1
    assert outside <= 0.001 * samples
    assert boundary > 0.02 * samples  # saturation reached: the coupling matters
    assert law_error < 1e-4  # float32 state: the law holds to float32 noise
    assert parity <= 1e-5 + 5e-5 * peak
    assert most <= 4

"""The coupled solve: every drive of a model at once, consistent with MuJoCo's actual step.

Without constraints (no contacts, no joint limits) MuJoCo's end-of-step velocity is exactly the one
the plugin predicts, so after each ``mj_step`` every drive must satisfy, at the velocity MuJoCo
actually integrated (an independent check from the spec, not a copy of the solver):

* inside the envelope (relative margin >= -1e-6), or released (zero effort above the no-load speed);
* strictly inside: PhysX's implicit PD law ``tau - ff = k*(q* - q0 - h*v1) + c*(v* - v1)``;
* on the boundary: the law asks for at least as much effort, with the same sign (a clamp).

The old plugin predicted each DOF alone (9.6 % of a Go2's squat samples outside); these models are
driven into saturation so that the coupling matters.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import PerformanceEnvelope
from drive_envelope.mujoco import solver_stats

pytestmark = pytest.mark.mujoco

ROOT = Path(__file__).resolve().parents[1]
GO2 = ROOT.parent / "shared" / "data" / "menagerie" / "go2.xml"


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


@pytest.fixture(scope="module")
def quadruped() -> Any:
    sys.path.insert(0, str(ROOT / "examples" / "mujoco"))
    try:
        import quadruped as module
    finally:
        sys.path.pop(0)
    return module


def _squat(time: float, home: np.ndarray) -> np.ndarray:
    """Fast squats of every leg, beyond what the motors can follow."""
    ramp = min(time / 0.2, 1.0)
    wave = np.array([0.4 * np.sin(9 * time), 0.8 * np.sin(14 * time), 0.9 * np.sin(14 * time + 1)])
    return home + ramp * np.tile(wave, 4)


def _run(
    mujoco: Any,
    model: Any,
    joints: list[str],
    envelopes: list[PerformanceEnvelope],
    home: np.ndarray,
    steps: int,
    targets: Callable[[float], np.ndarray] | None = None,
) -> dict[str, Any]:
    """Step the squats (or ``targets(time)``); check every drive after every step (module docstring).

    A drive at zero effort below its cap whose law asks for some counts as ``let_go``: PhysX's clamp
    jumps from full braking to 0 where braking cannot bring the joint back under its cap in one step,
    and a drive the others push back and forth across that jump twice lets go for the rest of the
    solve (no consistent effort need exist), even where the step then ends below its cap.
    """
    from drive_envelope.mujoco import get_gains

    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
    dof, qadr = model.jnt_dofadr[ids], model.jnt_qposadr[ids]
    actuators = [int(np.flatnonzero(model.actuator_trnid[:, 0] == j)[0]) for j in ids]
    gains = np.array([get_gains(model, a) for a in actuators])
    data = mujoco.MjData(model)
    data.qpos[qadr] = home
    h = model.opt.timestep
    samples = outside = released = boundary = let_go = 0
    law_error, sweeps = 0.0, []
    bounds = model.actuator_ctrlrange[actuators]
    limited = model.actuator_ctrllimited[actuators].astype(bool)
    for _ in range(steps):
        target = _squat(data.time, home) if targets is None else targets(data.time)
        target = np.where(
            limited, np.clip(target, bounds[:, 0], bounds[:, 1]), target
        )  # as the drives read it
        data.ctrl[model.actuator_ctrladr[actuators]] = target
        q0 = data.qpos[qadr].copy()
        mujoco.mj_step(model, data)
        sweeps.append(solver_stats(model, data).iterations)
        v1, tau = data.qvel[dof], data.actuator_force[actuators]
        law = gains[:, 0] * (target - q0 - h * v1) - gains[:, 1] * v1
        for i, env in enumerate(envelopes):
            effort_margin, velocity_margin = env.margins(v1[i], tau[i])
            relative = min(effort_margin / env.max_effort, velocity_margin / env.max_actuator_velocity)
            samples += 1
            if tau[i] == 0.0 and abs(v1[i]) > env.no_load_velocity():
                released += 1
            elif tau[i] == 0.0 and law[i] != 0.0:
                let_go += 1
            elif relative < -1e-6:
                outside += 1
            elif relative > 1e-6:
                law_error = max(law_error, abs(law[i] - tau[i]) / env.max_effort)
            else:
                boundary += 1
                assert np.sign(law[i]) == np.sign(tau[i]) and abs(law[i]) >= abs(tau[i]) * (1 - 1e-9)
    return {
        "samples": samples,
        "outside": outside,
        "released": released,
        "let_go": let_go,
        "boundary": boundary / samples,
        "law_error": law_error,
        "sweeps": max(sweeps),
    }


def _quadruped_model(mujoco: Any, quadruped: Any, integrator: str, damping: float) -> tuple[Any, list[str]]:
    """The example quadruped, torso welded, no joint limits, stiff drives (400 N*m/rad, 4 N*m*s/rad)."""
    from drive_envelope.mujoco import set_gains

    spec = quadruped.build_quadruped("plugin", fixed_base=True)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    for joint in spec.joints:
        joint.damping = [damping, 0.0, 0.0]
    model = spec.compile()
    for actuator in range(model.nu):
        set_gains(model, actuator, stiffness=400.0, damping=4.0)
    names = [f"{leg}_{j}" for leg in quadruped.LEGS for j in quadruped.JOINTS]
    return model, names


@pytest.mark.parametrize(("integrator", "damping"), [("euler", 0.0), ("euler", 0.5), ("implicitfast", 0.5)])
def test_every_drive_is_consistent_with_the_step_mujoco_takes(
    mujoco: Any, quadruped: Any, integrator: str, damping: float
) -> None:
    """Keep a fixed-base 12-DOF quadruped driven into saturation inside its envelopes, PD law exact."""
    model, joints = _quadruped_model(mujoco, quadruped, integrator, damping)
    limits = quadruped.envelopes()
    home = np.array([quadruped.STAND[j] for j in quadruped.JOINTS] * 4)
    result = _run(mujoco, model, joints, [limits[j] for j in joints], home, 600)
    assert result["outside"] == 0 and result["let_go"] == 0
    assert result["boundary"] > 0.03  # saturation reached: the coupling matters
    assert result["law_error"] < 1e-8
    assert result["sweeps"] <= 4  # Newton settles the coupled drives in a few steps


def test_implicit_integrator_is_close_but_not_exact(mujoco: Any, quadruped: Any) -> None:
    """Stay inside with the full implicit integrator, whose RNE derivatives the plugin does not model."""
    model, joints = _quadruped_model(mujoco, quadruped, "implicit", 0.5)
    limits = quadruped.envelopes()
    home = np.array([quadruped.STAND[j] for j in quadruped.JOINTS] * 4)
    result = _run(mujoco, model, joints, [limits[j] for j in joints], home, 600)
    assert result["outside"] <= 0.001 * result["samples"]
    assert 1e-8 < result["law_error"] < 0.2  # the end-of-step velocity is not the one predicted


def test_menagerie_go2_fixed_base_stays_inside(mujoco: Any) -> None:
    """Keep the Menagerie Go2 (free joint removed, no contacts) inside its envelopes under squats."""
    if not GO2.is_file():
        pytest.skip(f"needs the Menagerie Go2 at {GO2} (../shared/data, not part of a user's clone)")
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec.from_file(str(GO2))
    for joint in list(spec.body("base").joints):
        spec.delete(joint)
    for key in list(spec.keys):
        spec.delete(key)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(
        mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS | mujoco.mjtDisableBit.mjDSBL_LIMIT
    )
    joints = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    hip = PerformanceEnvelope(max_effort=23.7, max_actuator_velocity=30.1, speed_effort_gradient=0.5)
    knee = PerformanceEnvelope(
        max_effort=35.55, max_actuator_velocity=20.07, velocity_dependent_resistance=0.1
    )
    envelopes = [knee if "calf" in j else hip for j in joints]
    for joint, env in zip(joints, envelopes, strict=True):
        add_drive(spec, joint, envelope=env, stiffness=300, damping=3, replace=True, effort_sensor=False)
    result = _run(mujoco, spec.compile(), joints, envelopes, np.array([0.0, 0.9, -1.8] * 4), 1000)
    assert (
        result["outside"] == 0 and result["let_go"] == 0
    )  # the Go2 keeps its joint damping 2 and armature 0.01
    assert result["boundary"] > 0.02
    assert result["law_error"] < 1e-8


def test_a_single_drive_needs_no_iteration_until_it_saturates(mujoco: Any) -> None:
    """Solve one unsaturated drive exactly by the linear solve (0 iterations), a saturated one in two."""
    xml = (
        '<mujoco><option timestep="0.01" gravity="0 0 0"/>'
        '<extension><plugin plugin="drive_envelope.envelope"/>'
        '</extension><worldbody><body><joint name="j" axis="0 0 1"/>'
        '<inertial pos="0 0 0" mass="1" diaginertia="0.5 0.5 0.5"/></body></worldbody>'
        '<actuator><plugin joint="j" plugin="drive_envelope.envelope" dynprm="5 2 0 0 100 5"/>'
        "</actuator></mujoco>"
    )  # fmt: skip
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.ctrl[0] = 0.01
    mujoco.mj_step(model, data)
    assert solver_stats(model, data).iterations == 0
    # the implicit PD law, solved by hand: tau = (k*e - (k*h + c)*v0) / (1 + (h*k + c)*h/I)
    k, c, h, inertia = 100.0, 5.0, 0.01, 0.5
    assert data.actuator_force[0] == pytest.approx(k * 0.01 / (1 + (h * k + c) * h / inertia), rel=1e-12)
    data.ctrl[0] = 10.0
    mujoco.mj_step(model, data)
    assert solver_stats(model, data).iterations == 2 and data.actuator_force[0] == pytest.approx(5.0)


def test_menagerie_panda_with_stiff_gains_converges_and_stays_inside(mujoco: Any) -> None:
    """Solve the Panda's 7 stiff drives (kp 4500, kv 450, armature 0.1) without hitting the iteration cap."""
    panda = GO2.parent / "panda.xml"
    if not panda.is_file():
        pytest.skip(f"needs the Menagerie Panda at {panda} (../shared/data, not part of a user's clone)")
    from drive_envelope._src.adapters.mujoco.mjcf import Assignment, apply_drives, load_spec

    spec = load_spec(panda)
    limits = {
        f"joint{i}": PerformanceEnvelope(
            max_effort=87.0 if i <= 4 else 12.0, max_actuator_velocity=2.175 if i <= 4 else 2.61
        )
        for i in range(1, 8)
    }
    apply_drives(spec, [Assignment(joint=j, envelope=e) for j, e in limits.items()])
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)  # no joint limits, no contacts
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in limits]
    dof, qadr = model.jnt_dofadr[ids], model.jnt_qposadr[ids]
    home, iterations, outside, released, zero_inside = data.qpos[qadr].copy(), [], 0, 0, 0
    for _ in range(1500):
        data.ctrl[:7] = home + 0.6 * np.sin(6 * data.time + np.arange(7))
        mujoco.mj_step(model, data)
        iterations.append(solver_stats(model, data).iterations)
        for i, env in enumerate(limits.values()):
            velocity, effort = data.qvel[dof[i]], data.actuator_force[i]
            effort_margin, velocity_margin = env.margins(velocity, effort)
            if effort == 0.0 and abs(velocity) > env.max_actuator_velocity:
                released += 1  # the coupled arm pushed it past its speed: it let go, as PhysX's does
            elif effort == 0.0 and abs(velocity) < 0.99 * env.max_actuator_velocity:
                zero_inside += 1  # held let go where its own solve would not: Gauss-Seidel cycled
            elif min(effort_margin / env.max_effort, velocity_margin / env.max_actuator_velocity) < -1e-6:
                outside += 1
    assert outside == 0
    # every joint swings at its speed limit: drives that their neighbours push past it let go
    assert 0 < released < 0.5 * 1500 * 7
    # the sweeps that check a drive Newton held let go (it switched twice) reach their cap of 50
    # only where Gauss-Seidel neither settles nor cycles (6 of 1500 steps); Newton's answer stays
    assert sum(i >= 50 for i in iterations) <= 0.005 * len(iterations)
    assert np.mean(iterations) < 10
    assert zero_inside <= 0.001 * 1500 * 7  # 8 samples; 15 when Newton's holds went unchecked


def test_menagerie_panda_stepped_to_its_range_edges_keeps_driving_below_its_caps(mujoco: Any) -> None:
    """No drive at zero effort below 99 % of its speed cap when every target jumps to a range edge.

    A new user's run: the Panda held at ``home`` for 2 s, then each target to an end of its control
    range (kp 4500 against 87 N*m caps). Joints 1 and 3 (then 7) pushed each other across the
    clamp's jump; Newton held them let go, at 0 for 13 steps at 1.74-1.78 rad/s of 2.175 (34 such
    samples), where PhysX's Gauss-Seidel drives them at 87 N*m up to the cap. Gauss-Seidel now
    checks each held drive; PGS 4/1 on the same steps gives no such sample either.
    """
    panda = GO2.parent / "panda.xml"
    if not panda.is_file():
        pytest.skip(f"needs the Menagerie Panda at {panda} (../shared/data, not part of a user's clone)")
    from drive_envelope._src.adapters.mujoco.mjcf import Assignment, apply_drives, load_spec

    spec = load_spec(panda)
    limits = [
        PerformanceEnvelope(
            max_effort=87.0 if i <= 4 else 12.0, max_actuator_velocity=2.175 if i <= 4 else 2.61
        )
        for i in range(1, 8)
    ]
    apply_drives(spec, [Assignment(joint=f"joint{i + 1}", envelope=e) for i, e in enumerate(limits)])
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    dof = model.jnt_dofadr[
        [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"joint{i}") for i in range(1, 8)]
    ]
    for _ in range(1000):
        mujoco.mj_step(model, data)
    edges = model.actuator_ctrlrange[:7]
    data.ctrl[:7] = np.where(np.arange(7) % 2 == 0, edges[:, 1], edges[:, 0])
    driven = released = 0
    for _ in range(60):
        mujoco.mj_step(model, data)
        for i, env in enumerate(limits):
            velocity, effort = data.qvel[dof[i]], data.actuator_force[i]
            assert effort != 0.0 or abs(velocity) >= 0.99 * env.max_actuator_velocity, (i, velocity)
            driven += effort != 0.0
            released += effort == 0.0
    assert driven > 0 and released > 0  # both happen: joints 1, 3 and 4 pass their caps and let go


@pytest.mark.parametrize("amplitude", [0.25, 1.2])
def test_menagerie_g1_floating_saturated_drives_keep_the_law(mujoco: Any, amplitude: float) -> None:
    """Keep the G1's 29 map drives (speed caps without a slope) exact on its floating base, no contacts.

    The G1 exercises the tree path of the Newton steps on a free base: a small amplitude saturates a
    few rows (an update of the linear guess's factor), a large one many (a new factor), and rows
    pinned at a speed cap with no gradient (the dense step).
    """
    g1 = GO2.parent / "unitree_g1" / "scene.xml"
    if not g1.is_file():
        pytest.skip(f"needs the Menagerie G1 at {g1} (../shared/data, not part of a user's clone)")
    from drive_envelope._src.adapters.mujoco.mjcf import Assignment, apply_drives, driven_joints, load_spec
    from drive_envelope._src.adapters.usd.joint_map import match_joints, read_map, resolve_envelopes
    from drive_envelope._src.datasheet.maps import robot_map_path

    spec = load_spec(g1)
    match = match_joints(read_map(str(robot_map_path("unitree-g1"))), driven_joints(spec))
    items = [
        Assignment(joint=i.joint, envelope=i.envelope, where=i.entry.where)
        for i in resolve_envelopes(match)
        if i.envelope is not None
    ]
    apply_drives(spec, items)
    for key in list(spec.keys):
        spec.delete(key)
    # no constraints (contacts, limits, friction loss): MuJoCo's end-of-step velocity is the solve's
    spec.option.disableflags |= int(
        mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    )
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    model = spec.compile()
    joints = [item.joint for item in items]
    envelopes = [item.envelope for item in items]
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
    assert len(ids) == 29 and all(e.speed_effort_gradient == 0 for e in envelopes)
    from drive_envelope.mujoco import set_gains

    for actuator in range(model.nu):
        set_gains(model, actuator, stiffness=100.0, damping=2.0)
    waves = np.arange(29)
    home = np.zeros(29)
    result = _run(mujoco, model, joints, envelopes, home, 800, lambda t: amplitude * np.sin(15 * t + waves))
    assert result["outside"] == 0
    assert result["boundary"] > 0.01  # saturated: the Newton steps ran
    assert result["law_error"] < 1e-8
    assert result["let_go"] <= 0.001 * result["samples"]  # 3 of 23,200 samples
    assert result["sweeps"] < 8 + 50

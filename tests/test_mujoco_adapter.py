"""``drive_envelope.mujoco``: adding drives to an ``MjSpec``, reading operating points, rollouts."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import numpy as np
import pytest

from drive_envelope import InputError, PerformanceEnvelope

pytestmark = pytest.mark.mujoco

ARM = """<mujoco><option timestep="0.005" integrator="Euler"/><worldbody>
<body pos="0 0 1"><joint name="shoulder" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>
<body pos="0.4 0 0"><joint name="elbow" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="slider" type="slide" axis="1 0 0"/><geom type="sphere" size="0.05"/>
<body><joint name="ball" type="ball"/><geom type="sphere" size="0.02" pos="0.1 0 0"/></body>
</body></body></body></worldbody></mujoco>"""


@pytest.fixture(scope="module")
def mujoco() -> Any:
    module = pytest.importorskip("mujoco")
    from drive_envelope._src.adapters.mujoco import build, loader

    try:
        loader.load_plugin()
    except build.PluginError:
        build.build_plugin(quiet=True)  # `make setup` normally built it
        loader.load_plugin()
    return module


def _env(**kwargs: Any) -> PerformanceEnvelope:
    return PerformanceEnvelope(**{"max_effort": 8.0, "max_actuator_velocity": 4.0, **kwargs})


def test_add_drive_builds_a_model_that_round_trips_through_mjcf(mujoco: Any) -> None:
    """Add drives from an envelope and a catalog datasheet; the saved MJCF compiles to the same model."""
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec.from_string(ARM)
    shoulder = add_drive(
        spec,
        "shoulder",
        envelope=_env(velocity_dependent_resistance=0.5),
        stiffness=80,
        damping="2 N*m*s/rad",
    )
    elbow = add_drive(
        spec, "elbow", datasheet="tmotor-ak80-6", stiffness="30 N*m/rad", damping=1.0, inputs="pos vel ff"
    )
    model = spec.compile()
    assert shoulder.actuators == ("shoulder",)
    assert elbow.actuators == ("elbow", "elbow_vel", "elbow_ff")
    assert elbow.envelope.max_effort == pytest.approx(12.0)
    assert model.nu == 4 and model.nplugin == 2 and model.nsensor == 2
    again = mujoco.MjModel.from_xml_string(spec.to_xml())
    assert again.nu == model.nu
    text = spec.to_xml()
    assert 'plugin="drive_envelope.envelope"' in text and 'key="input" value="pos vel ff"' in text


def test_add_drive_refuses_bad_joints_and_arguments(mujoco: Any) -> None:
    """Raise one-line InputErrors for an unknown or ball joint, a wrong envelope type or bad gains."""
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec.from_string(ARM)
    with pytest.raises(InputError, match="no joint named 'knee'"):
        add_drive(spec, "knee", envelope=_env(), stiffness=1, damping=1)
    with pytest.raises(InputError, match="is a ball joint; expected a hinge or slide"):
        add_drive(spec, "ball", envelope=_env(), stiffness=1, damping=1)
    with pytest.raises(InputError, match="envelope is for a revolute joint but 'slider' is prismatic"):
        add_drive(spec, "slider", envelope=_env(), stiffness=1, damping=1)
    with pytest.raises(InputError, match="argument 'stiffness'"):
        add_drive(spec, "shoulder", envelope=_env(), stiffness=-1, damping=1)
    with pytest.raises(InputError, match="argument 'damping'"):
        add_drive(spec, "shoulder", envelope=_env(), stiffness=1, damping="3 N*m")
    with pytest.raises(InputError, match="argument 'inputs'"):
        add_drive(spec, "shoulder", envelope=_env(), stiffness=1, damping=1, inputs=("pos", "torque"))
    with pytest.raises(InputError, match="exactly one of"):
        add_drive(spec, "shoulder", stiffness=1, damping=1)


def test_operating_points_stay_inside_the_envelope_or_let_go(mujoco: Any) -> None:
    """Keep (end-of-step velocity, effort) inside the envelope on a coupled arm, or let go."""
    from drive_envelope.mujoco import add_drive, drive_state

    spec = mujoco.MjSpec.from_string(ARM)
    env = _env(velocity_dependent_resistance=0.8, speed_effort_gradient=0.05)
    drive = add_drive(spec, "shoulder", envelope=env, stiffness=100, damping=5)
    spec.option.gravity = [0.0, 0.0, 0.0]
    model = spec.compile()
    data = mujoco.MjData(model)
    points = []
    for i in range(400):
        drive.set_targets(model, data, position=1.5 if i < 200 else -1.5)
        mujoco.mj_step(model, data)
        points.append(drive_state(model, data, drive))
    velocity, effort = np.array(points).T
    # the invariant: inside the envelope, or zero effort where the free links' coupling forces push
    # the joint past max_actuator_velocity while the drive asks for more (PhysX lets go then)
    inside = env.contains(velocity, effort, atol=1e-9)
    assert (inside | (effort == 0.0)).all()
    assert np.abs(effort).max() > 0.95 * env.max_effort / (1 + 0.8 * 0.005 * 10)  # limits reached
    assert np.abs(velocity).max() < 1.1 * env.max_actuator_velocity  # it coasts, never runs off


def test_rollout_threads_match_sequential_steps(mujoco: Any) -> None:
    """Give the same operating points from mujoco.rollout (threads) as from stepping by hand."""
    from mujoco import rollout

    from drive_envelope.mujoco import add_drive, drive_state, rollout_operating_points

    spec = mujoco.MjSpec.from_string(ARM)
    drive = add_drive(
        spec, "elbow", envelope=_env(velocity_dependent_resistance=0.5), stiffness=60, damping=1
    )
    model = spec.compile()
    data = mujoco.MjData(model)
    nstep, nbatch = 120, 3
    targets = np.linspace(-1.0, 1.5, nbatch)
    control = np.repeat(targets[:, None, None], nstep, axis=1)
    state0 = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    datas = [mujoco.MjData(model) for _ in range(2)]
    state, sensordata = rollout.rollout(model, datas, np.tile(state0, (nbatch, 1)), control)
    velocity, effort = rollout_operating_points(model, drive, state, sensordata)
    assert velocity.shape == (nbatch, nstep)
    for b, target in enumerate(targets):
        mujoco.mj_resetData(model, data)
        data.ctrl[0] = target
        for k in range(nstep):
            mujoco.mj_step(model, data)
            assert drive_state(model, data, drive) == (velocity[b, k], effort[b, k])


def test_public_module_imports_no_engine() -> None:
    """Import drive_envelope.mujoco without importing mujoco itself."""
    code = "import sys, drive_envelope.mujoco; print('mujoco' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"


def test_add_drives_shares_one_instance_and_matches_single_drives(mujoco: Any) -> None:
    """Step identically whether two joints share one plugin instance or have one each."""
    from drive_envelope.mujoco import add_drive, add_drives

    env = _env(velocity_dependent_resistance=0.5, speed_effort_gradient=0.05)
    shared_spec, single_spec = mujoco.MjSpec.from_string(ARM), mujoco.MjSpec.from_string(ARM)
    shared = add_drives(
        shared_spec, ["shoulder", "elbow"], envelope=env, stiffness=50, damping=1, inputs="pos vel"
    )
    for joint in ("shoulder", "elbow"):
        add_drive(single_spec, joint, envelope=env, stiffness=50, damping=1, inputs="pos vel")
    assert {d.instance for d in shared} == {"drives_shoulder"}
    runs = []
    for spec in (shared_spec, single_spec):
        model = spec.compile()
        data = mujoco.MjData(model)
        data.ctrl[:] = [1.0, 0.5, -0.8, 0.0]
        for _ in range(100):
            mujoco.mj_step(model, data)
        runs.append((model.nplugin, data.qpos.copy(), data.actuator_force.copy()))
    assert (runs[0][0], runs[1][0]) == (1, 2)
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    np.testing.assert_array_equal(runs[0][2], runs[1][2])


def test_quadruped_example_stays_inside_its_envelopes(mujoco: Any) -> None:
    """Run the shipped quadruped example briefly: every operating point inside (or let go)."""
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples" / "mujoco"))
    try:
        import quadruped
    finally:
        sys.path.pop(0)
    trajectories = quadruped.run(seconds=0.6)
    limits = quadruped.envelopes()
    assert len(trajectories) == 12
    for name, traj in trajectories.items():
        inside = limits[name].contains(traj.velocity, traj.effort, atol=1e-9) | (traj.effort == 0.0)
        assert inside.all(), name
    assert "inside" in quadruped.summary(trajectories)


def test_quadruped_efforts_match_dense_numpy_computation(mujoco: Any) -> None:
    """Reproduce all 12 efforts of the floating-base quadruped from the dense M^-1 and the core."""
    from pathlib import Path

    from drive_envelope import clamp_effort_implicit, implicit_drive_effort

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples" / "mujoco"))
    try:
        import quadruped
    finally:
        sys.path.pop(0)
    model = quadruped.build_quadruped("plugin").compile()
    data = mujoco.MjData(model)
    names = quadruped.joint_names()
    joints = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in names]
    data.qpos[model.jnt_qposadr[joints]] = quadruped.targets(0.0)
    for _ in range(300):  # walk into a loaded, moving state with foot contacts
        data.ctrl[:] = quadruped.targets(data.time)
        mujoco.mj_step(model, data)
    mujoco.mj_forward(model, data)
    dense = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, dense)
    inverse = np.linalg.inv(dense)
    acceleration = inverse @ (data.qfrc_passive - data.qfrc_bias + data.qfrc_applied)
    dt, limits = model.opt.timestep, quadruped.envelopes()
    for index, (name, joint) in enumerate(zip(names, joints, strict=True)):
        dof = model.jnt_dofadr[joint]
        r, v0 = inverse[dof, dof], data.qvel[dof] + dt * acceleration[dof]
        stiffness, damping = quadruped.GAINS[name.split("_", 1)[1]]
        error = data.ctrl[index] - data.qpos[model.jnt_qposadr[joint]]
        drive = implicit_drive_effort(
            stiffness=stiffness, damping=damping, position_error=error, velocity=v0,
            target_velocity=0.0, response=r, dt=dt,
        )  # fmt: skip
        expected = float(clamp_effort_implicit(limits[name], drive, v0, r, dt))
        assert data.actuator_force[index] == pytest.approx(expected, rel=1e-9, abs=1e-12), name


def test_wheel_ships_every_plugin_source() -> None:
    """List every C++ source of plugin/mujoco in the wheel's force-include and in PLUGIN_SOURCES."""
    from pathlib import Path

    from drive_envelope._src.adapters.mujoco.build import PLUGIN_SOURCES

    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    root = Path(__file__).resolve().parents[1]
    on_disk = {p.name for p in (root / "plugin" / "mujoco").iterdir() if p.suffix in (".cc", ".h")}
    on_disk.add("CMakeLists.txt")
    config = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))
    shipped = config["tool"]["hatch"]["build"]["targets"]["wheel"]["force-include"]
    assert set(PLUGIN_SOURCES) == on_disk
    assert shipped == {f"plugin/mujoco/{n}": f"drive_envelope/_plugin/mujoco/{n}" for n in PLUGIN_SOURCES}

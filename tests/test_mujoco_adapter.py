"""``drive_envelope.mujoco``: adding drives to an ``MjSpec``, reading operating points, rollouts."""

from __future__ import annotations

import re
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import TENDON_ARM, mujoco_with_plugin
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
    return mujoco_with_plugin()


def _env(**kwargs: Any) -> PerformanceEnvelope:
    return PerformanceEnvelope(**{"max_effort": 8.0, "max_actuator_velocity": 4.0, **kwargs})


def test_add_drive_builds_a_model_that_round_trips_through_mjcf(mujoco: Any, tmp_path: Path) -> None:
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
    # one instance per input set, shared by every drive with those inputs
    assert (shoulder.instance, elbow.instance) == ("drive_envelope_pos", "drive_envelope_pos_vel_ff")
    assert model.nu == 4 and model.nplugin == 2 and model.nsensor == 2
    # the numbers live in the effort actuator's dynprm: envelope, then gains (inf speed as -1)
    assert model.actuator_dynprm[0, :6].tolist() == [8.0, 4.0, 0.5, 0.0, 80.0, 2.0]
    assert model.actuator_dynprm[1, :2].tolist() == [12.0, elbow.envelope.max_actuator_velocity]
    text = spec.to_xml()
    again = mujoco.MjModel.from_xml_string(text)
    assert again.nu == model.nu
    np.testing.assert_allclose(
        again.actuator_dynprm, model.actuator_dynprm, rtol=1e-5
    )  # MuJoCo writes 6 digits
    assert 'plugin="drive_envelope.envelope"' in text and 'key="input" value="pos vel ff"' in text
    from drive_envelope.mujoco import write_mjcf

    exact = write_mjcf(spec, tmp_path / "arm.xml")  # every digit, and checked to load
    np.testing.assert_array_equal(exact.actuator_dynprm, model.actuator_dynprm)
    with pytest.raises(InputError, match=r"output '.*arm\.toml': expected an \.xml file name \(MJCF\)$"):
        write_mjcf(spec, tmp_path / "arm.toml")  # a map or envelope file name given by mistake
    assert not (tmp_path / "arm.toml").exists()


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
    with pytest.raises(InputError, match=r"argument 'stiffness': expected a number in \[0, 1e12\]"):
        add_drive(spec, "shoulder", envelope=_env(), stiffness=1e308, damping=1)
    with pytest.raises(InputError, match=r"max_effort = 1e\+20: expected a number in \[0, 1e12\]"):
        add_drive(spec, "shoulder", envelope=PerformanceEnvelope(max_effort=1e20), stiffness=1, damping=1)
    add_drive(spec, "shoulder", envelope=_env(), stiffness=1, damping=1)
    with pytest.raises(
        InputError, match=r"joint 'shoulder' already has actuator 'shoulder' \(drive\).*replace=True"
    ):
        add_drive(spec, "shoulder", envelope=_env(), stiffness=1, damping=1)


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


def test_rollout_outputs_of_another_layout_are_refused(mujoco: Any) -> None:
    """A state that is not mjSTATE_FULLPHYSICS, the two outputs swapped, or unequal nstep: one line each.

    Each was read at the wrong offsets before: an mjSTATE_PHYSICS state (no time) gave another
    slot as the velocity, a silently wrong number.
    """
    from mujoco import rollout

    from drive_envelope.mujoco import add_drive, rollout_operating_points

    spec = mujoco.MjSpec.from_string(ARM)
    drive = add_drive(spec, "elbow", envelope=_env(), stiffness=60, damping=1)
    model = spec.compile()
    data = mujoco.MjData(model)
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    nstate = mujoco.mj_stateSize(model, full)
    state0 = np.zeros(nstate)
    mujoco.mj_getState(model, data, state0, full)
    state, sensordata = rollout.rollout(model, data, state0[None], np.full((1, 20, 1), 1.0))
    velocity, _ = rollout_operating_points(model, drive, state, sensordata)
    assert velocity.shape == (1, 20)
    physics = state[..., 1:]  # the mjSTATE_PHYSICS layout: FULLPHYSICS without the time
    with pytest.raises(
        InputError,
        match=rf"argument 'state' has shape \(1, 20, {nstate - 1}\); expected \(\.\.\., nstep, {nstate}\)",
    ):
        rollout_operating_points(model, drive, physics, sensordata)
    with pytest.raises(InputError, match=r"argument 'state' has shape \(1, 20, 1\)"):
        rollout_operating_points(model, drive, sensordata, state)
    with pytest.raises(InputError, match=r"argument 'sensordata' has shape \(1, 20, 2\)"):
        rollout_operating_points(model, drive, state, np.zeros((1, 20, 2)))
    with pytest.raises(InputError, match=r"differ in their leading \(\.\.\., nstep\) shape"):
        rollout_operating_points(model, drive, state[:, :10], sensordata)


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
        add_drive(single_spec, joint, envelope=env, stiffness=50, damping=1, inputs="pos vel", instance=joint)
    assert {d.instance for d in shared} == {"drive_envelope_pos_vel"}
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
    checks = quadruped.checks(trajectories)
    assert len(trajectories) == 12
    assert sum(c.samples_outside for c in checks.values()) == 0
    summary = quadruped.summary(trajectories)
    assert "all joints: 0 of 3600 samples outside the envelope (0.000 %), 0 released" in summary


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


MOTORS = """<mujoco><compiler angle="radian"/><option timestep="0.005"/><worldbody>
<body pos="0 0 1"><joint name="hip" axis="0 1 0" range="-1 2"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="knee" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="toe" axis="0 1 0"/><geom type="sphere" size="0.03"/>
</body></body></body></worldbody>
<actuator><motor name="hip_motor" joint="hip" ctrlrange="-20 20"/>
<position name="knee_pos" joint="knee" kp="50" kv="2"/><motor name="knee_extra" joint="knee"/>
<velocity name="toe_vel" joint="toe" kv="3"/><motor name="other" joint="toe"/>
</actuator><keyframe><key name="k" qpos="0.5 -0.3 0.1" ctrl="7 -0.3 1 0.2 4"/></keyframe></mujoco>"""


def test_replace_converts_the_first_actuator_in_place_and_fixes_keyframes(mujoco: Any) -> None:
    """Keep the replaced actuator's name and ctrl slot, delete the others, rewrite keyframe controls."""
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec.from_string(MOTORS)
    hip = add_drive(spec, "hip", envelope=_env(), stiffness=30, damping=1, replace=True, effort_sensor=False)
    deleted = r"'knee_extra' \(motor\) deleted: .* the 2 actuator\(s\) after them move"
    with pytest.warns(UserWarning, match=deleted):
        knee = add_drive(
            spec, "knee", envelope=_env(), stiffness=50, damping=2, replace=True, effort_sensor=False
        )
    assert (hip.name, hip.replaced) == ("hip_motor", ("hip_motor",))
    assert (knee.name, knee.replaced) == ("knee_pos", ("knee_pos", "knee_extra"))
    model = spec.compile()
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(model.nu)]
    assert names == ["hip_motor", "knee_pos", "toe_vel", "other"]
    # the motor's torque 7 became the key's hip position; the deleted knee_extra's column is gone
    np.testing.assert_allclose(model.key_ctrl[0], [0.5, -0.3, 0.2, 4.0])
    # a motor's control range (a torque) became the joint's range (a target position)
    np.testing.assert_allclose(model.actuator_ctrlrange[0], [-1.0, 2.0])
    assert (
        model.actuator_plugin[0] >= 0 and model.actuator_plugin[1] >= 0 and not model.actuator_forcelimited[1]
    )


def test_replace_keeps_what_the_replaced_actuator_knew(mujoco: Any) -> None:
    """Describe a joint's existing actuators: position gains, velocity gain, motors."""
    from drive_envelope._src.adapters.mujoco.existing import joint_actuators

    spec = mujoco.MjSpec.from_string(MOTORS)
    knee = joint_actuators(spec, "knee")
    assert [(a.name, a.kind, a.stiffness, a.damping) for a in knee] == [
        ("knee_pos", "position", 50.0, 2.0),
        ("knee_extra", "motor", None, None),
    ]
    assert [(a.kind, a.stiffness, a.damping) for a in joint_actuators(spec, "toe")] == [
        ("velocity", 0.0, 3.0),
        ("motor", None, None),
    ]


def test_model_drives_lists_every_drive_with_its_numbers(mujoco: Any) -> None:
    """List drives of a compiled model: effort actuator, joint, inputs, envelope, gains."""
    from drive_envelope.mujoco import add_drive, model_drives

    spec = mujoco.MjSpec.from_string(ARM)
    add_drive(spec, "shoulder", envelope=_env(speed_effort_gradient=0.1), stiffness=80, damping=2)
    add_drive(
        spec, "elbow", envelope=PerformanceEnvelope(max_effort=3.0), stiffness=9, damping=1, inputs="pos ff"
    )
    drives = model_drives(spec.compile())
    assert [(d.name, d.joint, d.inputs) for d in drives] == [
        ("shoulder", "shoulder", ("pos",)),
        ("elbow", "elbow", ("pos", "ff")),
    ]
    assert drives[0].envelope == PerformanceEnvelope(
        max_effort=8.0, max_actuator_velocity=4.0, speed_effort_gradient=0.1, name="shoulder"
    )
    assert drives[1].envelope is not None and drives[1].envelope.max_actuator_velocity == float("inf")
    assert (drives[1].stiffness, drives[1].damping, drives[1].dynprm[1]) == (9.0, 1.0, -1.0)


# a new user's findings on the MuJoCo adapter: one lookup for every function that takes a drive,
# joint names, the documented snippet, the reason for a refused MjData

ROOT = Path(__file__).resolve().parents[1]


def _tendon_arm(tmp_path: Path, extra: str = "") -> Path:
    """Write the arm (shoulder, elbow, slider; a tendon, a site) as arm.xml, the docs' file name."""
    path = tmp_path / "arm.xml"
    path.write_text(TENDON_ARM.format(extra=extra))
    return path


def _driven_arm(mujoco: Any) -> tuple[Any, Any, tuple[Any, ...]]:
    """The arm with AK80-6 drives on the shoulder and the elbow: spec, model, drives."""
    from drive_envelope.mujoco import add_drives

    spec = mujoco.MjSpec.from_string(TENDON_ARM.format(extra=""))
    drives = add_drives(
        spec, ["shoulder", "elbow"], datasheet="tmotor-ak80-6", stiffness=30, damping=1, replace=True
    )
    return spec, spec.compile(), drives


def test_set_targets_reads_units_and_refuses_what_mujoco_would_zero(mujoco: Any) -> None:
    """Strings with units are read in the joint's SI unit; NaN, inf, arrays and bools are one line.

    A NaN or inf control was written as given: MuJoCo then warns once and zeroes every control of
    the model (the robot drives every joint to 0 with full effort). A refused call writes nothing.
    """
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec.from_string(ARM)
    elbow = add_drive(spec, "elbow", envelope=_env(), stiffness=60, damping=1, inputs="pos vel ff")
    slider = add_drive(
        spec, "slider", envelope=_env(joint="prismatic"), stiffness=60, damping=1, inputs="pos vel"
    )
    model = spec.compile()
    data = mujoco.MjData(model)
    elbow.set_targets(model, data, position="90 deg", velocity="60 rpm", effort="500 mNm")
    slider.set_targets(model, data, position="25 mm", velocity=np.float32(0.5))
    pos, vel, ff = (elbow.control_index(model, name) for name in ("pos", "vel", "ff"))
    assert data.ctrl[pos] == pytest.approx(np.pi / 2) and data.ctrl[vel] == pytest.approx(2 * np.pi)
    assert data.ctrl[ff] == pytest.approx(0.5)
    assert data.ctrl[slider.control_index(model, "pos")] == pytest.approx(0.025)
    assert data.ctrl[slider.control_index(model, "vel")] == 0.5
    before = data.ctrl.copy()
    for kwargs, message in [
        ({"position": float("nan")}, r"argument 'position' = nan: expected a finite target \[rad\]"),
        ({"velocity": np.inf}, r"argument 'velocity' = inf: expected a finite target \[rad/s\]"),
        ({"position": 1.0, "effort": [1.0, 2.0]}, r"argument 'effort': expected a number \[N\*m\]"),
        ({"position": True}, r"argument 'position': expected a number \[rad\]"),
        ({"position": "2 m"}, r"argument 'position': '2 m' is not"),
    ]:
        with pytest.raises(InputError, match=message) as error:
            elbow.set_targets(model, data, **kwargs)
        assert "\n" not in str(error.value) and str(error.value).startswith("drive 'elbow': set_targets:")
    with pytest.raises(InputError, match=r"argument 'position': '1 rad' is not"):
        slider.set_targets(model, data, position="1 rad")
    np.testing.assert_array_equal(data.ctrl, before)
    other = mujoco.MjSpec.from_string(ARM)
    add_drive(other, "shoulder", envelope=_env(), stiffness=60, damping=1)
    other_model = other.compile()
    with pytest.raises(
        InputError, match=r"drive 'elbow': the model has no actuator 'elbow'; expected the model compiled"
    ):
        elbow.set_targets(other_model, mujoco.MjData(other_model), position=0.0)


REPLACED = """<mujoco><compiler angle="radian"/><worldbody><body><joint name="j" range="-2 2"/>
<inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/></body></worldbody>
<actuator>{actuator}</actuator></mujoco>"""


@pytest.mark.parametrize(
    ("actuator", "inputs", "ctrlrange"),
    [
        ('<velocity name="m" joint="j" kv="3" ctrlrange="-5 5"/>', "pos", [-2.0, 2.0]),  # a speed range
        ('<position name="m" joint="j" kp="30" ctrlrange="-1 1"/>', "vel", None),  # a position range
        ('<motor name="m" joint="j" ctrlrange="-4 4"/>', "vel", None),  # a torque range
        ('<velocity name="m" joint="j" kv="3" ctrlrange="-5 5"/>', "vel", [-5.0, 5.0]),  # kept
        ('<position name="m" joint="j" kp="30" ctrlrange="-1 1"/>', "pos", [-1.0, 1.0]),  # kept
        ('<intvelocity name="m" joint="j" kp="30" actrange="-1 1"/>', "pos", None),  # compiles
    ],
)
def test_add_drive_replace_keeps_a_control_range_only_where_the_control_keeps_its_meaning(
    mujoco: Any, actuator: str, inputs: str, ctrlrange: list[float] | None
) -> None:
    """A velocity actuator's speed range was kept as the range of the drive's target position.

    ``add_drive(..., replace=True)`` (default inputs ``pos``) on a ``<velocity ctrlrange="-5 5">``
    clipped position targets to +-5 rad; a position actuator made a ``vel`` drive clipped speeds
    to its position range; an ``intvelocity``'s activation range failed MuJoCo's compile.
    """
    from drive_envelope.mujoco import add_drive

    spec = mujoco.MjSpec.from_string(REPLACED.format(actuator=actuator))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the intvelocity's dynamics: a warning of its own
        add_drive(spec, "j", envelope=_env(), stiffness=10, damping=1, inputs=inputs, replace=True)
    model = spec.compile()
    if ctrlrange is None:
        assert not model.actuator_ctrllimited[0]
    else:
        assert model.actuator_ctrllimited[0] and model.actuator_ctrlrange[0].tolist() == ctrlrange


def test_add_drive_replace_warns_of_a_tighter_force_range_as_mujoco_apply_does(mujoco: Any) -> None:
    """The Python path dropped a 3 N*m ``forcerange`` for the envelope's 8 N*m without a word."""
    from drive_envelope.mujoco import add_drive

    for forcerange, warned in (("-3 3", True), ("-20 20", False)):
        xml = REPLACED.format(actuator=f'<position name="m" joint="j" kp="30" forcerange="{forcerange}"/>')
        spec = mujoco.MjSpec.from_string(xml)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            add_drive(spec, "j", envelope=_env(), stiffness=10, damping=1, replace=True)
        messages = [str(w.message) for w in caught]
        expected = (
            "add_drive(joint='j'): actuator 'm' had forcerange [-3, 3] N*m, tighter than the envelope's "
            "max_effort 8 N*m; the drive replaces it, so the joint's limit becomes 8 N*m "
            "(lower max_effort to keep 3)"
        )
        assert messages == ([expected] if warned else []), messages


def test_a_stiffness_without_a_pos_input_is_a_warning(mujoco: Any) -> None:
    """inputs="vel" with stiffness 30: the target position is 0 and the joint is held there.

    Measured: a 2 rad/s target ends at v = 0, q = c*v/k = 0.0667 rad, with no word; ``mujoco apply
    --stiffness`` on a velocity actuator made such a drive too.
    """
    from drive_envelope.mujoco import add_drive

    xml = REPLACED.format(actuator="")
    message = (
        r"^add_drive\(joint='j'\): stiffness 30 N\*m/rad but no 'pos' input: the drive's target position is 0"
    )
    with pytest.warns(UserWarning, match=message + ", so it pulls the joint back to 0"):
        drive = add_drive(
            mujoco.MjSpec.from_string(xml), "j", envelope=_env(), stiffness=30, damping=1, inputs="vel"
        )
    assert drive.inputs == ("vel",)
    for stiffness, inputs in ((0.0, "vel"), (30.0, "pos vel")):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            add_drive(
                mujoco.MjSpec.from_string(xml),
                "j",
                envelope=_env(),
                stiffness=stiffness,
                damping=1,
                inputs=inputs,
            )


def test_add_drive_names_a_spec_that_is_not_one(mujoco: Any) -> None:
    """A compiled MjModel was ``TypeError: unhashable type``, XML text an ``AttributeError``."""
    from drive_envelope.mujoco import add_drive, add_drives

    for bad in (mujoco.MjModel.from_xml_string(ARM), ARM):
        with pytest.raises(
            InputError, match=r"^add_drive: argument 'spec': expected a mujoco\.MjSpec \(mujoco\.MjSpec"
        ):
            add_drive(bad, "elbow", envelope=_env(), stiffness=1, damping=1)
        with pytest.raises(InputError, match=rf"got {type(bad).__name__}$"):
            add_drives(bad, ["elbow"], envelope=_env(), stiffness=1, damping=1)


def test_drive_state_takes_every_kind_of_drive_reference(mujoco: Any) -> None:
    """MjDriveInfo from model_drives, MjDrive, actuator name, index (numpy too) and joint name agree."""
    from drive_envelope.mujoco import drive_state, get_envelope, get_gains, model_drives

    _, model, drives = _driven_arm(mujoco)
    data = mujoco.MjData(model)
    drives[1].set_targets(model, data, position=-1.0)
    mujoco.mj_step(model, data)
    info = model_drives(model)[1]
    index = info.actuator
    refs = [drives[1], info, "el", index, np.int64(index), "elbow"]
    states = {drive_state(model, data, ref) for ref in refs}
    assert len(states) == 1 and next(iter(states))[1] != 0.0
    assert {get_gains(model, ref) for ref in refs} == {(30.0, 1.0)}
    assert {get_envelope(model, ref).max_effort for ref in refs} == {info.envelope.max_effort}


@pytest.mark.parametrize("bad", [1.5, None, ["el"], True])
def test_a_drive_of_another_type_is_an_input_error_naming_argument_and_type(mujoco: Any, bad: Any) -> None:
    """Never a TypeError from mj_name2id: one line naming the argument and the type given."""
    from drive_envelope.mujoco import drive_state, set_envelope

    _, model, _ = _driven_arm(mujoco)
    data = mujoco.MjData(model)
    kind = type(bad).__name__
    with pytest.raises(InputError, match=rf"drive_state: argument 'drive': expected .* got {kind}$"):
        drive_state(model, data, bad)
    with pytest.raises(InputError, match=rf"argument 'actuator': expected .* got {kind}$"):
        set_envelope(model, bad, "tmotor-ak80-6")


def test_a_handle_of_another_model_is_refused(mujoco: Any) -> None:
    """An MjDriveInfo or MjDrive that is not a drive of this model is named, with the model's drives."""
    from drive_envelope.mujoco import add_drive, drive_state, model_drives, rollout_operating_points

    _, model, _ = _driven_arm(mujoco)
    spec = mujoco.MjSpec.from_string(TENDON_ARM.format(extra=""))
    slider = add_drive(spec, "slider", datasheet="actuonix-l16-35-6-r", stiffness=10, damping=1, replace=True)
    other = spec.compile()
    with pytest.raises(InputError, match=r"MjDriveInfo 'sm' \(joint 'slider'\) is not a drive of this model"):
        drive_state(model, mujoco.MjData(model), model_drives(other)[0])
    with pytest.raises(InputError, match=r"MjDrive 'sm' .* its drives: 'ps', 'el'"):
        drive_state(model, mujoco.MjData(model), slider)
    # rollouts find the effort sensor from any reference
    states = np.zeros((1, 3, mujoco.mj_stateSize(other, mujoco.mjtState.mjSTATE_FULLPHYSICS)))
    sensors = np.arange(3.0).reshape(1, 3, 1)
    velocity, effort = rollout_operating_points(other, "slider", states, sensors)
    assert effort.tolist() == [[0.0, 1.0, 2.0]] and velocity.shape == (1, 3)


def test_the_reason_for_a_refused_mjdata_is_the_warning_before_it(mujoco: Any) -> None:
    """timestep = 0 after compiling: MuJoCo's FatalError, the plugin's reason just before; documented."""
    _, model, _ = _driven_arm(mujoco)
    model.opt.timestep = 0.0
    seen: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(seen.append)
    try:
        with pytest.raises(mujoco.FatalError, match="plugin->init failed"):
            mujoco.MjData(model)
    finally:
        mujoco.set_mju_user_warning(previous)
    assert any("option 'timestep' = 0: expected a finite number > 0 [s]" in w for w in seen)
    docs = (ROOT / "docs" / "mujoco.md").read_text()
    assert "initPluginOrFree: plugin->init failed" in docs and "option 'timestep' = 0" in docs


def test_the_documented_snippet_runs_as_written(
    mujoco: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Run the first python block of docs/mujoco.md on an arm whose elbow has a motor named 'el'."""
    docs = (ROOT / "docs" / "mujoco.md").read_text()
    snippet = re.search(r"```python\n(.*?)```", docs, flags=re.DOTALL)
    assert snippet is not None
    _tendon_arm(tmp_path)
    monkeypatch.chdir(tmp_path)
    scope: dict[str, Any] = {}
    exec(compile(snippet.group(1), "docs/mujoco.md", "exec"), scope)  # our own docs
    from drive_envelope.mujoco import get_envelope

    assert scope["elbow"].name == "el" and scope["elbow"].replaced == ("el",)
    assert scope["elbow"].envelope.contains(scope["velocity"], scope["effort"], atol=1e-9).item()
    assert get_envelope(scope["model"], "el").max_effort == get_envelope(scope["model"], "elbow").max_effort
    assert get_envelope(scope["model"], "el").max_effort != scope["elbow"].envelope.max_effort


def test_set_envelope_and_gains_take_a_joint_name_and_suggest_near_names(mujoco: Any) -> None:
    """Actuator name first, then the driven joint; an unknown name gets the nearest ones."""
    from drive_envelope.mujoco import get_gains, set_envelope, set_gains

    _, model, _ = _driven_arm(mujoco)
    set_gains(model, "elbow", stiffness=12.0)
    assert get_gains(model, "el") == (12.0, 1.0)
    set_envelope(model, "shoulder", PerformanceEnvelope(max_effort=3.0))
    assert model.actuator_dynprm[0, 0] == 3.0
    with pytest.raises(InputError, match=r"no actuator named 'elbw' and no driven joint .*'elbow'"):
        set_envelope(model, "elbw", PerformanceEnvelope(max_effort=1.0))
    with pytest.raises(
        InputError, match=r"joint 'slider' has no envelope drive; its drives .*'el' on 'elbow'"
    ):
        get_gains(model, "slider")
    with pytest.raises(InputError, match=r"actuator 'sm' is not a drive"):
        get_gains(model, "sm")

"""MuJoCo's own actuator features with the plugin, and the drives' numbers living in the MjModel.

Twin tests (MuJoCo's pid_test style): a plugin drive beside a native ``position`` actuator with the
same delay react at the same step; disabled groups silence both alike. The numbers are read from
``actuator_dynprm`` at every step, so changing the model changes every MjData at its next step, and
``mujoco.rollout`` over several models uses each model's own envelope.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import InputError, PerformanceEnvelope

pytestmark = pytest.mark.mujoco

EXT = '<extension><plugin plugin="drive_envelope.envelope"/></extension>'
TWIN = (
    '<mujoco><option timestep="0.002" gravity="0 0 0"/>' + EXT + "<worldbody>"
    '<body><joint name="a" axis="0 0 1"/><inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/></body>'
    '<body pos="1 0 0"><joint name="b" axis="0 0 1"/>'
    '<inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/></body></worldbody>'
    "<actuator>{actuators}</actuator></mujoco>"
)
ONE = (
    '<mujoco><option timestep="0.01" gravity="0 0 0"/>'
    + EXT
    + '<worldbody><body><joint name="j" axis="0 0 1"/>'
    '<inertial pos="0 0 0" mass="1" diaginertia="0.5 0.5 0.5"/></body></worldbody>'
    '<actuator><plugin name="drive" joint="j" plugin="drive_envelope.envelope" dynprm="{dynprm}" {extra}/>'
    "</actuator></mujoco>"
)


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


@pytest.fixture
def warnings_seen(mujoco: Any) -> Iterator[list[str]]:
    """Collect MuJoCo's warnings (mju_warning) instead of printing them."""
    seen: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(seen.append)
    yield seen
    mujoco.set_mju_user_warning(previous)


def _first_step_with_force(mujoco: Any, model: Any, steps: int = 40) -> list[int]:
    data = mujoco.MjData(model)
    first = [-1] * model.nu
    for k in range(steps):
        data.ctrl[:] = 1.0
        mujoco.mj_step(model, data)
        for i in range(model.nu):
            if first[i] < 0 and data.actuator_force[i] != 0.0:
                first[i] = k
    return first


@pytest.mark.parametrize("delay", [0.0, 0.006, 0.02])
def test_delay_reads_the_delayed_control_as_a_native_actuator_does(mujoco: Any, delay: float) -> None:
    """React to a control step at the same step as a native position actuator with the same delay."""
    attrs = f'delay="{delay}" nsample="20"' if delay else ""
    actuators = (
        f'<plugin name="p" joint="a" plugin="drive_envelope.envelope" dynprm="-1 -1 0 0 10 0" {attrs}/>'
        f'<position name="n" joint="b" kp="10" {attrs}/>'
    )
    model = mujoco.MjModel.from_xml_string(TWIN.format(actuators=actuators))
    first = _first_step_with_force(mujoco, model)
    assert first[0] == first[1] == round(delay / 0.002)


def test_disabled_actuator_group_silences_the_drive_like_a_native_one(mujoco: Any) -> None:
    """Give zero force while the drive's group is disabled, and force again once it is enabled."""
    actuators = (
        '<plugin name="p" joint="a" plugin="drive_envelope.envelope" dynprm="5 -1 0 0 10 1" group="3"/>'
        '<position name="n" joint="b" kp="10" group="3"/>'
    )
    model = mujoco.MjModel.from_xml_string(TWIN.format(actuators=actuators))
    data = mujoco.MjData(model)
    data.ctrl[:] = 1.0
    model.opt.disableactuator = 1 << 3
    mujoco.mj_step(model, data)
    np.testing.assert_array_equal(data.actuator_force, [0.0, 0.0])
    assert data.qvel[0] == 0.0
    model.opt.disableactuator = 0
    mujoco.mj_step(model, data)
    assert data.actuator_force[0] > 0.0 and data.actuator_force[1] > 0.0


def test_a_disabled_input_actuator_contributes_nothing(mujoco: Any) -> None:
    """Read a disabled input's control as 0 (its channel is off), the drive still runs."""
    xml = (
        '<mujoco><option timestep="0.01" gravity="0 0 0"/>' + EXT
        + '<worldbody><body><joint name="j" axis="0 0 1"/>'
        '<inertial pos="0 0 0" mass="1" diaginertia="0.5 0.5 0.5"/></body></worldbody>'
        '<extension><plugin plugin="drive_envelope.envelope"><instance name="i">'
        '<config key="input" value="pos ff"/></instance></plugin></extension>'
        '<actuator><plugin name="pos" joint="j" instance="i" dynprm="-1 -1 0 0 0 0"/>'
        '<plugin name="ff" joint="j" instance="i" group="2"/></actuator></mujoco>'
    )  # fmt: skip
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.ctrl[:] = [0.0, 2.0]  # zero gains: the effort is the feed-forward alone
    mujoco.mj_step(model, data)
    assert data.actuator_force[0] == pytest.approx(2.0)
    model.opt.disableactuator = 1 << 2
    mujoco.mj_step(model, data)
    assert data.actuator_force[0] == 0.0


def test_two_drives_on_one_joint_fail_compilation_naming_both(mujoco: Any) -> None:
    """Refuse a second plugin drive on a joint (20 N*m against a 10 N*m cap before)."""
    actuators = (
        '<plugin name="first" joint="a" plugin="drive_envelope.envelope" dynprm="10 -1 0 0 10 1"/>'
        '<plugin name="second" joint="a" plugin="drive_envelope.envelope" dynprm="10 -1 0 0 10 1"/>'
    )
    with pytest.raises(ValueError, match="joint 'a' has two drives: actuators 'first' and 'second'"):
        mujoco.MjModel.from_xml_string(TWIN.format(actuators=actuators))


def test_another_actuator_on_a_driven_joint_warns_naming_both(mujoco: Any, warnings_seen: list[str]) -> None:
    """Warn when the model is made that a native actuator's force on a driven joint bypasses the envelope."""
    # names of their own: the plugin says each distinct warning once per process
    actuators = (
        '<plugin name="warned_drive" joint="a" plugin="drive_envelope.envelope" dynprm="10 -1 0 0 10 1"/>'
        '<motor name="warned_extra" joint="a"/>'
    )
    model = mujoco.MjModel.from_xml_string(TWIN.format(actuators=actuators))
    mujoco.MjData(model)
    found = [
        w
        for w in warnings_seen
        if "actuator 'warned_extra' also acts on joint 'a', driven by 'warned_drive'" in w
    ]
    assert len(found) == 1 and "'ff' input" in found[0]


def test_another_actuators_force_enters_the_prediction(mujoco: Any) -> None:
    """Keep the drive on its envelope at the end-of-step velocity with a native motor pushing the joint."""
    actuators = (
        '<plugin name="drive" joint="a" plugin="drive_envelope.envelope" dynprm="2 1 0 0 0 10">'
        '<config key="input" value="vel"/></plugin><motor name="extra" joint="a"/>'
    )
    model = mujoco.MjModel.from_xml_string(TWIN.format(actuators=actuators))
    data = mujoco.MjData(model)
    data.qvel[0] = 0.99
    data.ctrl[:] = [5.0, 0.5]  # the drive wants 5 rad/s; the motor adds 0.01 rad/s per step on its own
    mujoco.mj_step(model, data)
    env = PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=1.0)
    # the motor's push was predicted: the drive's effort keeps the end-of-step velocity at 1 rad/s
    assert data.qvel[0] == pytest.approx(1.0, abs=1e-12)
    assert env.contains(data.qvel[0], data.actuator_force[0], atol=1e-9)


def test_numbers_changed_in_the_model_take_effect_at_the_next_step(mujoco: Any) -> None:
    """Read actuator_dynprm at every step: two MjData of one model follow it, mj_resetData keeps it."""
    from drive_envelope.mujoco import get_envelope, set_envelope

    model = mujoco.MjModel.from_xml_string(ONE.format(dynprm="8 -1 0 0 1000 0", extra=""))
    datas = [mujoco.MjData(model) for _ in range(2)]
    for data in datas:
        data.ctrl[0] = 1.0
        mujoco.mj_step(model, data)
        assert data.actuator_force[0] == pytest.approx(8.0)
    set_envelope(model, "drive", PerformanceEnvelope(max_effort=2.0))
    for data in datas:
        mujoco.mj_resetData(model, data)
        data.ctrl[0] = 1.0
        mujoco.mj_step(model, data)
        assert data.actuator_force[0] == pytest.approx(2.0)
    assert get_envelope(model, "drive").max_effort == 2.0
    assert model.actuator_dynprm[0, :6].tolist() == [2.0, -1.0, 0.0, 0.0, 1000.0, 0.0]


def test_rollout_over_models_uses_each_models_own_envelope(mujoco: Any) -> None:
    """Give caps 2 and 8 N*m in one mujoco.rollout over two models of one structure."""
    from mujoco import rollout

    from drive_envelope.mujoco import set_envelope

    models = [
        mujoco.MjModel.from_xml_string(ONE.format(dynprm="8 -1 0 0 1000 0", extra="")) for _ in range(2)
    ]
    set_envelope(models[0], 0, PerformanceEnvelope(max_effort=2.0))
    datas = [mujoco.MjData(models[0]) for _ in range(2)]  # made from the first model only
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.zeros(mujoco.mj_stateSize(models[0], spec))
    mujoco.mj_getState(models[0], datas[0], state0, spec)
    control = np.ones((2, 5, 1))
    states, _ = rollout.rollout(models, datas, np.tile(state0, (2, 1)), control)
    velocity = states[:, :, 1 + models[0].nq]
    # from rest with inertia 0.5: v after one step = cap * dt / 0.5
    np.testing.assert_allclose(velocity[:, 0], [2.0 * 0.01 / 0.5, 8.0 * 0.01 / 0.5], rtol=1e-12)


def _capped_stiff_drive(mujoco: Any) -> tuple[Any, Any]:
    """ONE's drive with an 8 N*m cap and kp 1000, its target 1 rad away: the cap binds."""
    model = mujoco.MjModel.from_xml_string(ONE.format(dynprm="8 -1 0 0 1000 0", extra=""))
    data = mujoco.MjData(model)
    data.ctrl[0] = 1.0
    return model, data


def test_bad_numbers_set_between_steps_give_no_effort_and_one_warning(
    mujoco: Any, warnings_seen: list[str]
) -> None:
    """Let the drive go (0) on a NaN or negative number set at run time, warning once per MjData."""
    model, data = _capped_stiff_drive(mujoco)
    model.actuator_dynprm[0, 0] = np.nan
    for _ in range(3):
        mujoco.mj_step(model, data)
        assert data.actuator_force[0] == 0.0
    assert len([w for w in warnings_seen if "dynprm[0] (max_effort) = nan" in w]) == 1
    model.actuator_dynprm[0, 0] = 8.0
    mujoco.mj_step(model, data)
    assert data.actuator_force[0] == pytest.approx(8.0)


def test_numbers_changed_between_good_steps_take_effect_at_the_next_step(
    mujoco: Any, warnings_seen: list[str]
) -> None:
    """Read every changed slot at the next step, although the plugin checks only numbers that changed."""
    model, data = _capped_stiff_drive(mujoco)
    efforts = []
    for change in ((0, 8.0), (0, 3.0), (4, 1.0), (7, 1.0), (7, 0.0), (0, -2.0), (0, 3.0)):
        model.actuator_dynprm[0, change[0]] = change[1]
        mujoco.mj_resetData(model, data)
        data.ctrl[0] = 1.0
        mujoco.mj_step(model, data)
        efforts.append(float(data.actuator_force[0]))
    # kp 1000 on a 1 rad error: the cap binds (8, then 3); kp 1: the PD law at the end-of-step
    # velocity, below the cap; a reserved slot or a negative cap set after good steps: no effort
    kp1 = efforts[2]
    assert efforts[:2] == pytest.approx([8.0, 3.0])
    assert 0.5 < kp1 < 1.0
    assert efforts[3] == 0.0 and efforts[4] == pytest.approx(kp1) and efforts[5] == 0.0
    assert efforts[6] == pytest.approx(kp1)
    # one warning per drive and MjData: the first bad number's
    assert [w for w in warnings_seen if "dynprm" in w] == [
        w for w in warnings_seen if "dynprm[7] = 1: reserved" in w
    ]
    assert len([w for w in warnings_seen if "dynprm" in w]) == 1


def test_a_timestep_made_negative_between_steps_gives_no_effort(
    mujoco: Any, warnings_seen: list[str]
) -> None:
    """Give zero effort (never 1.7e7 N*m) when opt.timestep is set <= 0 after compilation."""
    model = mujoco.MjModel.from_xml_string(ONE.format(dynprm="3.3 -1 0 0 1000 0", extra=""))
    data = mujoco.MjData(model)
    data.ctrl[0] = 1.0
    model.opt.timestep = -0.002
    mujoco.mj_forward(model, data)
    assert data.actuator_force[0] == 0.0
    assert any("option 'timestep' = -0.002" in w for w in warnings_seen)


def test_set_envelope_and_set_gains_refuse_bad_input(mujoco: Any) -> None:
    """Raise one-line InputErrors for an unknown actuator, a non-drive, a wrong joint type, a huge number."""
    from drive_envelope.mujoco import get_gains, set_envelope, set_gains

    actuators = (
        '<plugin name="drive" joint="a" plugin="drive_envelope.envelope" dynprm="10 -1 0 0 10 1"/>'
        '<motor name="motor" joint="b"/>'
    )
    model = mujoco.MjModel.from_xml_string(TWIN.format(actuators=actuators))
    with pytest.raises(InputError, match="the model has no actuator named 'knee'"):
        set_envelope(model, "knee", PerformanceEnvelope(max_effort=1.0))
    with pytest.raises(InputError, match="actuator 'motor' is not a drive"):
        set_envelope(model, "motor", PerformanceEnvelope(max_effort=1.0))
    with pytest.raises(InputError, match=r"an id in \[0, 2\), got 7"):
        set_envelope(model, 7, PerformanceEnvelope(max_effort=1.0))
    with pytest.raises(InputError, match="envelope is for a prismatic joint but 'a' is revolute"):
        set_envelope(model, "drive", PerformanceEnvelope(max_effort=1.0, joint="prismatic"))
    with pytest.raises(InputError, match=r"max_effort = 10000000000000.0: expected a number in \[0, 1e12\]"):
        set_envelope(model, "drive", PerformanceEnvelope(max_effort=1e13))
    with pytest.raises(InputError, match="stiffness = -1"):
        set_gains(model, "drive", stiffness=-1)
    set_gains(model, "drive", damping=3.0)
    assert get_gains(model, "drive") == (10.0, 3.0)


def test_set_gains_reads_units_as_add_drive_does(mujoco: Any) -> None:
    """Strings with units, as add_drive takes them, in the drive type's unit; other types one line.

    ``set_gains(model, "a", stiffness="60 N*m/deg")`` was float()'s bare ValueError; a list was a
    TypeError. A refused call changes neither gain.
    """
    from drive_envelope.mujoco import get_gains, set_gains

    actuators = (
        '<plugin name="drive" joint="a" plugin="drive_envelope.envelope" dynprm="10 -1 0 0 10 1"/>'
        '<plugin name="accel" joint="b" dynprm="10 -1 0 0 10 1" instance="acc"/>'
    )
    xml = TWIN.format(actuators=actuators).replace(
        "<actuator>",
        '<extension><plugin plugin="drive_envelope.envelope"><instance name="acc">'
        '<config key="drive_type" value="acceleration"/></instance></plugin></extension><actuator>',
    )
    model = mujoco.MjModel.from_xml_string(xml)
    set_gains(model, "drive", stiffness="60 N*m/deg", damping=np.float32(2.0))
    assert get_gains(model, "drive") == (pytest.approx(60 * 180 / np.pi), 2.0)
    set_gains(model, "accel", stiffness="400 1/s^2", damping="20 1/s")
    assert get_gains(model, "accel") == (400.0, 20.0)
    for kwargs, message in [
        (
            {"stiffness": "60 N*m", "damping": 1.0},
            r"argument 'stiffness': '60 N\*m' has no matching angle unit",
        ),
        ({"damping": [1.0]}, r"argument 'damping': expected a number \[N\*m\*s/rad\] or a string with units"),
        ({"stiffness": True}, r"argument 'stiffness': expected a number"),
        ({"stiffness": 1.0, "damping": "-3 N*m*s/rad"}, r"damping = -3\.0: expected a number in \[0, 1e12\]"),
    ]:
        with pytest.raises(InputError, match=message) as error:
            set_gains(model, "drive", **kwargs)
        assert "\n" not in str(error.value)
    assert get_gains(model, "drive") == (pytest.approx(60 * 180 / np.pi), 2.0)
    with pytest.raises(InputError, match=r"argument 'stiffness': '1 N\*m/rad' is not"):
        set_gains(model, "accel", stiffness="1 N*m/rad")


def test_a_spec_or_data_where_the_model_goes_is_one_line(mujoco: Any) -> None:
    """An MjSpec (not compiled) or the MjData (arguments swapped) was an AttributeError on
    ``nplugin`` or ``plugin_attradr``; a model where the data goes, on ``qvel``.
    """
    from drive_envelope.mujoco import drive_state, get_envelope, model_drives, set_envelope, set_gains

    xml = TWIN.format(
        actuators='<plugin name="drive" joint="a" plugin="drive_envelope.envelope" dynprm="10 -1 0 0 10 1"/>'
    )
    spec = mujoco.MjSpec.from_string(xml)
    model = spec.compile()
    data = mujoco.MjData(model)
    spec_hint = r"expected a mujoco\.MjModel \(spec\.compile\(\)\), got MjSpec$"
    for where, call, message in [
        ("model_drives", lambda: model_drives(spec), spec_hint),
        ("set_envelope", lambda: set_envelope(spec, "drive", PerformanceEnvelope(max_effort=1.0)), spec_hint),
        ("get_envelope", lambda: get_envelope(data, "drive"), r"expected a mujoco\.MjModel, got MjData$"),
        (
            "set_gains",
            lambda: set_gains(data, "drive", stiffness=1.0),
            r"expected a mujoco\.MjModel, got MjData$",
        ),
        (
            "drive_state",
            lambda: drive_state(data, model, "drive"),
            r"expected a mujoco\.MjModel, got MjData$",
        ),
    ]:
        with pytest.raises(InputError, match=rf"^{where}: argument 'model': {message}"):
            call()
    with pytest.raises(
        InputError, match=r"^drive_state: argument 'data': expected a mujoco\.MjData, got MjModel$"
    ):
        drive_state(model, model, "drive")


def test_solver_stats_report_the_solve_and_the_plugin_has_no_state(mujoco: Any) -> None:
    """The solve's iterations and drive solves of the last step; none of it is MuJoCo state."""
    from drive_envelope.mujoco import solver_stats

    model = mujoco.MjModel.from_xml_string(ONE.format(dynprm="1 -1 0 0 1000 0", extra=""))
    data = mujoco.MjData(model)
    # as MuJoCo's pid: a saved mjSTATE_FULLPHYSICS holds time, qpos, qvel (and act) only
    assert model.npluginstate == 0
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    assert mujoco.mj_stateSize(model, full) == 1 + model.nq + model.nv + model.na
    data.ctrl[0] = 0.0
    mujoco.mj_step(model, data)
    assert solver_stats(model, data) == (0, 0)  # inside the envelope: the linear solve is it
    data.ctrl[0] = 1.0
    mujoco.mj_step(model, data)
    # saturated: a Newton step (clamp, two slope probes), then a second clamp that confirms it
    assert solver_stats(model, data) == (2, 4)
    mujoco.mj_resetData(model, data)
    assert solver_stats(model, data) == (0, 0)


def test_copy_data_steps_as_the_original(mujoco: Any) -> None:
    """mj_copyData gives an independent drive (its own instance) that steps bit for bit alike."""
    model = mujoco.MjModel.from_xml_string(ONE.format(dynprm="1 -1 0 0 100 5", extra=""))
    data = mujoco.MjData(model)
    data.ctrl[0] = 1.0
    for _ in range(3):
        mujoco.mj_step(model, data)
    copy = mujoco.MjData(model)
    mujoco.mj_copyData(copy, model, data)
    for _ in range(20):
        mujoco.mj_step(model, data)
        mujoco.mj_step(model, copy)
    assert copy.qvel.tolist() == data.qvel.tolist()
    assert copy.actuator_force.tolist() == data.actuator_force.tolist()


@pytest.mark.parametrize(
    ("ctrl", "dv_dctrl"),
    [
        # inside the envelope: dv1/dctrl = h/I * k/(1 + (h*k + c)*h/I), the implicit PD law by hand
        (0.005, 0.01 / 0.5 * 100.0 / (1.0 + (0.01 * 100.0 + 5.0) * 0.01 / 0.5)),
        (1.0, 0.0),  # saturated at max_effort = 1 N*m: the effort does not move with the target
    ],
)
def test_finite_differences_see_the_drive_law(mujoco: Any, ctrl: float, dv_dctrl: float) -> None:
    """mjd_transitionFD through the plugin: the control derivative is the drive law's, 0 when clamped."""
    model = mujoco.MjModel.from_xml_string(ONE.format(dynprm="1 -1 0 0 100 5", extra=""))
    data = mujoco.MjData(model)
    data.ctrl[0] = ctrl
    nx = 2 * model.nv + model.na
    a, b = np.zeros((nx, nx)), np.zeros((nx, model.nu))
    mujoco.mjd_transitionFD(model, data, 1e-6, 1, a, b, None, None)
    h = model.opt.timestep
    np.testing.assert_allclose(b[:, 0], [h * dv_dctrl, dv_dctrl], rtol=1e-6, atol=1e-9)


def test_keyframe_reset_starts_the_drive_from_the_keyframe(mujoco: Any) -> None:
    """mj_resetDataKeyframe: qpos and ctrl from the keyframe; the first step is the drive law from there."""
    xml = ONE.format(dynprm="5 -1 0 0 100 5", extra="").replace(
        "</actuator>", '</actuator><keyframe><key qpos="0.3" ctrl="0.32"/></keyframe>'
    )
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_step(model, data)
    k, c, h, inertia = 100.0, 5.0, 0.01, 0.5
    expected = k * (0.32 - 0.3) / (1.0 + (h * k + c) * h / inertia)  # from rest, inside max_effort 5
    assert data.actuator_force[0] == pytest.approx(expected, rel=1e-12)


def test_solver_stats_need_a_model_with_drives(mujoco: Any) -> None:
    """A model without the plugin is a one-line error naming the plugin."""
    from drive_envelope.mujoco import solver_stats

    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
    with pytest.raises(InputError, match=r"no instance of the 'drive_envelope\.envelope' plugin"):
        solver_stats(model, mujoco.MjData(model))


def test_domain_randomization_example_gives_each_model_its_own_envelope(mujoco: Any) -> None:
    """Run the shipped example briefly: each rollout's knee efforts stay within its own max_effort."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples" / "mujoco"))
    try:
        import domain_randomization as example
    finally:
        sys.path.pop(0)
    models, drawn = example.randomized_models(3, seed=1)
    _, effort = example.roll_out(models, seconds=0.4)
    caps = np.array([env.max_effort for env in drawn])
    assert len(set(caps)) == 3
    peaks = np.abs(effort).max(axis=(1, 2))
    assert (peaks <= caps * (1 + 1e-12)).all() and (peaks > 0.9 * caps).all()  # each saturates at its own cap

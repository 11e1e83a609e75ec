"""drive_envelope.mjwarp: the plugin-free twin, per-world numbers, bad input, graph capture."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import InputError, PerformanceEnvelope

pytestmark = [pytest.mark.mujoco, pytest.mark.warp]

# a 1 kg*m^2 wheel without gravity: a step of the target saturates the drive at its cap
WHEEL = """<mujoco><option timestep="0.01" integrator="Euler" gravity="0 0 0"/>
<extension><plugin plugin="drive_envelope.envelope"/></extension>
<worldbody><body><joint name="j" axis="0 0 1"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>
<body pos="1 0 0"><joint name="s" type="slide" axis="1 0 0"/>
<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></body></worldbody><actuator>
<plugin name="a" joint="j" plugin="drive_envelope.envelope" dynprm="5 -1 0 0 1000 10" group="0"/>
<plugin name="b" joint="s" plugin="drive_envelope.envelope" dynprm="2 -1 0 0 100 1" group="3"/>
</actuator></mujoco>"""


@pytest.fixture(scope="module")
def env() -> Any:
    """(mujoco, mujoco_warp) with the plugin loaded and Warp quiet."""
    mujoco = mujoco_with_plugin()
    mjw = pytest.importorskip("mujoco_warp")
    import warp as wp

    wp.config.quiet = True
    return mujoco, mjw


@pytest.fixture(scope="module")
def wheel(env: Any) -> tuple[Any, Any, Any]:
    """(spec, MJWarp model with an actuator_dynprm row per world, its compiled twin) for 3 worlds."""
    mujoco, _ = env
    from drive_envelope.mjwarp import envelope_drives, put_model

    spec = mujoco.MjSpec.from_string(WHEEL)
    m = put_model(spec, batch_sizes={"actuator_dynprm": 3})
    return spec, m, envelope_drives(m).mj_model


def _saturate(env: Any, m: Any, mjm: Any, nworld: int, steps: int = 3) -> np.ndarray:
    """The drives' efforts after a big target step, one row per world."""
    _, mjw = env
    d = mjw.make_data(mjm, nworld=nworld)
    d.ctrl.assign(np.full((nworld, mjm.nu), 10.0, dtype=np.float32))
    for _ in range(steps):
        mjw.step(m, d)
    return d.actuator_force.numpy().astype(np.float64)


def test_stock_mjwarp_still_rejects_the_plugin_model(env: Any) -> None:
    """Document the upstream limit the twin works around: MJWarp's put_model refuses the plugin."""
    mujoco, mjw = env
    model = mujoco.MjModel.from_xml_string(WHEEL)
    with pytest.raises(NotImplementedError, match="Actuator plugins"):
        mjw.put_model(model)


def test_a_compiled_model_with_plugin_drives_names_what_to_pass(env: Any) -> None:
    """Refuse a compiled MjModel with plugin drives in one line that names the spec or file."""
    mujoco, _ = env
    from drive_envelope.mjwarp import put_model

    with pytest.raises(InputError, match=r"pass the mujoco\.MjSpec or the MJCF file") as info:
        put_model(mujoco.MjModel.from_xml_string(WHEEL))
    assert "\n" not in str(info.value)


def test_the_twin_keeps_every_actuator_without_the_plugin(env: Any, wheel: Any) -> None:
    """Keep names, order, groups and dynprm in the twin; leave the user's spec as it was."""
    spec, _, twin = wheel
    original = spec.compile()
    assert twin.nplugin == 0 and (twin.actuator_plugin == -1).all()
    assert original.nplugin > 0  # the spec was not changed
    assert [twin.actuator(i).name for i in range(twin.nu)] == ["a", "b"]
    np.testing.assert_array_equal(twin.actuator_dynprm, original.actuator_dynprm)
    np.testing.assert_array_equal(twin.actuator_group, original.actuator_group)


def test_each_world_has_its_own_envelope(env: Any, wheel: Any) -> None:
    """Saturate world k at its own max_effort after set_envelope(world=k); the others keep theirs."""
    from drive_envelope.mjwarp import get_envelope, set_envelope

    _, m, twin = wheel
    set_envelope(m, "a", PerformanceEnvelope(max_effort=5.0))
    set_envelope(m, "a", PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=40.0), world=1)
    set_envelope(m, 0, PerformanceEnvelope(max_effort=8.0), world=[2])
    efforts = _saturate(env, m, twin, 3)
    np.testing.assert_allclose(efforts[:, 0], [5.0, 2.0, 8.0], rtol=1e-6)
    assert get_envelope(m, "a", world=1).max_actuator_velocity == pytest.approx(40.0)
    assert get_envelope(m, "a", world=0).max_actuator_velocity == float("inf")


def test_gains_change_per_world(env: Any, wheel: Any) -> None:
    """Change one world's stiffness; read it back per world."""
    from drive_envelope.mjwarp import get_gains, set_gains

    _, m, _ = wheel
    set_gains(m, "a", stiffness=250.0, world=0)
    assert get_gains(m, "a", world=0) == (250.0, 10.0)
    assert get_gains(m, "a", world=2) == (1000.0, 10.0)
    set_gains(m, "a", stiffness=1000.0)


def test_a_drive_in_a_disabled_group_gives_nothing(env: Any) -> None:
    """Give 0 for a drive whose actuator group opt.disableactuator disables, as the plugin does."""
    mujoco, _ = env
    from drive_envelope.mjwarp import envelope_drives, put_model

    spec = mujoco.MjSpec.from_string(WHEEL)
    spec.option.disableactuator = 1 << 3
    m = put_model(spec)
    efforts = _saturate(env, m, envelope_drives(m).mj_model, 1)
    assert efforts[0, 0] == pytest.approx(5.0, rel=1e-6) and efforts[0, 1] == 0.0


BAD_CALLS = [
    ("set_envelope", ("nope", "tmotor-ak80-6"), {}, "'nope'"),
    ("set_envelope", ("a", "tmotor-ak80-6"), {"world": 3}, r"\[0, 3\)"),
    ("set_envelope", ("a", PerformanceEnvelope(max_effort=2e12)), {}, "1e12"),
    ("set_envelope", ("b", "tmotor-ak80-6"), {}, "revolute joint"),
    ("set_gains", ("a",), {"damping": -1.0}, r"damping = -1\.0"),
    ("get_envelope", ("a",), {"world": -1}, "world"),
]


@pytest.mark.parametrize(("name", "args", "kwargs", "match"), BAD_CALLS)
def test_bad_arguments_are_one_line_errors(
    wheel: Any, name: str, args: tuple, kwargs: dict, match: str
) -> None:
    """Name the argument, the value and what was expected in one line."""
    import drive_envelope.mjwarp

    _, m, _ = wheel
    with pytest.raises(InputError, match=match) as info:
        getattr(drive_envelope.mjwarp, name)(m, *args, **kwargs)
    assert "\n" not in str(info.value)


def test_shared_rows_refuse_one_world(env: Any) -> None:
    """Say how to get an envelope per world when the worlds share one row."""
    mujoco, _ = env
    from drive_envelope.mjwarp import put_model, set_envelope

    m = put_model(mujoco.MjSpec.from_string(WHEEL))
    with pytest.raises(InputError, match="batch_sizes=\\{'actuator_dynprm': nworld\\}"):
        set_envelope(m, "a", PerformanceEnvelope(max_effort=1.0), world=1)


def test_attach_refuses_what_cannot_feed_a_drive(env: Any) -> None:
    """Refuse an unknown actuator, a forcerange, and two drives on one joint, naming them."""
    mujoco, mjw = env
    from drive_envelope.mjwarp import attach, envelope_drives

    xml = (
        '<mujoco><worldbody><body><joint name="j"/><geom size="0.1" mass="1"/></body></worldbody>'
        '<actuator><motor name="m1" joint="j"/><motor name="m2" joint="j" forcerange="-1 1"/>'
        '<motor name="m3" joint="j"/></actuator></mujoco>'
    )
    mjm = mujoco.MjModel.from_xml_string(xml)
    m = mjw.put_model(mjm)
    with pytest.raises(InputError, match="no actuator 'x'"):
        attach(m, mjm, ["x"])
    with pytest.raises(InputError, match=r"'m2'.*forcerange"):
        attach(m, mjm, ["m2"])
    with pytest.raises(InputError, match="two drives: actuators 'm1' and 'm3'"):
        attach(m, mjm, ["m1", "m3"])
    with pytest.raises(InputError, match="no envelope drives"):
        envelope_drives(m)


@pytest.mark.gpu
def test_a_captured_cuda_graph_steps_like_plain_launches(env: Any) -> None:
    """Capture mujoco_warp.step with the drives in a CUDA graph; replay it like plain steps."""
    mujoco, mjw = env
    import warp as wp

    from drive_envelope.mjwarp import put_model

    if not wp.is_cuda_available():
        pytest.skip("needs a CUDA device (Warp finds none)")
    spec = mujoco.MjSpec.from_string(WHEEL)
    mjm = spec.compile()
    with wp.ScopedDevice("cuda:0"):
        m = put_model(spec)
        plain, graphed = mjw.make_data(mjm, nworld=4), mjw.make_data(mjm, nworld=4)
        for d in (plain, graphed):
            d.ctrl.fill_(10.0)
        mjw.step(m, plain)  # compiles the kernels outside the capture
        wp.copy(graphed.qvel, plain.qvel)
        wp.copy(graphed.qpos, plain.qpos)
        with wp.ScopedCapture() as capture:
            mjw.step(m, graphed)
        for _ in range(5):
            mjw.step(m, plain)
            wp.capture_launch(capture.graph)
        np.testing.assert_allclose(graphed.qvel.numpy(), plain.qvel.numpy(), rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(graphed.actuator_force.numpy(), plain.actuator_force.numpy(), rtol=1e-6)

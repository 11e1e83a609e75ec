"""The ``drive_envelope.envelope`` MuJoCo plugin through the Python bindings: one drive at a time.

Golden numbers are computed by hand from the spec (first-step effort ``tau_max/(1 + r*R*dt)``, the
velocity settling on ``max_actuator_velocity``) or independently in NumPy from MuJoCo's dense mass
matrix and the core functions (multi-DOF response and smooth forces). The coupled solve of several
drives is in ``test_mujoco_coupled.py``; MuJoCo's actuator features (delay, groups) and the model-side
numbers in ``test_mujoco_features.py``.
"""

from __future__ import annotations

import json
import math
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import PerformanceEnvelope, clamp_effort_implicit, implicit_drive_effort
from drive_envelope.errors import DriveEnvelopeError

pytestmark = pytest.mark.mujoco

HEAD = '<mujoco><option timestep="0.01" gravity="0 0 0" integrator="Euler"/>'
EXT = '<extension><plugin plugin="drive_envelope.envelope"/></extension>'
BODY = (
    '<worldbody><body><joint name="j" type="{joint}" axis="0 0 1"/>'
    '<inertial pos="0 0 0" mass="2" diaginertia="0.5 0.5 0.5"/></body></worldbody>'
)
# max_effort max_actuator_velocity velocity_dependent_resistance speed_effort_gradient stiffness damping
DYNPRM = "10 3 1 0.05 100 5"


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


def _xml(dynprm: str = DYNPRM, *, joint: str = "hinge", extra: str = "", config: str = "") -> str:
    plugin = f'<plugin name="a" joint="j" plugin="drive_envelope.envelope" dynprm="{dynprm}" {extra}>'
    plugin += f"{config}</plugin>"
    return HEAD + EXT + BODY.format(joint=joint) + f"<actuator>{plugin}</actuator></mujoco>"


def test_first_step_effort_is_reduced_by_resistance(mujoco: Any) -> None:
    """Start from rest at maxEffort/(1 + r*R*dt), as real PhysX does."""
    model = mujoco.MjModel.from_xml_string(_xml())
    data = mujoco.MjData(model)
    data.ctrl[0] = 2.0
    mujoco.mj_step(model, data)
    r, resistance, dt = 1 / 0.5, 1.0, 0.01
    assert data.actuator_force[0] == pytest.approx(10.0 / (1 + r * resistance * dt), rel=1e-12)


@pytest.mark.parametrize("joint", ["hinge", "slide"])
def test_envelope_holds_and_velocity_settles_on_max(mujoco: Any, joint: str) -> None:
    """Keep every operating point inside the envelope and settle exactly on max_actuator_velocity."""
    # damping-only drive toward 10 rad/s (or m/s), beyond the envelope: a velocity drive
    model = mujoco.MjModel.from_xml_string(
        _xml("10 3 1 0 0 5", joint=joint, config='<config key="input" value="vel"/>')
    )
    data = mujoco.MjData(model)
    data.ctrl[0] = 10.0
    env = PerformanceEnvelope(
        max_effort=10.0,
        max_actuator_velocity=3.0,
        velocity_dependent_resistance=1.0,
        joint="revolute" if joint == "hinge" else "prismatic",
    )
    points = []
    for _ in range(300):
        mujoco.mj_step(model, data)
        points.append((data.qvel[0], data.actuator_force[0]))
    velocity, effort = np.array(points).T
    assert env.contains(velocity, effort, atol=1e-9).all()
    assert velocity[-1] == pytest.approx(3.0, abs=1e-12)


def test_braking_effort_shrinks_with_speed(mujoco: Any) -> None:
    """Brake with at most tau_max - R*|v| when the effort opposes the velocity (no speed limit: -1)."""
    model = mujoco.MjModel.from_xml_string(_xml("10 -1 1 0 100 5"))
    data = mujoco.MjData(model)
    data.qvel[0] = 5.0
    data.ctrl[0] = 0.0  # target 0 while moving at +5: full braking
    mujoco.mj_step(model, data)
    v1, effort = data.qvel[0], data.actuator_force[0]
    assert effort < 0
    assert abs(effort) == pytest.approx(10.0 - 1.0 * abs(v1), rel=1e-9)


def test_over_speed_releases_the_drive_as_physx_does(mujoco: Any) -> None:
    """Give zero effort when the joint already moves past max_actuator_velocity (it coasts)."""
    model = mujoco.MjModel.from_xml_string(_xml("10 3 0 0 100 5"))
    data = mujoco.MjData(model)
    data.qvel[0] = 20.0  # pushed far past 3 rad/s; one step of 10 N*m braking cannot bring it back
    data.ctrl[0] = 0.0
    mujoco.mj_step(model, data)
    assert data.actuator_force[0] == 0.0
    assert data.qvel[0] == pytest.approx(20.0)


def test_matches_core_functions_on_a_two_link_arm_with_gravity(mujoco: Any) -> None:
    """Compute the effort from diag(M^-1) and the smooth forces exactly as the core functions do."""
    # one explicit instance, two actuators on j2: the pos and ff inputs
    xml = (
        '<mujoco><option timestep="0.005" integrator="Euler"/>'
        '<extension><plugin plugin="drive_envelope.envelope"><instance name="d2">'
        '<config key="input" value="pos ff"/>'
        "</instance></plugin></extension><worldbody>"
        '<body pos="0 0 1"><joint name="j1" axis="0 1 0"/>'
        '<geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>'
        '<body pos="0.4 0 0"><joint name="j2" axis="0 1 0"/>'
        '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>'
        "</body></body></worldbody><actuator>"
        '<plugin name="a2" joint="j2" instance="d2" dynprm="3 -1 0.2 0 40 2"/>'
        '<plugin name="a2_ff" joint="j2" instance="d2"/>'
        "</actuator></mujoco>"
    )
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qpos[:] = [0.3, -0.5]
    data.qvel[:] = [1.0, -2.0]
    data.ctrl[:] = [0.7, 0.4]  # target position, feed-forward effort
    data.qfrc_applied[:] = [0.1, -0.2]
    data.xfrc_applied[2] = [0.0, 0.0, 1.5, 0.0, 0.3, 0.0]
    mujoco.mj_forward(model, data)

    dense = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, dense)
    inverse = np.linalg.inv(dense)
    xfrc = np.zeros(model.nv)
    mujoco.mj_applyFT(model, data, data.xfrc_applied[2, :3], data.xfrc_applied[2, 3:], data.xipos[2], 2, xfrc)
    smooth = data.qfrc_passive - data.qfrc_bias + data.qfrc_applied + xfrc
    dt, ff, dof = model.opt.timestep, 0.4, 1
    r = inverse[dof, dof]
    v0 = data.qvel[dof] + dt * (inverse @ smooth)[dof] + dt * r * ff
    drive = implicit_drive_effort(
        stiffness=40.0, damping=2.0, position_error=0.7 - data.qpos[dof], velocity=v0,
        target_velocity=0.0, response=r, dt=dt,
    )  # fmt: skip
    env = PerformanceEnvelope(max_effort=3.0, velocity_dependent_resistance=0.2)
    expected = clamp_effort_implicit(env, ff + drive, v0, r, dt, applied_effort=ff)
    assert data.actuator_force[0] == pytest.approx(float(expected), rel=1e-10, abs=1e-12)
    assert data.actuator_force[1] == 0.0  # the ff channel carries no force of its own


def test_feed_forward_alone_equals_a_native_motor(mujoco: Any) -> None:
    """Twin test: with zero gains and no limit the plugin's ff input is a native motor actuator."""
    body = (
        '<body pos="{x} 0 1"><joint name="{j}" axis="0 1 0"/>'
        '<geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/></body>'
    )
    xml = (
        '<mujoco><option timestep="0.002"/>' + EXT + "<worldbody>"
        + body.format(x=0, j="a") + body.format(x=2, j="b") + "</worldbody><actuator>"
        '<plugin name="p" joint="a" plugin="drive_envelope.envelope" dynprm="-1 -1 0 0 0 0">'
        '<config key="input" value="ff"/></plugin><motor name="m" joint="b"/></actuator></mujoco>'
    )  # fmt: skip
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    for i in range(200):
        data.ctrl[:] = math.sin(0.05 * i) * 3.0
        mujoco.mj_step(model, data)
    # equal up to the rounding of (effort*dt)/dt inside the clamp
    assert data.qpos[0] == pytest.approx(data.qpos[1], rel=1e-12)
    assert data.qvel[0] == pytest.approx(data.qvel[1], rel=1e-12)


@pytest.mark.parametrize(
    ("dynprm", "message"),
    [
        ("-2 3 1 0 100 5", "dynprm[0] (max_effort) = -2: expected a number in [0, 1e12] or -1 (no limit)"),
        ("10 nan 1 0 100 5", "dynprm[1] (max_actuator_velocity) = nan"),
        ("10 inf 1 0 100 5", "dynprm[1] (max_actuator_velocity) = inf"),
        (
            "10 3 -1 0 100 5",
            "dynprm[2] (velocity_dependent_resistance) = -1: expected a number in [0, 1e12] [",
        ),
        ("10 3 1 -0.1 100 5", "dynprm[3] (speed_effort_gradient) = -0.1: expected"),
        ("1e308 3 1 0 1e308 5", "dynprm[0] (max_effort) = 1e+308: expected a number in [0, 1e12]"),
        ("10 3 1 0 2e12 5", "dynprm[4] (stiffness) = 2000000000000"),
        ("10 3 1 0 100 -1", "dynprm[5] (damping) = -1"),
        ("10 3 1 0 100 5 0 1", "dynprm[7] = 1: reserved, expected 0"),
        ("1 0 0 0 0 0", "dynprm is MuJoCo's default (1 0 0 0 0 0): give the drive's numbers"),
    ],
)
def test_bad_numbers_fail_compilation_naming_actuator_and_slot(
    mujoco: Any, dynprm: str, message: str
) -> None:
    """Refuse negative, NaN, infinite, too large (> 1e12), reserved and forgotten numbers at compile time."""
    with pytest.raises(ValueError, match=r"drive_envelope\.envelope: actuator 'a'") as info:
        mujoco.MjModel.from_xml_string(_xml(dynprm))
    assert message in str(info.value)


def test_an_actuator_without_dynprm_is_refused(mujoco: Any) -> None:
    """Name the forgotten numbers: MuJoCo's default dynprm (1 0 ...) is never taken as a drive."""
    xml = (
        HEAD
        + EXT
        + BODY.format(joint="hinge")
        + ('<actuator><plugin name="a" joint="j" plugin="drive_envelope.envelope"/></actuator></mujoco>')
    )
    with pytest.raises(ValueError, match="dynprm is MuJoCo's default"):
        mujoco.MjModel.from_xml_string(xml)


def test_numbers_in_config_are_unknown_attributes(mujoco: Any) -> None:
    """A drive's numbers are its actuator's dynprm; as a <config> key MuJoCo refuses them."""
    config = '<config key="max_effort" value="10"/>'
    with pytest.raises(ValueError, match="unrecognized attribute 'plugin:max_effort'"):
        mujoco.MjModel.from_xml_string(_xml(config=config))


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ('<config key="drive_type" value="torque"/>', "attribute 'drive_type' = 'torque'"),
        ('<config key="input" value="pos pos"/>', "attribute 'input' = 'pos pos'"),
        ('<config key="input" value="pos vel"/>', "has 1 actuator(s) of this instance, expected 2"),
    ],
)
def test_bad_config_fails_compilation(mujoco: Any, config: str, message: str) -> None:
    """Refuse a bad drive type, repeated inputs and the wrong number of actuators for 'input'."""
    with pytest.raises(ValueError, match=re.escape(message)):
        mujoco.MjModel.from_xml_string(_xml(config=config))


@pytest.mark.parametrize(
    ("joint", "extra", "message"),
    [
        ("ball", "", "is a ball joint"),
        ("free", "", "is a free joint"),
        ("hinge", 'gear="2"', "'gear' must be 1"),
        ("hinge", 'forcerange="-1 1"', "'forcerange' must not be set"),
    ],
)
def test_unsupported_transmission_fails_compilation(
    mujoco: Any, joint: str, extra: str, message: str
) -> None:
    """Refuse ball and free joints, a gear and a forcerange on the plugin's actuators."""
    xml = _xml(joint=joint, extra=extra)
    if joint == "free":
        xml = xml.replace('<joint name="j" type="free" axis="0 0 1"/>', '<freejoint name="j"/>')
    with pytest.raises(ValueError, match=message):
        mujoco.MjModel.from_xml_string(xml)


@pytest.mark.parametrize("timestep", ["-0.002", "0"])
def test_a_timestep_that_is_not_positive_fails_compilation(mujoco: Any, timestep: str) -> None:
    """Refuse timestep <= 0 (a negative one gave 1.7e7 N*m against a 3.3 N*m cap)."""
    xml = _xml().replace('timestep="0.01"', f'timestep="{timestep}"')
    with pytest.raises(
        ValueError, match=r"option 'timestep' = -?0(\.002)?: expected a finite number > 0 \[s\]"
    ):
        mujoco.MjModel.from_xml_string(xml)


@pytest.mark.parametrize("velocity", [math.nan, math.inf, -1e300, 1e300])
def test_nan_or_huge_velocity_never_gives_nan_force(mujoco: Any, velocity: float) -> None:
    """Write a finite effort (0: the drive lets go) for NaN, infinite or huge joint velocities."""
    model = mujoco.MjModel.from_xml_string(_xml())
    data = mujoco.MjData(model)
    data.ctrl[0] = 1.0
    data.qvel[0] = velocity
    mujoco.mj_forward(model, data)
    assert np.isfinite(data.actuator_force).all()
    assert abs(data.actuator_force[0]) <= 10.0


def test_nan_control_never_gives_nan_force(mujoco: Any) -> None:
    """Write a finite effort when the target is NaN."""
    model = mujoco.MjModel.from_xml_string(_xml())
    data = mujoco.MjData(model)
    data.ctrl[0] = math.nan
    mujoco.mj_forward(model, data)
    assert np.isfinite(data.actuator_force).all()


def test_load_plugin_is_idempotent(mujoco: Any) -> None:
    """Return the same library path on every call without loading it again."""
    from drive_envelope.mujoco import load_plugin

    assert load_plugin() == load_plugin()


def test_missing_build_names_the_build_command(mujoco: Any, tmp_path: Path) -> None:
    """Raise a PluginError naming the build command when the library is absent."""
    from drive_envelope.mujoco import BUILD_COMMAND, PluginError, load_plugin

    with pytest.raises(PluginError, match="not built") as info:
        load_plugin(tmp_path / "libdrive_envelope_mujoco.so")
    assert BUILD_COMMAND in str(info.value)
    assert isinstance(info.value, DriveEnvelopeError)


def test_stale_build_for_another_mujoco_is_refused(mujoco: Any, tmp_path: Path) -> None:
    """Refuse a library built for another MuJoCo version before loading it."""
    from drive_envelope.mujoco import PluginError, load_plugin, plugin_library_path

    copy = tmp_path / "libdrive_envelope_mujoco.so"
    shutil.copy(plugin_library_path(), copy)
    (tmp_path / "build-info.json").write_text(json.dumps({"mujoco_version": "3.1.0"}))
    with pytest.raises(PluginError, match=r"built for MuJoCo 3\.1\.0 but MuJoCo .* is installed; rebuild"):
        load_plugin(copy)

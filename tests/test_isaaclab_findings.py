"""Issue 23 item 13 on Isaac Lab 2.3 (the PyPI wheel's source tree, see tests/conftest.py).

Each case is the finding's own: a partial effort-limit dict with a datasheet, ``env_ids =
slice(None)``, a partial ``effort_limit_sim`` dict, an explicit cfg given to the implicit check, a
string ``joint_names_expr``, ``effort_limit="23.5 N*m"``, float64 actions and a speed limit above the
envelope's. The same cases on Isaac Lab 3.0: tests/isaaclab3.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

pytestmark = [
    pytest.mark.isaaclab,
    pytest.mark.torch,
    pytest.mark.filterwarnings("ignore:`torch.jit.script` is deprecated:FutureWarning"),
]

JOINTS = [
    "FL_hip_joint",
    "FL_thigh_joint",
    "FL_calf_joint",
    "FR_hip_joint",
    "FR_thigh_joint",
    "FR_calf_joint",
]


def _build(num_envs: int = 2, **fields: Any) -> Any:
    """Build as Isaac Lab 2.3's Articulation does: the USD's max force 80 N*m, speed limit 100 rad/s."""
    import torch

    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg

    cfg = PerformanceEnvelopeActuatorCfg(
        **{"joint_names_expr": [".*"], "stiffness": 40.0, "damping": 2.0, "clip": "start_of_step", **fields}
    )
    shape = (num_envs, len(JOINTS))
    zeros = torch.zeros(shape)
    return cfg.class_type(
        cfg=cfg,
        joint_names=JOINTS,
        joint_ids=slice(None),
        num_envs=num_envs,
        device="cpu",
        stiffness=zeros,
        damping=zeros,
        armature=zeros,
        friction=zeros,
        dynamic_friction=zeros,
        viscous_friction=zeros,
        effort_limit=torch.full(shape, 80.0),
        velocity_limit=torch.full(shape, 100.0),
    )


def test_partial_effort_limit_dict_keeps_the_datasheets_value() -> None:
    """effort_limit={'.*_calf_joint': 30} with a datasheet: the hips and thighs get the datasheet's."""
    from drive_envelope.datasheet import resolve_envelope

    sheet = resolve_envelope("tmotor-ak80-6")
    actuator = _build(datasheet="tmotor-ak80-6", effort_limit={".*_calf_joint": 30.0})
    for column, name in enumerate(JOINTS):
        expected = 30.0 if "calf" in name else sheet.max_effort
        assert float(actuator.effort_limit[0, column]) == pytest.approx(expected)


def test_event_term_takes_slice_env_ids() -> None:
    """env_ids = slice(None), as EventManager.apply(mode='reset') passes without env_ids: every env."""
    from drive_envelope.isaaclab import randomize_actuator_envelope

    actuator = _build(num_envs=3, effort_limit=12.0, max_actuator_velocity=8.0)
    env = SimpleNamespace(scene={"robot": SimpleNamespace(actuators={"legs": actuator})})
    randomize_actuator_envelope(
        env,
        slice(None),
        SimpleNamespace(name="robot", joint_ids=slice(None)),
        max_effort_distribution_params=(0.5, 0.5),
    )
    assert bool((actuator.effort_limit == 6.0).all())


def test_check_implicit_actuator_findings() -> None:
    """A partial effort_limit_sim dict (maxForce 0), an explicit cfg, a string joint_names_expr."""
    from isaaclab.actuators import ActuatorNetMLPCfg, ImplicitActuatorCfg

    from drive_envelope.isaaclab import check_implicit_actuator

    envelopes = {
        "FL_calf_joint": de.PerformanceEnvelope(max_effort=45.43),
        "FL_hip_joint": de.PerformanceEnvelope(max_effort=23.7),
    }
    partial = ImplicitActuatorCfg(
        joint_names_expr=[".*"], stiffness=None, damping=None, effort_limit_sim={".*_calf_joint": 45.43}
    )
    assert check_implicit_actuator(partial, envelopes) == [
        "effort_limit_sim names no value for joint 'FL_hip_joint': Isaac Lab writes 0 as its max force, "
        "which turns the drive off (the envelope's max_effort is 23.7; name every joint, or leave it None)"
    ]
    explicit = ActuatorNetMLPCfg(
        joint_names_expr=[".*"],
        network_file="net.pt",
        pos_scale=1.0,
        vel_scale=1.0,
        torque_scale=1.0,
        input_order="pos_vel",
        input_idx=[0],
        effort_limit=80.0,
        saturation_effort=120.0,
        velocity_limit=8.5,
    )
    (line,) = check_implicit_actuator(explicit, envelopes)
    assert line.startswith("ActuatorNetMLPCfg is an explicit actuator") and "effort_limit" not in line
    with pytest.raises(InputError, match=r"joint_names_expr = '\.\*_calf_joint': a string"):
        check_implicit_actuator(SimpleNamespace(joint_names_expr=".*_calf_joint"), envelopes)


def test_effort_limit_with_units_is_read_or_one_line() -> None:
    """effort_limit='23.5 N*m' is 23.5 in SI; a wrong unit is one InputError naming the field."""
    assert bool((_build(effort_limit="23.5 N*m").effort_limit == 23.5).all())
    with pytest.raises(InputError, match=r"PerformanceEnvelopeActuatorCfg\.effort_limit: ") as info:
        _build(effort_limit="23.5 rpm")
    assert "\n" not in str(info.value)


def test_float64_actions_and_the_speed_limit_warning() -> None:
    """float64 targets: advice to set float32; velocity_limit above max_actuator_velocity: a warning."""
    import torch
    from isaaclab.utils.types import ArticulationActions

    actuator = _build(effort_limit=12.0)
    zeros = torch.zeros(2, len(JOINTS))
    action = ArticulationActions(joint_positions=zeros, joint_velocities=zeros, joint_efforts=zeros.double())
    with pytest.raises(InputError, match=r"joint_efforts are torch\.float64.*as torch\.float32"):
        actuator.compute(action, zeros, zeros)
    with pytest.warns(UserWarning, match=r"max_actuator_velocity 15\.7 is below velocity_limit 21"):
        _build(max_actuator_velocity=15.7, velocity_limit=21.0)

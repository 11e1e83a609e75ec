"""drive_envelope.isaaclab in Isaac Lab 3.0 (its PyPI wheel, ``isaaclab==3.0.0``): actuator, event, check.

These tests need Isaac Lab 3.x, which pins Python 3.12, torch 2.11 and newton 1.6.1: they run in
their own environment (``scripts/test_isaaclab3.sh``, part of ``make test``) and skip elsewhere
(the main ``.venv`` tests Isaac Lab 2.3). Isaac Lab's own code builds and steps everything; the
references are the float64 NumPy clamp (``drive_envelope.clamp_effort``), an independent
implementation, and Isaac Lab 3.0's own ``DCMotor``.
"""

from __future__ import annotations

import inspect
import math
import warnings
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

isaaclab_actuators = pytest.importorskip(
    "isaaclab.actuators", reason="needs Isaac Lab 3.x: scripts/test_isaaclab3.sh"
)
if not hasattr(isaaclab_actuators, "ActuatorCollection"):
    pytest.skip("Isaac Lab 2.x here (tests/test_isaaclab_*.py test it)", allow_module_level=True)

import torch  # noqa: E402, TID253 - this folder runs only where Isaac Lab 3 (and torch) is installed

import drive_envelope as de  # noqa: E402
from drive_envelope.errors import InputError  # noqa: E402

NUM_ENVS, NUM_JOINTS = 4096, 12
JOINTS = [f"{leg}_{j}" for leg in ("LF", "LH", "RF", "RH") for j in ("HAA", "HFE", "KFE")]
ENVELOPE: dict[str, Any] = {
    "max_actuator_velocity": 8.0,
    "velocity_dependent_resistance": 0.3,
    "speed_effort_gradient": 0.5,
}


def _build(cfg: Any, num_envs: int = NUM_ENVS, **overrides: Any) -> Any:
    """Build the actuator with exactly the keywords Isaac Lab 3.0's IdealPDActuator.__init__ takes."""
    shape = (num_envs, len(JOINTS))
    given = {
        "cfg": cfg,
        "joint_names": JOINTS,
        "joint_ids": slice(None),
        "num_envs": num_envs,
        "device": "cpu",
        "stiffness": torch.full(shape, 3.0),
        "damping": torch.full(shape, 0.5),
        "actuator_effort_limit": torch.full(shape, 80.0),  # the USD's max force, as the collection passes it
        "actuator_velocity_limit": torch.full(shape, 100.0),
        "effort_limit": None,
        "velocity_limit": None,
        **overrides,
    }
    keywords = [
        p for p in inspect.signature(isaaclab_actuators.IdealPDActuator.__init__).parameters if p != "self"
    ]
    assert sorted(given) == sorted(keywords)  # every keyword 3.0 has, and no other
    return cfg.class_type(**given)


def _cfg(**fields: Any) -> Any:
    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg

    base = {"joint_names_expr": [".*"], "stiffness": 40.0, "damping": 2.0, "clip": "start_of_step"}
    return PerformanceEnvelopeActuatorCfg(**{**base, **fields})


def test_the_shim_reads_isaac_lab_3() -> None:
    """compat.api() tells 3.0 from the keywords of IdealPDActuator.__init__."""
    from drive_envelope._src.adapters.isaaclab import compat

    assert compat.api() is compat.ISAACLAB_3_0 and compat.api().effort_limit == "actuator_effort_limit"


def test_4096_envs_by_12_joints_step_inside_the_envelope_in_float32() -> None:
    """compute() on 4096 x 12: float32 (num_envs, joints) out, equal to the float64 clamp, no deprecation."""
    from isaaclab.utils.types import ArticulationActions

    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)  # 3.0's names only: no deprecated alias is used
        actuator = _build(_cfg(actuator_effort_limit=12.0, **ENVELOPE))
        rng = np.random.default_rng(7)
        shape = (NUM_ENVS, NUM_JOINTS)
        envelope = de.PerformanceEnvelope(max_effort=12.0, **ENVELOPE)
        for _ in range(3):
            targets = {
                k: torch.as_tensor(rng.normal(0.0, s, shape), dtype=torch.float32)
                for k, s in (("joint_positions", 0.5), ("joint_velocities", 2.0), ("joint_efforts", 3.0))
            }
            q = torch.as_tensor(rng.normal(0.0, 0.5, shape), dtype=torch.float32)
            v = torch.as_tensor(rng.normal(0.0, 6.0, shape), dtype=torch.float32)
            out = actuator.compute(ArticulationActions(**targets), q, v)
            effort = out.joint_efforts
            assert effort.dtype == torch.float32 and tuple(effort.shape) == shape
            assert out.joint_positions is None and out.joint_velocities is None
            pd = (
                40.0 * (targets["joint_positions"] - q)
                + 2.0 * (targets["joint_velocities"] - v)
                + targets["joint_efforts"]
            )
            limit = de.clamp_effort(envelope, np.full(shape, 1e9), v.numpy().astype(np.float64))
            assert bool((effort.abs().numpy() <= limit * (1 + 1e-6) + 1e-5).all())  # inside the envelope
            reference = de.clamp_effort(envelope, pd.numpy().astype(np.float64), v.numpy().astype(np.float64))
            np.testing.assert_allclose(effort.numpy(), reference, rtol=1e-5, atol=1e-4)
    assert (
        bool((actuator.actuator_effort_limit == 12.0).all())
        and actuator.max_effort is actuator.actuator_effort_limit
    )


def test_datasheet_and_a_partial_effort_dict_keep_the_datasheets_value() -> None:
    """actuator_effort_limit={'.*_KFE': 30} with a datasheet: the others get the datasheet's max_effort."""
    from drive_envelope.datasheet import resolve_envelope

    sheet = resolve_envelope("tmotor-ak80-6")
    actuator = _build(_cfg(datasheet="tmotor-ak80-6", actuator_effort_limit={".*_KFE": 30.0}), num_envs=2)
    for column, name in enumerate(JOINTS):
        expected = 30.0 if name.endswith("KFE") else sheet.max_effort
        assert float(actuator.actuator_effort_limit[0, column]) == pytest.approx(expected)
    assert float(actuator.max_actuator_velocity[0, 0]) == pytest.approx(sheet.max_actuator_velocity)


def test_limits_with_units_and_the_deprecated_alias() -> None:
    """'23.5 N*m' is read as SI; 3.0's deprecated effort_limit still lands in actuator_effort_limit."""
    actuator = _build(_cfg(actuator_effort_limit="23.5 N*m"), num_envs=2)
    assert bool((actuator.actuator_effort_limit == 23.5).all())
    with pytest.warns(DeprecationWarning, match="effort_limit"):
        old = _build(_cfg(effort_limit=7.0), num_envs=2)
    assert bool((old.actuator_effort_limit == 7.0).all())
    with pytest.raises(InputError, match=r"actuator_effort_limit: .*23\.5 rpm"):
        _build(_cfg(actuator_effort_limit="23.5 rpm"), num_envs=2)


def test_speed_limit_above_the_envelopes_is_warned() -> None:
    """actuator_velocity_limit above max_actuator_velocity never binds: one warning naming the joints."""
    with pytest.warns(UserWarning, match=r"max_actuator_velocity 8 is below actuator_velocity_limit 20"):
        _build(_cfg(actuator_velocity_limit=20.0, **ENVELOPE), num_envs=2)


def test_equals_isaac_lab_3_dc_motor_when_driving() -> None:
    """Isaac Lab 3.0's DCMotor and the envelope with G = v_lim/sat agree in the driving quadrants."""
    from isaaclab.actuators import DCMotorCfg
    from isaaclab.utils.types import ArticulationActions

    sat, v_lim, cap = 40.0, 10.0, 25.0
    dc = _build(
        DCMotorCfg(
            joint_names_expr=[".*"],
            stiffness=0.0,
            damping=0.0,
            saturation_effort=sat,
            actuator_velocity_limit=v_lim,
            actuator_effort_limit=cap,
        ),
        num_envs=200,
    )
    ours = _build(
        _cfg(
            stiffness=0.0,
            damping=0.0,
            actuator_effort_limit=cap,
            max_actuator_velocity=v_lim,
            speed_effort_gradient=v_lim / sat,
        ),
        num_envs=200,
    )
    v = torch.linspace(-9.9, 9.9, 200)[:, None].expand(200, NUM_JOINTS).contiguous()
    zeros = torch.zeros_like(v)

    def step(actuator: Any) -> Any:
        action = ArticulationActions(
            joint_positions=zeros.clone(),
            joint_velocities=zeros.clone(),
            joint_efforts=1000.0 * torch.sign(v),
        )
        return actuator.compute(action, zeros, v).joint_efforts

    np.testing.assert_allclose(step(ours).numpy(), step(dc).numpy(), rtol=1e-6, atol=1e-5)


def test_event_term_writes_actuator_effort_limit_for_slice_env_ids() -> None:
    """randomize_actuator_envelope with env_ids = slice(None) (as EventManager passes) scales 3.0 tensors."""
    from drive_envelope.isaaclab import randomize_actuator_envelope

    actuator = _build(_cfg(actuator_effort_limit=12.0, **ENVELOPE), num_envs=3)
    env = SimpleNamespace(scene={"robot": SimpleNamespace(actuators={"legs": actuator})})
    randomize_actuator_envelope(
        env,
        slice(None),
        SimpleNamespace(name="robot", joint_ids=[2, 5]),
        max_effort_distribution_params=(0.5, 0.5),
    )
    row = actuator.actuator_effort_limit[1].tolist()
    assert row == pytest.approx([12.0, 12.0, 6.0, 12.0, 12.0, 6.0] + [12.0] * 6)


def test_check_implicit_reads_3_0s_joint_effort_limit() -> None:
    """A 3.0 ImplicitActuatorCfg: joint_effort_limit vs maxEffort, a partial dict writes 0, explicit cfgs."""
    from isaaclab.actuators import IdealPDActuatorCfg, ImplicitActuatorCfg

    from drive_envelope.isaaclab import check_implicit_actuator

    envelopes = {
        "LF_KFE": de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=8.0),
        "LF_HAA": de.PerformanceEnvelope(max_effort=12.0),
    }
    same = ImplicitActuatorCfg(joint_names_expr=[".*"], stiffness=None, damping=None, joint_effort_limit=12.0)
    assert check_implicit_actuator(same, envelopes) == []
    partial = ImplicitActuatorCfg(
        joint_names_expr=[".*"],
        stiffness=None,
        damping=None,
        joint_effort_limit={".*_KFE": 12.0},
        joint_velocity_limit=5.0,
    )
    problems = check_implicit_actuator(partial, envelopes)
    assert any("joint_effort_limit names no value for joint 'LF_HAA'" in p for p in problems)
    assert any("joint_velocity_limit = 5 for joint 'LF_KFE'" in p for p in problems)
    explicit = IdealPDActuatorCfg(joint_names_expr=[".*"], stiffness=1.0, damping=1.0)
    assert len(check_implicit_actuator(explicit, envelopes)) == 1
    assert "explicit actuator" in check_implicit_actuator(explicit, envelopes)[0]
    with pytest.raises(InputError, match=r"joint_names_expr = '\.\*_KFE': a string"):
        check_implicit_actuator(SimpleNamespace(joint_names_expr=".*_KFE"), envelopes)


def test_float64_actions_get_advice_an_actuator_user_can_follow() -> None:
    """float64 targets: one line saying to set them as float32."""
    from isaaclab.utils.types import ArticulationActions

    actuator = _build(_cfg(actuator_effort_limit=12.0), num_envs=2)
    zeros = torch.zeros(2, NUM_JOINTS)
    action = ArticulationActions(joint_positions=zeros.double(), joint_velocities=zeros, joint_efforts=zeros)
    with pytest.raises(
        InputError, match=r"joint_positions are torch\.float64.*set the targets as torch\.float32"
    ):
        actuator.compute(action, zeros, zeros)
    assert math.isfinite(float(actuator.actuator_effort_limit[0, 0]))

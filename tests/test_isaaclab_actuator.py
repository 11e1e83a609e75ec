"""``PerformanceEnvelopeActuator`` inside Isaac Lab's own actuator machinery (the real ``isaaclab`` package).

Isaac Lab is tested from its PyPI wheel (2.3.2.post1, installed ``--no-deps`` with ``toml`` and
``trimesh``): ``tests/conftest.py`` puts the wheel's source tree first on ``sys.path`` and, for the
tests marked ``isaaclab`` only, stands in for the two Isaac Sim modules ``isaaclab.utils.assets``
imports at load time (``carb``, ``omni.client``). Everything else is Isaac Lab's code: its
``configclass``, ``ActuatorBase`` parsing, ``IdealPDActuator``, ``DCMotor`` and
``ArticulationActions``.

:class:`_Articulation` does what Isaac Lab's ``Articulation`` does with actuators, line by line from
``isaaclab/assets/articulation/articulation.py`` (2.3.2): ``_process_actuators_cfg`` builds each
actuator with the simulation's per-joint defaults as ``(num_envs, num_joints)`` tensors, and
``_apply_actuator_model`` steps them with ``ArticulationActions``. No simulator runs: the references
are the float64 NumPy clamp (``drive_envelope.clamp_effort``) and Isaac Lab's own ``DCMotor``.
"""

from __future__ import annotations

import math
import subprocess
import sys
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

pytestmark = [
    pytest.mark.isaaclab,
    pytest.mark.torch,
    # isaaclab.utils.math (Isaac Lab's samplers) still decorates with torch.jit.script
    pytest.mark.filterwarnings("ignore:`torch.jit.script` is deprecated:FutureWarning"),
]

JOINTS = ["LF_HAA", "LF_HFE", "LF_KFE", "RF_HAA", "RF_HFE", "RF_KFE"]
NUM_ENVS = 5


class _Articulation:
    """Isaac Lab's ``Articulation`` actuator handling on tensors (no PhysX view behind it)."""

    def __init__(
        self, actuators: dict[str, Any], *, num_envs: int = NUM_ENVS, effort_limit: float = 80.0
    ) -> None:
        import isaaclab.utils.string as string_utils
        import torch
        from isaaclab.actuators import ImplicitActuator

        self.joint_names, self.num_envs, self.device = JOINTS, num_envs, "cpu"
        shape = (num_envs, len(JOINTS))
        # what the PhysX view reports from the USD (get_dof_stiffnesses, get_dof_max_forces, ...)
        self.default_joint_stiffness = torch.full(shape, 3.0)
        self.default_joint_damping = torch.full(shape, 0.5)
        self.joint_effort_limits = torch.full(shape, effort_limit)
        self.joint_vel_limits = torch.full(shape, 100.0)
        self.joint_pos_target = torch.zeros(shape)
        self.joint_vel_target = torch.zeros(shape)
        self.joint_effort_target = torch.zeros(shape)
        self.joint_effort_target_sim = torch.zeros(shape)
        self.computed_torque, self.applied_torque = torch.zeros(shape), torch.zeros(shape)
        self.sim_stiffness = {}
        self.actuators = {}
        for name, cfg in actuators.items():  # _process_actuators_cfg
            joint_ids, joint_names = string_utils.resolve_matching_names(
                cfg.joint_names_expr, self.joint_names
            )
            joint_ids = slice(None) if len(joint_names) == len(JOINTS) else torch.tensor(joint_ids)
            actuator = cfg.class_type(
                cfg=cfg,
                joint_names=joint_names,
                joint_ids=joint_ids,
                num_envs=num_envs,
                device=self.device,
                stiffness=self.default_joint_stiffness[:, joint_ids],
                damping=self.default_joint_damping[:, joint_ids],
                armature=torch.zeros(shape)[:, joint_ids],
                friction=torch.zeros(shape)[:, joint_ids],
                dynamic_friction=torch.zeros(shape)[:, joint_ids],
                viscous_friction=torch.zeros(shape)[:, joint_ids],
                effort_limit=self.joint_effort_limits[:, joint_ids].clone(),
                velocity_limit=self.joint_vel_limits[:, joint_ids],
            )
            self.actuators[name] = actuator
            # explicit actuators: the simulation's drive gains go to 0 (write_joint_stiffness_to_sim)
            self.sim_stiffness[name] = actuator.stiffness if isinstance(actuator, ImplicitActuator) else 0.0

    def apply_actuator_model(self, joint_pos: Any, joint_vel: Any) -> None:
        """``Articulation._apply_actuator_model``: each group computes, the sim buffers are filled."""
        from isaaclab.utils.types import ArticulationActions

        for actuator in self.actuators.values():
            ids = actuator.joint_indices
            action = ArticulationActions(
                joint_positions=self.joint_pos_target[:, ids],
                joint_velocities=self.joint_vel_target[:, ids],
                joint_efforts=self.joint_effort_target[:, ids],
                joint_indices=ids,
            )
            action = actuator.compute(action, joint_pos=joint_pos[:, ids], joint_vel=joint_vel[:, ids])
            assert action.joint_positions is None and action.joint_velocities is None  # explicit
            self.joint_effort_target_sim[:, ids] = action.joint_efforts
            self.computed_torque[:, ids] = actuator.computed_effort
            self.applied_torque[:, ids] = actuator.applied_effort


def _cfg(**fields: Any) -> Any:
    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg

    base = {"joint_names_expr": [".*"], "stiffness": 40.0, "damping": 2.0}
    return PerformanceEnvelopeActuatorCfg(**{**base, **fields})


def test_cfg_is_an_isaac_lab_configclass_naming_its_actuator() -> None:
    """Subclass IdealPDActuatorCfg with class_type = PerformanceEnvelopeActuator, like Isaac Lab's cfgs."""
    from isaaclab.actuators import IdealPDActuator, IdealPDActuatorCfg

    from drive_envelope.isaaclab import PerformanceEnvelopeActuator

    cfg = _cfg(max_actuator_velocity="300 rpm")
    assert isinstance(cfg, IdealPDActuatorCfg) and cfg.class_type is PerformanceEnvelopeActuator
    assert issubclass(PerformanceEnvelopeActuator, IdealPDActuator)
    copied = cfg.copy()  # configclass's own utilities work on it
    assert copied.max_actuator_velocity == "300 rpm" and copied.to_dict()["datasheet"] is None


def test_built_as_the_articulation_builds_it_with_per_env_tensors() -> None:
    """Parse floats, units, regex dicts and datasheets into (num_envs, num_joints) tensors, in order."""
    cfg = _cfg(
        datasheet={".*_HAA": "tmotor-ak80-6", ".*_HFE": "cubemars-ak80-9-v3"},
        max_actuator_velocity={".*_HFE": "300 rpm"},  # replaces the datasheet's on the HFE joints
        speed_effort_gradient=0.25,  # replaces every datasheet's
    )
    actuator = _Articulation({"legs": cfg}).actuators["legs"]
    from drive_envelope.datasheet import resolve_envelope

    ak80_6, ak80_9 = resolve_envelope("tmotor-ak80-6"), resolve_envelope("cubemars-ak80-9-v3")
    column = {name: k for k, name in enumerate(actuator.joint_names)}
    for name in ("LF_HAA", "RF_HAA"):
        assert actuator.effort_limit[0, column[name]] == pytest.approx(ak80_6.max_effort)
        assert actuator.max_actuator_velocity[0, column[name]] == pytest.approx(ak80_6.max_actuator_velocity)
    for name in ("LF_HFE", "RF_HFE"):
        assert actuator.effort_limit[0, column[name]] == pytest.approx(ak80_9.max_effort)
        assert actuator.max_actuator_velocity[0, column[name]] == pytest.approx(10.0 * math.pi)
    for name in ("LF_KFE", "RF_KFE"):  # no datasheet: Isaac Lab's effort limit (the USD's), no speed limit
        assert actuator.effort_limit[0, column[name]] == 80.0
        assert math.isinf(actuator.max_actuator_velocity[0, column[name]])
    for attribute in (
        "effort_limit",
        "max_actuator_velocity",
        "velocity_dependent_resistance",
        "speed_effort_gradient",
    ):
        tensor = getattr(actuator, attribute)
        assert tuple(tensor.shape) == (NUM_ENVS, len(JOINTS))
        assert bool((getattr(actuator, f"default_{attribute}") == tensor).all())
    assert bool((actuator.speed_effort_gradient == 0.25).all())
    assert bool((actuator.stiffness == 40.0).all())  # the cfg's gains replace the USD's (3.0)


def test_compute_fills_efforts_like_isaac_lab_and_clips_by_the_envelope() -> None:
    """Step as _apply_actuator_model does: computed = PD law, applied = the core clamp at the velocity."""
    import torch

    envelope: dict[str, Any] = {
        "max_actuator_velocity": 8.0,
        "velocity_dependent_resistance": 0.3,
        "speed_effort_gradient": 0.5,
    }
    articulation = _Articulation({"legs": _cfg(effort_limit=12.0, clip="start_of_step", **envelope)})
    rng = np.random.default_rng(3)
    shape = (NUM_ENVS, len(JOINTS))
    articulation.joint_pos_target[:] = torch.as_tensor(rng.normal(0.0, 0.5, shape), dtype=torch.float32)
    articulation.joint_vel_target[:] = torch.as_tensor(rng.normal(0.0, 2.0, shape), dtype=torch.float32)
    articulation.joint_effort_target[:] = torch.as_tensor(rng.normal(0.0, 3.0, shape), dtype=torch.float32)
    q = torch.as_tensor(rng.normal(0.0, 0.5, shape), dtype=torch.float32)
    v = torch.as_tensor(rng.normal(0.0, 6.0, shape), dtype=torch.float32)
    articulation.apply_actuator_model(q, v)
    pd = (
        40.0 * (articulation.joint_pos_target - q)
        + 2.0 * (articulation.joint_vel_target - v)
        + articulation.joint_effort_target
    )
    np.testing.assert_allclose(articulation.computed_torque.numpy(), pd.numpy(), rtol=1e-6, atol=1e-5)
    reference = de.clamp_effort(
        de.PerformanceEnvelope(max_effort=12.0, **envelope),
        pd.numpy().astype(np.float64),
        v.numpy().astype(np.float64),
    )
    np.testing.assert_allclose(articulation.applied_torque.numpy(), reference, rtol=1e-5, atol=1e-5)
    np.testing.assert_array_equal(
        articulation.joint_effort_target_sim.numpy(), articulation.applied_torque.numpy()
    )
    assert articulation.sim_stiffness["legs"] == 0.0  # an explicit actuator: PhysX's drive gains are 0


def test_envelope_follows_in_place_edits_and_replaced_tensors() -> None:
    """The clip's envelope is cached, so both ways a user changes it must reach the next compute()."""
    import torch

    articulation = _Articulation({"legs": _cfg(effort_limit=12.0, clip="start_of_step")})
    actuator = articulation.actuators["legs"]
    shape = (NUM_ENVS, len(JOINTS))
    q, v = torch.zeros(shape), torch.full(shape, 4.0)
    articulation.joint_pos_target[:] = 10.0  # the PD law asks 400 N*m: every joint at its limit
    assert actuator.envelope is actuator.envelope  # one object while nothing changes
    articulation.apply_actuator_model(q, v)
    np.testing.assert_array_equal(articulation.applied_torque.numpy(), 12.0)
    actuator.velocity_dependent_resistance[:] = 0.5  # in place, as the randomization event writes
    articulation.apply_actuator_model(q, v)
    np.testing.assert_allclose(articulation.applied_torque.numpy(), 12.0 - 0.5 * 4.0)
    actuator.max_actuator_velocity = torch.full(shape, 5.0)  # new tensors: the speed line 5 - 0.25*tau
    actuator.speed_effort_gradient = torch.full(shape, 0.25)  # at v = 4 it allows tau <= 4
    articulation.apply_actuator_model(q, v)
    np.testing.assert_allclose(articulation.applied_torque.numpy(), 4.0)
    assert actuator.envelope.speed_effort_gradient is actuator.speed_effort_gradient


def test_two_groups_on_joint_subsets_index_their_own_columns() -> None:
    """Build two groups on disjoint joints (tensor joint_ids) and clip each with its own envelope."""
    import torch

    articulation = _Articulation(
        {
            "hips": _cfg(
                joint_names_expr=[".*_HAA", ".*_HFE"],
                effort_limit=5.0,
                max_actuator_velocity=2.0,
                clip="start_of_step",
            ),
            "knees": _cfg(joint_names_expr=[".*_KFE"], effort_limit=30.0, clip="start_of_step"),
        }
    )
    knees = articulation.actuators["knees"]
    assert knees.joint_indices.tolist() == [2, 5]
    articulation.joint_effort_target[:] = 100.0
    for speed, hips in ((1.5, 5.0), (2.5, 0.0)):  # G = 0: the box up to the hips' 2 rad/s, nothing above
        v = torch.full((NUM_ENVS, len(JOINTS)), speed)
        articulation.apply_actuator_model(torch.zeros_like(v), v)
        applied = articulation.applied_torque
        assert bool((applied[:, [2, 5]] == 30.0).all())  # knees: only their effort cap
        assert bool((applied[:, [0, 1, 3, 4]] == hips).all())


def test_equals_dc_motor_when_driving_and_allows_less_when_braking() -> None:
    """Agree with Isaac Lab's DCMotor when driving; brake less at speed and not at all above v_lim."""
    import torch
    from isaaclab.actuators import DCMotorCfg

    sat, v_lim, max_e = 40.0, 10.0, 25.0
    dc_cfg = DCMotorCfg(
        joint_names_expr=[".*"],
        stiffness=0.0,
        damping=0.0,
        saturation_effort=sat,
        velocity_limit=v_lim,
        effort_limit=max_e,
    )
    ours_cfg = _cfg(
        stiffness=0.0,
        damping=0.0,
        effort_limit=max_e,
        max_actuator_velocity=v_lim,
        speed_effort_gradient=v_lim / sat,
        clip="start_of_step",  # DCMotor's rule: the limit at the velocity the step starts from
    )
    articulation = _Articulation({"dc": dc_cfg}, num_envs=200)
    twin = _Articulation({"envelope": ours_cfg}, num_envs=200)
    velocity = torch.linspace(-9.9, 9.9, 200)[:, None].expand(200, len(JOINTS)).contiguous()
    for sign in (1.0, -1.0):  # along the motion (driving), then against it (braking)
        request = sign * 1000.0 * torch.sign(velocity)
        for stand in (articulation, twin):
            stand.joint_effort_target[:] = request
            stand.apply_actuator_model(torch.zeros_like(velocity), velocity)
        dc, ours = articulation.applied_torque, twin.applied_torque
        if sign > 0:
            np.testing.assert_allclose(ours.numpy(), dc.numpy(), rtol=1e-6, atol=1e-5)
        else:
            assert bool((dc.abs() == max_e).all())  # DCMotor brakes with the full cap at any speed
            corner = v_lim * (1.0 - max_e / sat)  # beyond it the envelope's speed line binds
            fast = velocity.abs() > corner + 1e-3
            assert bool((ours.abs() <= dc.abs() + 1e-6).all()) and bool(
                (ours.abs()[fast] < dc.abs()[fast]).all()
            )
    above = torch.full((1, len(JOINTS)), 12.0)  # past the speed limit, driven by something else
    for stand in (articulation, twin):
        stand.joint_effort_target[:] = -1000.0
        stand.apply_actuator_model(torch.zeros_like(above).expand(200, -1), above.expand(200, -1))
    assert bool((articulation.applied_torque == -max_e).all()) and bool((twin.applied_torque == 0.0).all())


def test_event_terms_write_the_envelope_per_environment() -> None:
    """Write envelope tensors per env as randomize_actuator_gains writes gains; the next compute uses them."""
    import torch

    from drive_envelope.isaaclab import randomize_actuator_envelope

    articulation = _Articulation(
        {
            "legs": _cfg(
                effort_limit=12.0, max_actuator_velocity=8.0, speed_effort_gradient=0.5, clip="start_of_step"
            )
        }
    )
    actuator = articulation.actuators["legs"]
    env_ids = torch.tensor([1, 3])
    actuator.speed_effort_gradient[env_ids] = 2.0  # what an event term does: in place, per env
    articulation.joint_effort_target[:] = 50.0
    v = torch.full((NUM_ENVS, len(JOINTS)), 4.0)
    articulation.apply_actuator_model(torch.zeros_like(v), v)
    limits = articulation.applied_torque[:, 0]
    assert limits.tolist() == pytest.approx([8.0, 2.0, 8.0, 2.0, 8.0])  # (8 - 4)/G
    # the event term: scale G by U(0.5, 0.5) on env 0 only, for the KFE joints of the asset cfg
    env = SimpleNamespace(scene={"robot": articulation})
    asset_cfg = SimpleNamespace(name="robot", joint_ids=[2, 5])
    randomize_actuator_envelope(
        env, torch.tensor([0]), asset_cfg, speed_effort_gradient_distribution_params=(0.5, 0.5)
    )
    assert actuator.speed_effort_gradient[0].tolist() == pytest.approx([0.5, 0.5, 0.25, 0.5, 0.5, 0.25])
    assert actuator.speed_effort_gradient[1].tolist() == pytest.approx([2.0] * 6)  # other envs untouched
    randomize_actuator_envelope(
        env,
        None,
        SimpleNamespace(name="robot", joint_ids=slice(None)),
        max_actuator_velocity_distribution_params=(-50.0, -50.0),
        operation="add",
    )
    assert bool((actuator.max_actuator_velocity == 0.0).all())  # clipped at 0, never negative
    with pytest.raises(InputError, match="operation = 'mul'"):
        randomize_actuator_envelope(env, None, asset_cfg, operation="mul")


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"speed_effort_gradient": -0.1}, r"speed_effort_gradient of joint 'LF_HAA' is -0\.1"),
        ({"max_actuator_velocity": "5 Hz"}, "angle"),
        ({"velocity_dependent_resistance": {"nope_.*": 1.0}}, r"velocity_dependent_resistance: .*nope_"),
        ({"datasheet": "no-such-motor"}, r"datasheet\['\.\*'\]"),
        ({"effort_limit": -1.0}, r"max_effort \(effort_limit\) of joint 'LF_HAA' is -1\.0"),
        ({"max_actuator_velocity": [1.0]}, "expected a number, a string with units"),
    ],
)
def test_bad_cfg_values_are_one_line_errors(fields: dict[str, Any], message: str) -> None:
    """Refuse bad envelope values with one InputError naming the cfg field and joint."""
    with pytest.raises(InputError, match=message):
        _Articulation({"legs": _cfg(**fields)})


def test_facade_import_is_light() -> None:
    """Import drive_envelope.isaaclab without Isaac Lab, torch or warp."""
    code = (
        "import sys, drive_envelope.isaaclab\n"
        "print(sorted(m for m in ('isaaclab', 'torch', 'warp') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


# -- the end-of-step clip (issue 22): PhysX's rule on the one-joint stand --------------------------

STAND_INERTIA, STAND_DT, STAND_STEPS = 0.05, 0.005, 600  # kg*m^2, s; from rest to a 1 rad target


def _stand_reference(envelope: Any, kp: float, kd: float, load: float) -> tuple[Any, Any]:
    """The stand stepped with the PD request clamped by the PhysX-exact clamp at the end-of-step velocity.

    PhysX integrates the load into the velocity before its solver clamps the drive (v0 below), then
    q1 = q0 + v1*dt (PGS). Returns the positions and velocities after each step.
    """
    q = v = 0.0
    qs, vs = [], []
    for _ in range(STAND_STEPS):
        request = kp * (1.0 - q) - kd * v
        v0 = v + STAND_DT * load / STAND_INERTIA
        impulse = de.clamp_drive_impulse(
            v0,
            0.0,
            request * STAND_DT,
            1.0 / STAND_INERTIA,
            envelope.max_actuator_velocity,
            envelope.max_effort * STAND_DT,
            envelope.speed_effort_gradient / STAND_DT,
            envelope.velocity_dependent_resistance * STAND_DT,
            physx_exact=True,
        )
        v = v0 + float(impulse) / STAND_INERTIA
        q += v * STAND_DT
        qs.append(q)
        vs.append(v)
    return np.array(qs), np.array(vs)


def _stand_actuator(source: str, kp: float, kd: float, load: float, clip: str) -> tuple[Any, Any]:
    """The stand with the real actuator: its applied effort plus the load moves the joint for one step."""
    import torch
    from isaaclab.utils.types import ArticulationActions

    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg

    cfg = PerformanceEnvelopeActuatorCfg(
        joint_names_expr=[".*"],
        stiffness=kp,
        damping=kd,
        datasheet=source,
        clip=clip,
        effective_inertia=STAND_INERTIA,
        physics_dt=STAND_DT,
    )
    one = torch.zeros((1, 1))
    actuator = cfg.class_type(
        cfg=cfg,
        joint_names=["joint"],
        joint_ids=slice(None),
        num_envs=1,
        device="cpu",
        stiffness=one,
        damping=one,
        armature=one,
        friction=one,
        dynamic_friction=one,
        viscous_friction=one,
        effort_limit=torch.full((1, 1), math.inf),
        velocity_limit=torch.full((1, 1), math.inf),
    )
    q = v = 0.0
    qs, vs = [], []
    for _ in range(STAND_STEPS):
        action = ArticulationActions(
            joint_positions=torch.ones((1, 1)),
            joint_velocities=torch.zeros((1, 1)),
            joint_efforts=torch.zeros((1, 1)),
        )
        out = actuator.compute(action, joint_pos=torch.tensor([[q]]), joint_vel=torch.tensor([[v]]))
        v += STAND_DT * (float(out.joint_efforts[0, 0]) + load) / STAND_INERTIA
        q += v * STAND_DT
        qs.append(q)
        vs.append(v)
    return np.array(qs), np.array(vs)


# gains that reach each speed line from rest (critically damped on 0.05 kg*m^2)
STANDS = [
    ("franka-panda-joint1-4", 80.0, 4.0),
    ("unitree-go2-calf", 400.0, 9.0),
    ("unitree-g1-7520-22", 400.0, 9.0),
]


@pytest.mark.parametrize(("source", "kp", "kd"), STANDS)
@pytest.mark.parametrize("load_share", [0.0, -0.2])
def test_end_of_step_clip_follows_physx_rule_on_the_stand(
    source: str, kp: float, kd: float, load_share: float
) -> None:
    """Follow the PhysX-exact clamp's trajectory to 0.05 rad, end at the PD rest, stay at the speed line.

    The load holds the joint back with a fifth of max_effort (a load along the motion makes PhysX's
    own drive let go above the line and run away: the reference itself leaves the stand then).
    """
    from drive_envelope.datasheet import resolve_envelope

    envelope = resolve_envelope(source)
    load = load_share * envelope.max_effort
    q_ref, v_ref = _stand_reference(envelope, kp, kd, load)
    q, v = _stand_actuator(source, kp, kd, load, "end_of_step")
    assert np.max(np.abs(q - q_ref)) <= 0.05
    assert abs(q[-1] - (1.0 + load / kp)) < 0.01  # the PD law's rest position under the load
    assert np.mean(np.abs(v) > 1.05 * envelope.max_actuator_velocity) <= 0.01
    assert np.max(np.abs(v_ref)) >= 0.999 * envelope.max_actuator_velocity  # the stand reaches the line


@pytest.mark.parametrize(("source", "kp", "kd"), STANDS)
def test_start_of_step_clip_runs_away_on_the_stand(source: str, kp: float, kd: float) -> None:
    """Keep today's clip by name: past the line after one step, it gives 0 and the joint runs away."""
    q, _ = _stand_actuator(source, kp, kd, 0.0, "start_of_step")
    assert q[-1] > 10.0


def test_end_of_step_clip_is_the_implicit_clamp_of_the_free_velocity() -> None:
    """Step 0 (rest) is cut to the effort that ends on the line; from above it, a braking request is whole."""
    import torch

    articulation = _Articulation(
        {
            "legs": _cfg(
                effort_limit=87.0, max_actuator_velocity=2.175, effective_inertia=0.05, physics_dt=0.005
            )
        },
        num_envs=1,
    )
    articulation.joint_pos_target[:] = 1.0
    zero = torch.zeros((1, len(JOINTS)))
    articulation.apply_actuator_model(zero, zero)
    # 40 N*m requested; the line at 2.175 rad/s after 5 ms on 0.05 kg*m^2 allows 2.175*0.05/0.005
    assert articulation.applied_torque[0].tolist() == pytest.approx([21.75] * 6, rel=1e-6)
    actuator = articulation.actuators["legs"]
    actuator.reset(slice(None))  # a reset forgets the last step: no velocity change is carried over
    articulation.joint_pos_target[:] = -1.0
    fast = torch.full((1, len(JOINTS)), 3.0)
    articulation.apply_actuator_model(zero, fast)
    # -40 - 2*3 = -46 N*m brings 3 rad/s to 3 - 46*0.1 = -1.6: inside, given whole
    assert articulation.applied_torque[0].tolist() == pytest.approx([-46.0] * 6, rel=1e-6)


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"clip": "implicit"}, r"clip = 'implicit'; expected one of 'end_of_step', 'start_of_step'"),
        ({"effective_inertia": -0.1}, r"effective_inertia: joint 'LF_HAA' is -0\.1"),
        ({"effective_inertia": {".*_KFE": 0.1}}, r"effective_inertia: joint 'LF_HAA' is not named"),
        ({"effective_inertia": "2 N*m"}, "effective_inertia"),
        ({"effective_inertia": 0.1, "physics_dt": 0.0}, r"physics_dt: got 0\.0"),
    ],
)
def test_bad_clip_fields_are_one_line_errors(fields: dict[str, Any], message: str) -> None:
    """Refuse a bad clip rule, effective inertia or time step with one line naming the field."""
    with pytest.raises(InputError, match=message):
        _Articulation({"legs": _cfg(**fields)})


def test_a_physics_dt_in_milliseconds_is_said() -> None:
    """physics_dt = 5 (meant 5 ms) steps 5 s: a warning says it is seconds and what 5 ms is."""
    with pytest.warns(UserWarning, match=r"physics_dt = 5 s is a very long physics step .* 5 ms is 0\.005$"):
        _Articulation({"legs": _cfg(effective_inertia=0.1, physics_dt=5)})


def test_end_of_step_without_a_response_says_what_to_set() -> None:
    """Without effective_inertia or a mass-matrix response, the first compute names the three ways."""
    import torch

    articulation = _Articulation({"legs": _cfg(physics_dt=0.005)})
    zero = torch.zeros((NUM_ENVS, len(JOINTS)))
    with pytest.raises(InputError, match=r"effective_inertia: not given.*clip='start_of_step'"):
        articulation.apply_actuator_model(zero, zero)


@pytest.mark.parametrize("floating", [False, True])
def test_response_from_the_mass_matrix_is_the_inverse_diagonal(floating: bool) -> None:
    """Write (M^-1)_ii at each actuator's joints: M = 3 blocks [[2, 1], [1, 1]] has inverse diagonal 1, 2."""
    import torch

    from drive_envelope.isaaclab import set_response_from_mass_matrix

    articulation = _Articulation(
        {
            "hips": _cfg(joint_names_expr=[".*_HAA", ".*_HFE"], physics_dt=0.005),
            "knees": _cfg(joint_names_expr=[".*_KFE"], physics_dt=0.005),
        }
    )
    block = torch.tensor([[2.0, 1.0], [1.0, 1.0]])
    joints = torch.block_diag(block, block, block)  # joint order LF_HAA, LF_HFE, LF_KFE, RF_HAA, ...
    matrix = torch.block_diag(torch.eye(6) * 4.0, joints) if floating else joints
    view = SimpleNamespace(get_generalized_mass_matrices=lambda: matrix.expand(NUM_ENVS, -1, -1).clone())
    vars(articulation).update(root_physx_view=view, num_joints=len(JOINTS))  # what PhysX's view gives
    set_response_from_mass_matrix(articulation)
    expected = [1.0, 2.0, 1.0, 2.0, 1.0, 2.0]
    hips, knees = articulation.actuators["hips"], articulation.actuators["knees"]
    assert hips.response[0].tolist() == pytest.approx([expected[i] for i in (0, 1, 3, 4)])
    assert knees.response[0].tolist() == pytest.approx([expected[i] for i in (2, 5)])
    assert hips.response_source == "mass_matrix"
    zero = torch.zeros((NUM_ENVS, len(JOINTS)))
    articulation.apply_actuator_model(zero, zero)  # the response is set: no error


GO2_JOINTS = [
    "FL_hip_joint",
    "FL_thigh_joint",
    "FL_calf_joint",
    "FR_hip_joint",
    "FR_thigh_joint",
    "FR_calf_joint",
]


def _build_go2(num_envs: int = 2, **fields: Any) -> Any:
    """Build as Isaac Lab 2.3's Articulation does: the USD's max force 80 N*m, speed limit 100 rad/s.

    For issue 23 item 13's cases, on Go2 joint names (the same cases on Isaac Lab 3.0: tests/isaaclab3).
    """
    import torch

    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg

    cfg = PerformanceEnvelopeActuatorCfg(
        **{"joint_names_expr": [".*"], "stiffness": 40.0, "damping": 2.0, "clip": "start_of_step", **fields}
    )
    shape = (num_envs, len(GO2_JOINTS))
    zeros = torch.zeros(shape)
    return cfg.class_type(
        cfg=cfg,
        joint_names=GO2_JOINTS,
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
    actuator = _build_go2(datasheet="tmotor-ak80-6", effort_limit={".*_calf_joint": 30.0})
    for column, name in enumerate(GO2_JOINTS):
        expected = 30.0 if "calf" in name else sheet.max_effort
        assert float(actuator.effort_limit[0, column]) == pytest.approx(expected)


def test_event_term_takes_slice_env_ids() -> None:
    """env_ids = slice(None), as EventManager.apply(mode='reset') passes without env_ids: every env."""
    from drive_envelope.isaaclab import randomize_actuator_envelope

    actuator = _build_go2(num_envs=3, effort_limit=12.0, max_actuator_velocity=8.0)
    env = SimpleNamespace(scene={"robot": SimpleNamespace(actuators={"legs": actuator})})
    randomize_actuator_envelope(
        env,
        slice(None),
        SimpleNamespace(name="robot", joint_ids=slice(None)),
        max_effort_distribution_params=(0.5, 0.5),
    )
    assert bool((actuator.effort_limit == 6.0).all())


def test_effort_limit_with_units_is_read_or_one_line() -> None:
    """effort_limit='23.5 N*m' is 23.5 in SI; a wrong unit is one InputError naming the field."""
    assert bool((_build_go2(effort_limit="23.5 N*m").effort_limit == 23.5).all())
    with pytest.raises(InputError, match=r"PerformanceEnvelopeActuatorCfg\.effort_limit: ") as info:
        _build_go2(effort_limit="23.5 rpm")
    assert "\n" not in str(info.value)


def test_float64_actions_and_the_speed_limit_warning() -> None:
    """float64 targets: advice to set float32; velocity_limit above max_actuator_velocity: a warning."""
    import torch
    from isaaclab.utils.types import ArticulationActions

    actuator = _build_go2(effort_limit=12.0)
    zeros = torch.zeros(2, len(GO2_JOINTS))
    action = ArticulationActions(joint_positions=zeros, joint_velocities=zeros, joint_efforts=zeros.double())
    with pytest.raises(InputError, match=r"joint_efforts are torch\.float64.*as torch\.float32"):
        actuator.compute(action, zeros, zeros)
    with pytest.warns(UserWarning, match=r"max_actuator_velocity 15\.7 is below velocity_limit 21"):
        _build_go2(max_actuator_velocity=15.7, velocity_limit=21.0)

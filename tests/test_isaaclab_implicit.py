"""The implicit path for Isaac Lab: the envelope in the USD for PhysX, and in the PhysX tensor API's order.

Isaac Lab is the PyPI wheel's real code with two Isaac Sim modules stood in for (see
``tests/conftest.py``). Real PhysX is ovphysx 0.7 on CPU: its ``ARTICULATION_DOF_DRIVE_MODEL``
tensor binding is the same view as omni.physics.tensors' ``get/set_dof_drive_model_properties``
(``[..., 3]`` = speedEffortGradient, maxActuatorVelocity, velocityDependentResistance, PhysX's
own SI values), and its per-attribute reads (``jointSpeedEffortGradient``, ..., per degree on
angular DOFs) tell which value went where. Assets: ``../shared/data/newton-assets/anymal_c.usd``
(skipped when absent), the repository's ``examples/usd/robot.usda`` and a three-DOF arm built here.
"""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

pytestmark = [
    pytest.mark.torch,
    # ovphysx 0.7 notes that newton-usd-schemas (installed with newton[importers]) was not registered
    # with ovstage; the stand's stages author no newton:* attribute, so nothing is dropped
    pytest.mark.filterwarnings("ignore:attach_ovstage. the Newton USD schema:RuntimeWarning"),
]

REPO = Path(__file__).resolve().parents[1]
ANYMAL = REPO.parent / "shared" / "data" / "newton-assets" / "anymal_c.usd"
DEG = math.pi / 180.0
ENVELOPE = de.PerformanceEnvelope(
    max_effort=10.0, max_actuator_velocity=3.0, velocity_dependent_resistance=0.5, speed_effort_gradient=0.1
)


def _anymal() -> Path:
    if not ANYMAL.is_file():
        pytest.skip("needs ../shared/data/newton-assets/anymal_c.usd (Newton's example assets; absent here)")
    return ANYMAL


def test_drive_model_order_is_the_tensor_api_order_not_the_constructor_order() -> None:
    """Put (G, v_max, R) on the last axis, the PhysX tensor API's order, and read it back exactly."""
    import torch

    from drive_envelope._src.params.table import parameter
    from drive_envelope.isaaclab import (
        DRIVE_MODEL_ORDER,
        drive_model_properties,
        envelope_from_drive_model_properties,
    )
    from drive_envelope.torch import EnvelopeTensors

    envelope = de.PerformanceEnvelope(
        max_effort=1.0,
        max_actuator_velocity=2.0,
        velocity_dependent_resistance=3.0,
        speed_effort_gradient=4.0,
    )
    assert drive_model_properties(envelope).tolist() == [4.0, 2.0, 3.0]
    assert [parameter(name).physx_tensor_index for name in DRIVE_MODEL_ORDER] == [0, 1, 2]  # the glossary's
    per_joint = EnvelopeTensors.from_values(
        max_effort=[[12.0, 8.0]], max_actuator_velocity=[[30.0, 20.0]], speed_effort_gradient=[[0.5, 0.25]]
    )
    props = drive_model_properties(per_joint)
    assert tuple(props.shape) == (1, 2, 3) and props.dtype == torch.float32
    back = envelope_from_drive_model_properties(props, per_joint.max_effort)
    for name in (
        "max_effort",
        "max_actuator_velocity",
        "velocity_dependent_resistance",
        "speed_effort_gradient",
    ):
        torch.testing.assert_close(getattr(back, name), getattr(per_joint, name).expand(1, 2))
    with pytest.raises(InputError, match="last axis of 3"):
        envelope_from_drive_model_properties(torch.zeros(2, 4), torch.zeros(2))
    with pytest.raises(InputError, match="max_forces: shape"):
        envelope_from_drive_model_properties(torch.zeros(2, 3), torch.zeros(3))


@pytest.mark.physx
def test_ovphysx_drive_model_binding_has_the_same_order() -> None:
    """Read PhysX's drive-model tensor as our order says, and write ours so PhysX stores each value right."""
    from ovphysx.types import TensorType

    from drive_envelope._src.adapters.physx.runner import _attached, _physx, _read_joints
    from drive_envelope._src.adapters.physx.scene import ARTICULATION_PATH, JOINT_PATH, build_teststand_stage
    from drive_envelope.isaaclab import drive_model_properties, envelope_from_drive_model_properties
    from drive_envelope.teststand import scenario_from_mapping

    scenario = scenario_from_mapping(
        {
            "joint": {"inertia": 0.05},
            "drive": {"damping": 1.0, "max_effort": ENVELOPE.max_effort},
            "envelope": {
                "max_actuator_velocity": 3.0,
                "velocity_dependent_resistance": 0.5,
                "speed_effort_gradient": 0.1,
            },
            "simulation": {"solver": "pgs"},
        },
        source="stand",
    )
    new = de.PerformanceEnvelope(
        max_effort=10.0,
        max_actuator_velocity=5.5,
        velocity_dependent_resistance=0.25,
        speed_effort_gradient=0.7,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # ovphysx 0.7 deprecates tensor bindings
        stage = build_teststand_stage(scenario)  # keep the stage alive while its layer is exported
        usda = stage.GetRootLayer().ExportToString()
        with _physx() as physx, _attached(physx, usda=usda):
            physx.warmup()
            binding = physx.create_tensor_binding(
                pattern=ARTICULATION_PATH, tensor_type=TensorType.ARTICULATION_DOF_DRIVE_MODEL
            )
            read = np.zeros(binding.shape, dtype=np.float32)
            binding.read(read)
            binding.write(drive_model_properties(new).reshape(binding.shape).numpy())
            written = np.zeros(binding.shape, dtype=np.float32)
            binding.read(written)
            binding.destroy()
            stored = _read_joints(
                physx,
                ["jointSpeedEffortGradient", "jointMaxActuatorVelocity", "jointVelocityDependentResistance"],
            )
    np.testing.assert_allclose(read.reshape(3), drive_model_properties(ENVELOPE).numpy(), rtol=1e-6)
    back = envelope_from_drive_model_properties(read.reshape(1, 3), [ENVELOPE.max_effort])
    assert (
        float(back.speed_effort_gradient[0]) == pytest.approx(0.1)
        and float(back.max_actuator_velocity[0]) == 3.0
    )
    np.testing.assert_allclose(written.reshape(3), [0.7, 5.5, 0.25], rtol=1e-6)
    # PhysX's per-attribute reads, per degree on this revolute DOF: each value landed on its own field
    assert stored["jointSpeedEffortGradient"][JOINT_PATH][0] == pytest.approx(0.7 / DEG, rel=1e-5)
    assert stored["jointMaxActuatorVelocity"][JOINT_PATH][0] == pytest.approx(5.5 / DEG, rel=1e-5)
    assert stored["jointVelocityDependentResistance"][JOINT_PATH][0] == pytest.approx(0.25 * DEG, rel=1e-5)


class _OvphysxArticulation:
    """The two things ``write_envelope_to_sim`` uses of an Isaac Lab Articulation, on ovphysx bindings.

    ``root_physx_view.get/set_dof_drive_model_properties`` and ``write_joint_effort_limit_to_sim``
    (which Isaac Lab sends to ``set_dof_max_forces``), here the ``ARTICULATION_DOF_DRIVE_MODEL`` and
    ``ARTICULATION_DOF_MAX_FORCE`` bindings of one real PhysX articulation.
    """

    device = "cpu"

    def __init__(self, physx: Any, pattern: str) -> None:
        from ovphysx.types import TensorType

        self.model = physx.create_tensor_binding(
            pattern=pattern, tensor_type=TensorType.ARTICULATION_DOF_DRIVE_MODEL
        )
        self.forces = physx.create_tensor_binding(
            pattern=pattern, tensor_type=TensorType.ARTICULATION_DOF_MAX_FORCE
        )
        self.root_physx_view = self
        self.count = self.model.shape[0]
        self.dof_names = list(self.model.dof_names)

    def get_dof_drive_model_properties(self) -> np.ndarray:
        out = np.zeros(self.model.shape, dtype=np.float32)
        self.model.read(out)
        return out

    def set_dof_drive_model_properties(self, data: Any, indices: Any) -> None:
        self.model.write(np.asarray(data, dtype=np.float32), indices=np.asarray(indices, dtype=np.int32))

    def write_joint_effort_limit_to_sim(
        self, limits: Any, joint_ids: Any = None, env_ids: Any = None
    ) -> None:
        current = np.zeros(self.forces.shape, dtype=np.float32)
        self.forces.read(current)
        columns = slice(None) if joint_ids is None else np.asarray(joint_ids)
        current[:, columns] = np.asarray(limits, dtype=np.float32)
        self.forces.write(current)

    def close(self) -> None:
        self.model.destroy()
        self.forces.destroy()


def _arm(path: Path) -> list[str]:
    """A fixed-base arm (shoulder, elbow: revolute; slide: prismatic), each with its own envelope."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics

    from drive_envelope.usd import save_stage, write_envelope

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    scene = UsdPhysics.Scene.Define(stage, "/World/physicsScene")
    scene.CreateGravityMagnitudeAttr().Set(0.0)
    UsdPhysics.ArticulationRootAPI.Apply(UsdGeom.Xform.Define(stage, "/World/arm").GetPrim())
    links = ["base", "upper", "fore", "tip"]
    for link in links:
        prim = UsdGeom.Xform.Define(stage, f"/World/arm/{link}").GetPrim()
        UsdPhysics.RigidBodyAPI.Apply(prim)
        mass = UsdPhysics.MassAPI.Apply(prim)
        mass.CreateMassAttr().Set(1.0)
        mass.CreateDiagonalInertiaAttr().Set(Gf.Vec3f(0.01, 0.01, 0.01))
    root = UsdPhysics.FixedJoint.Define(stage, "/World/arm/root")
    root.CreateBody1Rel().SetTargets([Sdf.Path("/World/arm/base")])
    joints = []
    for k, (name, schema, envelope) in enumerate(
        (
            ("shoulder", UsdPhysics.RevoluteJoint, ENVELOPE),
            (
                "elbow",
                UsdPhysics.RevoluteJoint,
                de.PerformanceEnvelope(
                    max_effort=4.0,
                    max_actuator_velocity=6.0,
                    velocity_dependent_resistance=0.2,
                    speed_effort_gradient=0.3,
                ),
            ),
            (
                "slide",
                UsdPhysics.PrismaticJoint,
                de.PerformanceEnvelope(
                    joint="prismatic",
                    max_effort=50.0,
                    max_actuator_velocity=0.5,
                    velocity_dependent_resistance=10.0,
                    speed_effort_gradient=0.004,
                ),
            ),
        )
    ):
        joint = schema.Define(stage, f"/World/arm/{name}")
        joint.CreateAxisAttr().Set("Z" if schema is UsdPhysics.RevoluteJoint else "X")
        joint.CreateBody0Rel().SetTargets([Sdf.Path(f"/World/arm/{links[k]}")])
        joint.CreateBody1Rel().SetTargets([Sdf.Path(f"/World/arm/{links[k + 1]}")])
        write_envelope(stage, f"/World/arm/{name}", envelope)
        joints.append(f"/World/arm/{name}")
    save_stage(stage, path, flatten=True)
    return joints


@pytest.mark.physx
@pytest.mark.usd
def test_write_envelope_to_sim_changes_only_the_chosen_joints(tmp_path: Path) -> None:
    """Write one joint's envelope into real PhysX at run time; the others keep theirs, each value in place."""
    from drive_envelope._src.adapters.physx.runner import _attached, _physx, _read_joints
    from drive_envelope.isaaclab import write_envelope_to_sim
    from drive_envelope.usd import open_stage, read_envelope

    joints = _arm(tmp_path / "arm.usda")
    authored = {joint: read_envelope(open_stage(tmp_path / "arm.usda"), joint) for joint in joints}
    elbow = de.PerformanceEnvelope(
        max_effort=7.0,
        max_actuator_velocity=9.0,
        velocity_dependent_resistance=0.4,
        speed_effort_gradient=0.02,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        with _physx() as physx, _attached(physx, path=tmp_path / "arm.usda"):
            physx.warmup()
            articulation = _OvphysxArticulation(physx, "/World/arm")
            try:
                assert articulation.dof_names == ["shoulder", "elbow", "slide"]
                write_envelope_to_sim(articulation, [elbow], joint_ids=[1])
            finally:
                articulation.close()
            names = [
                "jointMaxForce",
                "jointSpeedEffortGradient",
                "jointMaxActuatorVelocity",
                "jointVelocityDependentResistance",
            ]
            stored = _read_joints(physx, names)
    for joint in joints:
        expected = elbow if joint.endswith("elbow") else authored[joint]
        angle = 1.0 if joint.endswith("slide") else DEG  # PhysX reports angular DOFs per degree
        assert stored["jointMaxForce"][joint][0] == pytest.approx(expected.max_effort, rel=1e-6)
        assert stored["jointMaxActuatorVelocity"][joint][0] == pytest.approx(
            expected.max_actuator_velocity / angle, rel=1e-5
        )
        assert stored["jointSpeedEffortGradient"][joint][0] == pytest.approx(
            expected.speed_effort_gradient / angle, rel=1e-5
        )
        assert stored["jointVelocityDependentResistance"][joint][0] == pytest.approx(
            expected.velocity_dependent_resistance * angle, rel=1e-5
        )


@pytest.mark.isaaclab
@pytest.mark.usd
def test_author_implicit_envelopes_gives_an_implicit_actuator_that_keeps_them(tmp_path: Path) -> None:
    """Author the envelopes and build Isaac Lab's ImplicitActuator from what PhysX loads: limits unchanged."""
    import torch
    from isaaclab.actuators import ImplicitActuator, ImplicitActuatorCfg

    from drive_envelope.isaaclab import author_implicit_envelopes, check_implicit_actuator

    setup = author_implicit_envelopes(
        _anymal(),
        REPO / "examples" / "newton" / "anymal_map.toml",
        tmp_path / "anymal_envelope.usda",
        stiffness={".*_KFE": 80.0, ".*_H[AF][AE]": 40.0},
        damping=2.0,
    )
    assert setup.usd_path == tmp_path / "anymal_envelope.usda" and setup.usd_path.is_file()
    assert sorted(setup.envelopes) == sorted(
        f"{leg}_{j}" for leg in ("LF", "LH", "RF", "RH") for j in ("HAA", "HFE", "KFE")
    )
    cfg = setup.actuator
    assert isinstance(cfg, ImplicitActuatorCfg)
    assert cfg.effort_limit_sim is None and cfg.velocity_limit_sim is None and cfg.effort_limit is None
    assert all(re.fullmatch(pattern, pattern.replace("\\", "")) for pattern in cfg.joint_names_expr)
    assert check_implicit_actuator(cfg, setup.envelopes) == []
    names = sorted(setup.envelopes)
    # the USD's max force, as PhysX reports it to Isaac Lab (get_dof_max_forces), is the envelope's max_effort
    max_forces = torch.tensor([[setup.envelopes[n].max_effort for n in names]])
    actuator = ImplicitActuator(
        cfg, names, slice(None), 1, "cpu", effort_limit=max_forces, velocity_limit=1e3
    )
    torch.testing.assert_close(actuator.effort_limit_sim, max_forces)  # what Isaac Lab writes back to PhysX
    assert (
        actuator.stiffness[0, names.index("LF_KFE")] == 80.0
        and actuator.stiffness[0, names.index("LF_HAA")] == 40.0
    )
    # an existing cfg that would override the envelope is reported, one line per setting and joint
    override = ImplicitActuatorCfg(
        joint_names_expr=[".*_KFE"],
        stiffness=None,
        damping=None,
        effort_limit_sim=80.0,
        velocity_limit_sim=7.5,
    )
    problems = check_implicit_actuator(override, setup.envelopes)
    assert len(problems) == 8 and "effort_limit_sim = 80 for joint 'LF_KFE' replaces" in problems[0]
    assert any("caps the joint below the envelope's max_actuator_velocity 13.09" in p for p in problems)


@pytest.mark.isaaclab
@pytest.mark.usd
def test_author_implicit_envelopes_refuses_a_bad_map_and_writes_nothing(tmp_path: Path) -> None:
    """Refuse a map pattern that matches no joint with the map key, leaving no file behind."""
    from drive_envelope.isaaclab import author_implicit_envelopes

    bad = tmp_path / "map.toml"
    bad.write_text('[joints]\n"*_NOPE" = "tmotor-ak80-6"\n', encoding="utf-8")
    with pytest.raises(InputError, match=r"map\.toml: key 'joints\.\*_NOPE'"):
        author_implicit_envelopes(
            REPO / "examples" / "usd" / "robot.usda", bad, tmp_path / "out.usda", stiffness=None, damping=None
        )
    assert not (tmp_path / "out.usda").exists()


@pytest.mark.isaaclab
@pytest.mark.usd
def test_author_implicit_envelopes_reads_gain_units_and_refuses_unmatched_regexes(tmp_path: Path) -> None:
    """A string gain was passed to ImplicitActuatorCfg as it was (Isaac Lab refuses it when the
    scene is built) and a regex that matches no joint likewise; now strings with units are read
    per radian and a bad gain is one line before anything is written.
    """
    from drive_envelope.isaaclab import author_implicit_envelopes

    def author(name: str, stiffness: object, damping: object = 2.0) -> Any:
        return author_implicit_envelopes(
            _anymal(), REPO / "examples" / "newton" / "anymal_map.toml", tmp_path / name,
            stiffness=stiffness, damping=damping,  # type: ignore[arg-type]
        )  # fmt: skip

    setup = author("deg.usda", "80 N*m/deg", {".*_KFE": "0.1 N*m*s/deg", ".*_H[AF][AE]": 2})
    assert setup.actuator.stiffness == pytest.approx(80 * 180 / math.pi)
    assert setup.actuator.damping == {".*_KFE": pytest.approx(0.1 * 180 / math.pi), ".*_H[AF][AE]": 2.0}
    for name, stiffness, message in [
        (
            "typo.usda",
            {".*_KFEE": 80.0},
            r"stiffness\['\.\*_KFEE'\]: matches none of the joints the map equipped",
        ),
        ("unit.usda", "80 N*m", r"stiffness: '80 N\*m' has no matching angle unit"),
        ("neg.usda", -1.0, r"stiffness: expected >= 0 and finite"),
        ("list.usda", [80.0], r"stiffness: expected a number \[N\*m/rad or N/m\] or a string with units"),
    ]:
        with pytest.raises(InputError, match=r"^author_implicit_envelopes: " + message) as info:
            author(name, stiffness)
        assert "\n" not in str(info.value)
        assert not (tmp_path / name).exists()


@pytest.mark.isaaclab
@pytest.mark.filterwarnings("ignore:`torch.jit.script` is deprecated:FutureWarning")
def test_check_implicit_actuator_findings() -> None:
    """A partial effort_limit_sim dict (maxForce 0), an explicit cfg, a string joint_names_expr.

    Issue 23 item 13 on Isaac Lab 2.3 (the same cases on Isaac Lab 3.0: tests/isaaclab3).
    """
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

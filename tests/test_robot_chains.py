"""Robot-scale chains (issue 21): the FR3 and the Go2 leg set, imported from real assets.

Golden values come from the assets' own text (``fr3.urdf``'s elements, ``go2.xml`` as MuJoCo
compiles it), from the USD conversion of the same FR3 (``fr3_usd``, read with pxr), from MuJoCo's
own dynamics of the same files (``mj_fullM`` and ``qfrc_bias`` of MuJoCo's URDF parser on the FR3
and of five Menagerie robots: the reference engine's M(q) and h(q, v) of the imported robots must
be MuJoCo's), from hand sums (a link welded
onto another by the parallel-axis theorem) and from real PhysX (the robot-scale rows). The
assets are in ``../shared/data``; every test here skips without them.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain import ChainScenario, chain_from_mapping
from drive_envelope._src.scenario.chain_frames import full_inertia, quat_to_matrix
from drive_envelope._src.scenario.import_urdf import urdf_joints
from drive_envelope._src.teststand.engines.chain_dynamics import ChainModel

REPO = Path(__file__).resolve().parents[1]


def _module(name: str) -> Any:
    spec = importlib.util.spec_from_file_location(name, REPO / "benchmarks" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault(name, module)  # dataclasses look their module up while defining
    spec.loader.exec_module(module)
    return sys.modules[name]


robots = _module("robot_chains")
needs_fr3 = pytest.mark.skipif(not robots.FR3_URDF.is_file(), reason="needs ../shared/data/newton-assets/fr3")
needs_go2 = pytest.mark.skipif(not robots.GO2_MJCF.is_file(), reason="needs ../shared/data/menagerie/go2.xml")


@needs_fr3
def test_fr3_urdf_import_reads_the_files_numbers() -> None:
    entries = urdf_joints(robots.FR3_URDF)
    assert [e["name"] for e in entries] == [f"fr3_joint{i}" for i in range(1, 8)]
    assert [e["parent"] for e in entries] == ["base"] + [f"fr3_joint{i}" for i in range(1, 7)]
    # fr3_joint1: <origin rpy="0 0 0" xyz="0 0 0.333"/>, link1 <mass value="2.9274653454"/>
    assert entries[0]["origin"] == [0.0, 0.0, 0.333] and entries[0]["mass"] == 2.9274653454
    assert entries[0]["inertia"][3] == 1.3317903455714081e-05  # ixy
    # fr3_joint2: rpy="-1.570796326794897 0 0": a quarter turn about -X
    np.testing.assert_allclose(entries[1]["quat"], [math.sqrt(0.5), -math.sqrt(0.5), 0, 0], atol=1e-15)
    assert entries[4]["origin"] == [-0.0825, 0.384, 0.0]
    assert all(e["axis"] == [0.0, 0.0, 1.0] for e in entries)
    # fr3_link8 (no inertial) is welded onto link7 by fr3_joint8 (fixed): link7 unchanged
    assert entries[6]["mass"] == 0.6271432862


@needs_fr3
def test_fr3_urdf_and_its_usd_conversion_hold_the_same_numbers() -> None:
    pytest.importorskip("pxr")
    from drive_envelope._src.adapters.usd.stage import register_schemas

    register_schemas()  # before any stage opens: PhysX's runs in this process need its schemas
    from pxr import Usd, UsdPhysics

    entries = {e["name"]: e for e in urdf_joints(robots.FR3_URDF)}
    stage = Usd.Stage.Open(str(robots.FR3_USD))
    joints, bodies = {}, {}
    for prim in stage.Traverse():
        if prim.IsA(UsdPhysics.RevoluteJoint):
            joints[prim.GetName()] = UsdPhysics.RevoluteJoint(prim)
        if prim.HasAPI(UsdPhysics.MassAPI):
            bodies[prim.GetName()] = UsdPhysics.MassAPI(prim)
    assert sorted(joints) == sorted(entries)
    for name, entry in entries.items():
        joint = joints[name]
        assert joint.GetAxisAttr().Get() == "Z"
        np.testing.assert_allclose(list(joint.GetLocalPos0Attr().Get()), entry["origin"], atol=1e-7)
        rot = joint.GetLocalRot0Attr().Get()
        usd = quat_to_matrix((rot.GetReal(), *rot.GetImaginary()))
        np.testing.assert_allclose(usd, quat_to_matrix(tuple(entry["quat"])), atol=1e-7)
        body = bodies[f"fr3_link{name[-1]}"]
        assert math.isclose(body.GetMassAttr().Get(), entry["mass"], rel_tol=1e-7)
        np.testing.assert_allclose(list(body.GetCenterOfMassAttr().Get()), entry["com"], atol=1e-7)
        axes = body.GetPrincipalAxesAttr().Get()
        tensor = full_inertia(
            list(body.GetDiagonalInertiaAttr().Get()), (axes.GetReal(), *axes.GetImaginary())
        )
        ixx, iyy, izz, ixy, ixz, iyz = entry["inertia"]
        np.testing.assert_allclose(tensor, [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], atol=2e-8)


@needs_fr3
def test_fr3_urdf_import_has_mujocos_dynamics_of_the_same_urdf() -> None:
    """MuJoCo's own URDF parser on ``fr3_boxes.urdf`` (fr3.urdf's inertials, boxes for meshes)."""
    mujoco = pytest.importorskip("mujoco")
    boxes = robots.FR3_URDF.with_name("fr3_boxes.urdf")
    if not boxes.is_file():
        pytest.skip(f"needs {boxes}")
    scenario = chain_from_mapping(
        {"simulation": {"dt": 0.01, "duration": 0.1}, "joints": urdf_joints(robots.FR3_URDF)}
    )
    model = mujoco.MjModel.from_xml_path(str(boxes))
    model.opt.gravity[:] = (0.0, 0.0, -scenario.simulation.gravity)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(5)
    q, v = rng.uniform(-1.5, 1.5, 7), rng.uniform(-3.0, 3.0, 7)
    data.qpos[:], data.qvel[:] = q, v
    mujoco.mj_forward(model, data)
    full = np.zeros((7, 7))
    mujoco.mj_fullM(model, data, full)
    chain = ChainModel(scenario)
    kin = chain.kinematics(q)
    np.testing.assert_allclose(chain.mass_matrix(kin), full, rtol=0, atol=1e-12)
    np.testing.assert_allclose(chain.bias(kin, v), data.qfrc_bias, rtol=0, atol=1e-10)


def test_urdf_fixed_link_is_welded_by_the_parallel_axis_theorem(tmp_path: Path) -> None:
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(
        """<robot name="arm">
  <link name="world_link"/>
  <link name="a"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.2" izz="0.3" ixy="0" ixz="0" iyz="0"/>
  </inertial></link>
  <link name="tool"><inertial><origin xyz="0 0 0.5" rpy="0 0 0"/><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>
  </inertial></link>
  <joint name="j1" type="continuous"><parent link="world_link"/><child link="a"/><axis xyz="0 1 0"/></joint>
  <joint name="weld" type="fixed"><parent link="a"/><child link="tool"/>
    <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint>
  <joint name="j2" type="prismatic"><parent link="tool"/><child link="b"/><origin xyz="0 2 0"/>
    <axis xyz="1 0 0"/></joint>
</robot>""",
        encoding="utf-8",
    )
    a, b = urdf_joints(urdf)
    # by hand: tool's centre at (1, 0, 0.5) in a; com = (2*0 + 1*1, 0, 1*0.5)/3
    assert a["mass"] == 3.0
    np.testing.assert_allclose(a["com"], [1 / 3, 0.0, 1 / 6], atol=1e-15)
    # ixx = 0.1 + 2*(1/6)^2 + 0.01 + 1*(1/3)^2; iyy = 0.2 + 2*(1/9 + 1/36) + 0.01 + (4/9 + 1/9);
    # ixz = -sum m*dx*dz
    ixx = 0.1 + 2 / 36 + 0.01 + 1 / 9
    iyy = 0.2 + 2 * (1 / 9 + 1 / 36) + 0.01 + (4 / 9 + 1 / 9)
    ixz = -(2 * (-1 / 3) * (-1 / 6) + 1 * (2 / 3) * (1 / 3))
    np.testing.assert_allclose(
        [a["inertia"][0], a["inertia"][1], a["inertia"][4]], [ixx, iyy, ixz], atol=1e-15
    )
    # j2 hangs on the tool: its origin is carried through the weld (1, 0, 0) + Rz(90deg) @ (0, 2, 0)
    assert b["parent"] == "j1" and b["type"] == "prismatic"
    np.testing.assert_allclose(b["origin"], [-1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(
        quat_to_matrix(tuple(b["quat"])), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15
    )


def test_urdf_errors_name_the_file_and_element(tmp_path: Path) -> None:
    cases = {
        "floating": '<robot><link name="a"/><link name="b"/><joint name="j" type="floating">'
        '<parent link="a"/><child link="b"/></joint></robot>',
        "no mass": '<robot><link name="a"/><link name="b"/><joint name="j" type="revolute">'
        '<parent link="a"/><child link="b"/></joint></robot>',
        "'xyz'": '<robot><link name="a"/><link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" '
        'izz="1"/></inertial></link><joint name="j" type="revolute"><origin xyz="0 0"/><parent link="a"/>'
        '<child link="b"/></joint></robot>',
        "cannot read": "<robot>",
    }
    for word, text in cases.items():
        path = tmp_path / "bad.urdf"
        path.write_text(text, encoding="utf-8")
        with pytest.raises(InputError) as info:
            urdf_joints(path)
        message = str(info.value)
        assert "\n" not in message and str(path) in message and word in message, message


@needs_go2
def test_go2_legs_import_is_a_tree_on_the_base() -> None:
    scenario = robots.scenario("go2_legs", "pgs")
    assert isinstance(scenario, ChainScenario) and scenario.dofs == 12 and not scenario.is_chain
    assert [scenario.joints[i].parent for i in (0, 3, 6, 9)] == [-1] * 4  # four legs on the base
    hip = scenario.joints[0]
    assert hip.origin == (0.1934, 0.0465, 0.0) and hip.armature == 0.01  # <body name="FL_hip" pos=...>
    assert hip.axis_vector == (1.0, 0.0, 0.0)


MENAGERIE = robots.DATA / "menagerie"
MODELS = [
    "go2.xml",
    "anybotics_anymal_c/anymal_c.xml",
    "unitree_g1/g1.xml",
    "panda.xml",
    "kinova_gen3/gen3.xml",
]


@pytest.mark.parametrize("name", MODELS)
def test_mjcf_import_has_mujocos_own_dynamics(name: str) -> None:
    """The reference's M(q) and h(q, v) of an imported Menagerie robot are MuJoCo's (base free, at rest).

    ANYmal C, G1 and Gen3 have turned body frames; the Panda's hand is welded onto link7 (merged).
    """
    mujoco = pytest.importorskip("mujoco")
    from drive_envelope._src.adapters.mujoco.chain_import import mjcf_joints

    path = MENAGERIE / name
    if not path.is_file():
        pytest.skip(f"needs {path}")
    scenario = chain_from_mapping({"simulation": {"dt": 0.01, "duration": 0.1}, "joints": mjcf_joints(path)})
    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.gravity[:] = (0.0, 0.0, -scenario.simulation.gravity)  # the stand's 9.80665, not 9.81
    data = mujoco.MjData(model)
    free = 6 if model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE else 0
    assert model.nv - free == scenario.dofs
    rng = np.random.default_rng(3)
    q, v = rng.uniform(-1.0, 1.0, scenario.dofs), rng.uniform(-3.0, 3.0, scenario.dofs)
    data.qpos[model.nq - scenario.dofs :], data.qvel[free:] = q, v
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    chain = ChainModel(scenario)
    kin = chain.kinematics(q)
    np.testing.assert_allclose(chain.mass_matrix(kin), full[free:, free:], rtol=0, atol=1e-12)
    np.testing.assert_allclose(chain.bias(kin, v), data.qfrc_bias[free:], rtol=0, atol=1e-10)
    if name == "panda.xml":  # link7 carries the welded link8 and hand, not the fingers
        link7 = next(joint for joint in scenario.joints if joint.name == "joint7")
        subtree = model.body_subtreemass
        fingers = subtree[model.body("left_finger").id] + subtree[model.body("right_finger").id]
        assert math.isclose(link7.mass, subtree[model.body("link7").id] - fingers, rel_tol=1e-12)
        assert link7.mass > model.body_mass[model.body("link7").id] + 0.5


def test_mjcf_import_of_turned_bodies_and_offset_joints_matches_mujoco(tmp_path: Path) -> None:
    mujoco = pytest.importorskip("mujoco")
    from drive_envelope._src.adapters.mujoco.chain_import import mjcf_joints

    xml = tmp_path / "turned.xml"
    xml.write_text(
        """<mujoco><worldbody>
  <body name="base" pos="0 0 1" quat="0.9 0.1 0.3 -0.2"><freejoint/>
    <inertial pos="0 0 0" mass="5" diaginertia="0.1 0.1 0.1"/>
    <body name="l1" pos="0.1 0.2 0" quat="0.7 0.5 0.1 0.2">
      <joint name="j1" pos="0.05 0 0.02" axis="0.3 0.4 1"/>
      <inertial pos="0.1 0.02 -0.03" quat="0.8 0.2 -0.3 0.1" mass="1.5" diaginertia="0.02 0.03 0.04"/>
      <body name="l2" pos="0.3 0 0.1" quat="0.6 -0.2 0.7 0.1">
        <joint name="j2" type="slide" pos="0 0.04 0" axis="1 0.2 0"/>
        <inertial pos="0.05 0 0" mass="0.7" fullinertia="0.01 0.02 0.015 0.001 -0.002 0.0005"/>
        <body name="l3" pos="0 0.2 0"><joint name="j3" pos="0.01 0.01 0.01" axis="0 1 0" armature="0.02"/>
          <inertial pos="0 0 -0.1" mass="0.4" diaginertia="0.004 0.004 0.001"/></body>
      </body>
    </body>
  </body></worldbody></mujoco>""",
        encoding="utf-8",
    )
    data_map = {"simulation": {"dt": 0.01, "duration": 0.1}, "joints": mjcf_joints(xml)}
    scenario = chain_from_mapping(data_map, source=str(xml))
    assert [joint.type for joint in scenario.joints] == ["revolute", "prismatic", "revolute"]
    model = mujoco.MjModel.from_xml_path(str(xml))
    model.opt.gravity[:] = (0.0, 0.0, -scenario.simulation.gravity)
    data = mujoco.MjData(model)
    q, v = np.array([0.7, -0.05, 1.9]), np.array([1.5, 0.4, -2.0])
    data.qpos[7:], data.qvel[6:] = q, v
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    chain = ChainModel(scenario)
    kin = chain.kinematics(q)
    # the base is turned by its quat, which the chain's base frame (the world's) carries
    np.testing.assert_allclose(chain.mass_matrix(kin), full[6:, 6:], rtol=0, atol=1e-12)
    np.testing.assert_allclose(chain.bias(kin, v), data.qfrc_bias[6:], rtol=0, atol=1e-11)


def test_mjcf_import_refuses_what_the_chain_cannot_hold(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    from drive_envelope._src.adapters.mujoco.chain_import import mjcf_joints

    cases = {
        "ball": '<mujoco><worldbody><body name="a"><joint type="ball"/><geom size="0.1"/></body>'
        "</worldbody></mujoco>",
        "2 joint(s)": '<mujoco><worldbody><body name="a"><joint/><joint/><geom size="0.1"/></body>'
        "</worldbody></mujoco>",
        "cannot compile": "<mujoco><worldbody><body></mujoco>",
    }
    for word, text in cases.items():
        path = tmp_path / "bad.xml"
        path.write_text(text, encoding="utf-8")
        with pytest.raises(InputError) as info:
            mjcf_joints(path)
        message = str(info.value)
        assert "\n" not in message and str(path) in message and word in message, message


@needs_fr3
def test_fr3_stand_meets_its_speed_line_on_the_reference() -> None:
    from drive_envelope._src.teststand.engines import simulate

    scenario = robots.scenario("fr3", "pgs")
    run = simulate(scenario)
    joint2 = run.joint("fr3_joint2")
    assert math.isclose(float(np.abs(joint2.effort).max()), 87.0, rel_tol=1e-9)  # saturated at 87 N*m
    released = int(np.flatnonzero(np.abs(joint2.effort[1:]) < 1e-4 * 87.0)[0]) + 1
    assert np.all(joint2.velocity[1:released] < 2.62 + 1e-9) and joint2.velocity[released + 2] > 2.62
    others = np.delete(np.abs(run.position - run.position[0]), 1, axis=1)
    assert others.max() < 0.15  # the other six hold their pose


@pytest.fixture(scope="module")
def robot_rows() -> list[Any]:
    pytest.importorskip("ovphysx")
    pytest.importorskip("mujoco")
    if not (robots.available("fr3") and robots.available("go2_legs")):
        pytest.skip("needs ../shared/data (FR3 and Go2 assets)")
    parity = _module("parity_table")
    scenarios = [robots.scenario(robot, solver) for robot in ("fr3", "go2_legs") for solver in robots.SOLVERS]
    return list(parity.chain_measure(["reference", "mujoco"], scenarios))


@pytest.mark.physx
@pytest.mark.usd
@pytest.mark.mujoco
@pytest.mark.slow
def test_robot_rows_hold_against_real_physx(robot_rows: list[Any]) -> None:
    assert len(robot_rows) == 8
    for row in robot_rows:
        assert row.joint == ("fr3_joint2" if row.scenario.startswith("FR3") else "FL_calf_joint")
        assert row.physx_release > 3, row  # it pushed first, then let go
        if row.engine == "reference":
            assert row.before < 1e-5 and row.release == row.physx_release, row
        else:
            assert row.before < 0.02 and abs(row.release - row.physx_release) <= 1, row
        assert row.after < 1e-4, row  # float32 noise at up to 16 rad/s


@pytest.mark.physx
@pytest.mark.usd
@pytest.mark.mujoco
@pytest.mark.slow
def test_robot_rows_are_docs_parity_md(robot_rows: list[Any]) -> None:
    parity = _module("parity_table")
    table = parity.chain_documented(parity.DOC.read_text(encoding="utf-8"))
    for row in robot_rows:
        before, release, physx_release, after = table[(row.scenario, row.engine)]
        assert (release, physx_release) == (row.release, row.physx_release), row
        # PhysX on the CPU repeats its float32 run; two significant digits are printed
        assert math.isclose(before, row.before, rel_tol=0.05) and math.isclose(
            after, row.after, rel_tol=0.05
        ), (
            "run: python benchmarks/parity_table.py --chains --write",
            row,
        )

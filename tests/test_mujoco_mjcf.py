"""``drive-envelope mujoco apply|show``: equipping MJCF robots with drives, on built and real models.

The command module is registered on a local parser here (the lead wires it into ``COMMANDS``).
Real inputs: the Menagerie Go2 and Panda in ``../shared/data/menagerie`` (skipped when absent), with
the robot maps shipped in ``drive_envelope/maps``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import InputError

pytestmark = pytest.mark.mujoco

MENAGERIE = Path(__file__).resolve().parents[2] / "shared" / "data" / "menagerie"
ROBOT = """<mujoco model="arm"><compiler angle="radian" meshdir="assets"/><option timestep="0.002"/>
<asset><mesh name="tet" file="tet.obj"/></asset>
<default><default class="arm"><general biastype="affine" forcerange="-50 50" ctrlrange="-2 2"/>
</default></default>
<worldbody><body name="l1" pos="0 0 1"><joint name="shoulder" axis="0 1 0" range="-1.5 1.5" damping="0.5"/>
<geom type="mesh" mesh="tet"/><geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="elbow" axis="0 1 0" range="-2 0"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="wrist" axis="0 1 0"/><geom type="sphere" size="0.03"/>
</body></body></body></worldbody>
<actuator><general class="arm" name="a_shoulder" joint="shoulder" gainprm="300" biasprm="0 -300 -30"/>
<motor name="a_elbow" joint="elbow" ctrlrange="-10 10"/><velocity name="a_wrist" joint="wrist" kv="2"/>
</actuator>
<keyframe><key name="home" qpos="0.2 -0.5 0" ctrl="0.2 3 0"/></keyframe></mujoco>"""
TET = "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
ENVELOPE = "max_effort = 8.0\nmax_actuator_velocity = 12.147491593880533\nspeed_effort_gradient = 0.1\n"


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    folder = tmp_path / "robot"
    (folder / "assets").mkdir(parents=True)
    (folder / "assets" / "tet.obj").write_text(TET)
    (folder / "arm.xml").write_text(ROBOT)
    (tmp_path / "joint.toml").write_text(ENVELOPE)
    return folder / "arm.xml"


def _cli(*argv: str) -> int:
    from drive_envelope._src.cli.commands import mujoco as command

    parser = argparse.ArgumentParser(prog="drive-envelope")
    command.register(parser.add_subparsers())
    args = parser.parse_args(argv)
    return int(args.func(args))


def test_apply_one_joint_writes_an_mjcf_that_loads_with_every_digit(
    mujoco: Any, robot: Path, tmp_path: Path
) -> None:
    """Replace the shoulder's general PD actuator, keep kp/kv and ctrl slot, write exact numbers."""
    out = tmp_path / "out" / "arm_env.xml"
    out.parent.mkdir()
    envelope = str(tmp_path / "joint.toml")
    assert (
        _cli("mujoco", "apply", str(robot), "--joint", "shoulder", "--envelope", envelope, "-o", str(out))
        == 0
    )
    model = mujoco.MjModel.from_xml_path(str(out))  # stock MuJoCo with the plugin loaded; assets re-pointed
    assert model.nu == 3 and int(model.actuator_plugin[0]) >= 0
    assert model.actuator_dynprm[0, :6].tolist() == [8.0, 12.147491593880533, 0.0, 0.1, 300.0, 30.0]
    assert not model.actuator_forcelimited[0] and model.actuator_biastype[0] == 0  # no class leaks in
    np.testing.assert_allclose(model.actuator_ctrlrange[0], [-2.0, 2.0])
    np.testing.assert_allclose(model.key_ctrl[0], [0.2, 3.0, 0.0])
    assert 'dynprm="8 12.147491593880533 0 0.1 300 30"' in out.read_text()


def test_a_joint_given_twice_is_refused_naming_both(robot: Path, tmp_path: Path, capsys: Any) -> None:
    """Refuse a repeated --joint (argparse kept only the last, equipping one joint of two silently)."""
    out = tmp_path / "o.xml"
    envelope = str(tmp_path / "joint.toml")
    with pytest.raises(SystemExit) as info:
        _cli("mujoco", "apply", str(robot), "--joint", "shoulder", "--joint", "elbow", "--envelope", envelope,
             "-o", str(out))  # fmt: skip
    assert info.value.code == 2 and not out.exists()
    assert "--joint: given twice ('shoulder', 'elbow'): one joint per --joint run" in capsys.readouterr().err


def test_stiffness_without_damping_says_which_damping_stays(
    mujoco: Any, robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Name the kept kv (30 N*m*s/rad of the shoulder's general PD, biasprm 0 -300 -30) beside the new kp."""
    out = tmp_path / "o.xml"
    envelope = str(tmp_path / "joint.toml")
    assert _cli("mujoco", "apply", str(robot), "--joint", "shoulder", "--envelope", envelope,
                "--stiffness", "60", "-o", str(out)) == 0  # fmt: skip
    printed = capsys.readouterr()
    assert "gains stiffness given, the other from position 'a_shoulder')" in printed.out
    assert (
        "--stiffness is given without --damping: 1 joint(s) keep their replaced actuator's damping "
        "(shoulder 30 N*m*s/rad), tuned for its own gains; give --damping too to set both"
    ) in printed.err


def test_apply_a_map_equips_every_joint_keeping_what_each_actuator_meant(
    mujoco: Any, robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Give a PD, a motor (gains given) and a velocity actuator drives; print one line per joint."""
    from drive_envelope.mujoco import model_drives

    joint_map = tmp_path / "arm_map.toml"
    joint_map.write_text('[joints]\n"shoulder" = "joint.toml"\n"*" = "joint.toml"\n')
    out = tmp_path / "arm_env.xml"
    with pytest.raises(InputError, match=r"joint 'elbow': its actuator 'a_elbow' is a motor .*--stiffness"):
        _cli("mujoco", "apply", str(robot), "--map", str(joint_map), "-o", str(out))
    assert not out.exists()
    assert _cli("mujoco", "apply", str(robot), "--map", str(joint_map), "--stiffness", "40 N*m/rad",
                "--damping", "1", "-o", str(out)) == 0  # fmt: skip
    printed = capsys.readouterr()
    assert "elbow: drive 'a_elbow' (replaces motor 'a_elbow'; inputs pos; gains given)" in printed.out
    assert "wrote 3 drive(s)" in printed.err and "redundant" not in printed.err
    model = mujoco.MjModel.from_xml_path(str(out))
    drives = {d.joint: d for d in model_drives(model)}
    assert drives["wrist"].inputs == ("vel",)  # a velocity actuator's control stays a target velocity
    assert (drives["elbow"].stiffness, drives["elbow"].damping) == (40.0, 1.0)
    np.testing.assert_allclose(model.actuator_ctrlrange[1], [-2.0, 0.0])  # the motor's torque range went
    np.testing.assert_allclose(model.key_ctrl[0], [0.2, -0.5, 0.0])  # its key torque became the key pose


def test_apply_refuses_bad_arguments_before_any_work(mujoco: Any, robot: Path, tmp_path: Path) -> None:
    """Refuse a missing -o, the input as output, a non-.xml output and mixed --map/--envelope flags."""
    envelope = str(tmp_path / "joint.toml")
    with pytest.raises(InputError, match=r"say where the result goes: -o arm_envelope\.xml"):
        _cli("mujoco", "apply", str(robot), "--joint", "shoulder", "--envelope", envelope)
    with pytest.raises(InputError, match=r"is ROBOT\.xml itself"):
        _cli("mujoco", "apply", str(robot), "--joint", "shoulder", "--envelope", envelope, "-o", str(robot))
    with pytest.raises(InputError, match=r"expected an \.xml file name"):
        _cli("mujoco", "apply", str(robot), "--joint", "shoulder", "--envelope", envelope, "-o", "x.usd")
    with pytest.raises(InputError, match="needs --datasheet FILE or --envelope FILE"):
        _cli("mujoco", "apply", str(robot), "--joint", "shoulder", "-o", str(tmp_path / "o.xml"))
    with pytest.raises(InputError, match="--joint: the model has no hinge or slide joint named 'knee'"):
        _cli(
            "mujoco",
            "apply",
            str(robot),
            "--joint",
            "knee",
            "--envelope",
            envelope,
            "-o",
            str(tmp_path / "o.xml"),
        )
    with pytest.raises(InputError, match="matches no joint name"):
        joint_map = tmp_path / "typo.toml"
        joint_map.write_text('[joints]\n"sholder" = "joint.toml"\n')
        _cli("mujoco", "apply", str(robot), "--map", str(joint_map), "-o", str(tmp_path / "o.xml"))
    assert not (tmp_path / "o.xml").exists()


def test_show_lists_drives_and_the_actuators_that_bypass_them(
    mujoco: Any, robot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """List the drives with their numbers, and the joints whose actuators are not drives."""
    out = tmp_path / "arm_env.xml"
    _cli(
        "mujoco",
        "apply",
        str(robot),
        "--joint",
        "shoulder",
        "--envelope",
        str(tmp_path / "joint.toml"),
        "-o",
        str(out),
    )
    capsys.readouterr()
    assert _cli("mujoco", "show", str(out)) == 0
    text = capsys.readouterr().out
    assert "1 drive_envelope.envelope drive(s)" in text and "a_shoulder  shoulder  pos" in text
    assert "elbow  a_elbow   motor" in text and "wrist  a_wrist   velocity" in text
    assert _cli("mujoco", "show", str(out), "--json") == 0
    data = json.loads(capsys.readouterr().out)
    assert data["drives"][0]["envelope"]["max_actuator_velocity"] == 12.147491593880533
    assert [o["actuator"] for o in data["other_actuators"]] == ["a_elbow", "a_wrist"]


def test_show_refuses_a_file_mujoco_cannot_read(mujoco: Any, tmp_path: Path) -> None:
    """Name the file and MuJoCo's reason on one line."""
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body><joint name='j'/></body></worldbody>")
    with pytest.raises(InputError, match=r"bad.xml: MuJoCo cannot compile it: .*") as info:
        _cli("mujoco", "show", str(bad))
    assert "\n" not in str(info.value)
    with pytest.raises(InputError, match="no such MJCF file"):
        _cli("mujoco", "show", str(tmp_path / "missing.xml"))


def _menagerie(name: str) -> Path:
    path = MENAGERIE / name
    if not path.is_file():
        pytest.skip(f"needs {path} (../shared/data/menagerie, not part of a user's clone)")
    return path


def test_equipping_the_menagerie_go2_is_one_command(mujoco: Any, tmp_path: Path) -> None:
    """Apply the shipped unitree-go2 map to Menagerie's Go2 on a floor: 12 drives, keyframe kept, it walks."""
    from drive_envelope.mujoco import model_drives

    out = tmp_path / "go2_env.xml"
    scene = str(_menagerie("scene_floor.xml"))
    assert (
        _cli(
            "mujoco",
            "apply",
            scene,
            "--map",
            "unitree-go2",
            "--stiffness",
            "60",
            "--damping",
            "2",
            "-o",
            str(out),
        )
        == 0
    )
    model = mujoco.MjModel.from_xml_path(str(out))
    drives = model_drives(model)
    assert len(drives) == 12 and model.nu == 12
    assert {d.envelope.max_effort for d in drives if d.envelope} == {23.7, 45.43}
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    for _ in range(500):  # stand on the floor holding the keyframe pose
        mujoco.mj_step(model, data)
    assert data.qpos[2] > 0.2 and np.isfinite(data.qpos).all()


def test_the_panda_keeps_its_gains_and_gripper(mujoco: Any, tmp_path: Path) -> None:
    """Apply the franka-panda map: joints 1-7 keep kp/kv of their general PD actuators, the gripper stays."""
    from drive_envelope.mujoco import model_drives

    out = tmp_path / "panda_env.xml"
    assert _cli("mujoco", "apply", str(_menagerie("panda.xml")), "--map", "franka-panda", "-o", str(out)) == 0
    model = mujoco.MjModel.from_xml_path(str(out))
    drives = model_drives(model)
    assert [(d.joint, d.stiffness, d.damping) for d in drives[:2]] == [
        ("joint1", 4500.0, 450.0),
        ("joint2", 4500.0, 450.0),
    ]
    assert len(drives) == 7 and model.nu == 8 and int(model.actuator_plugin[7]) == -1
    np.testing.assert_allclose(model.key_ctrl[0][:7], [0, 0, 0, -1.57079, 0, 1.57079, -0.7853])


def test_show_reports_mujocos_warnings_on_stderr(
    mujoco: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Print the plugin's warning about a second actuator on a driven joint as one stderr line."""
    model = tmp_path / "two.xml"
    model.write_text(
        '<mujoco><extension><plugin plugin="drive_envelope.envelope"/></extension><worldbody><body>'
        '<joint name="j"/><geom size="0.1"/></body></worldbody><actuator>'
        '<plugin name="d" joint="j" plugin="drive_envelope.envelope" dynprm="1 -1 0 0 1 0"/>'
        '<motor name="show_extra" joint="j"/></actuator></mujoco>'
    )
    assert _cli("mujoco", "show", str(model)) == 0
    printed = capsys.readouterr()
    assert "actuator 'show_extra' also acts on joint 'j', driven by 'd'" in printed.err
    assert "WARNING" not in printed.out and "show_extra  motor" in printed.out

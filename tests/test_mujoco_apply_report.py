"""``mujoco apply`` on models as Menagerie writes them (issue 23, items 2-6; issue 25, item 6).

Golden values are by hand: a ``position`` actuator with ``dampratio="1"`` on a hinge whose body has
inertia 0.04 kg*m^2 about the axis (nothing else moves) has kv = 2 * sqrt(kp * 0.04) = 4 for
kp = 100, as MuJoCo's compiler defines dampratio; ``inheritrange="1"`` makes the control range the
joint's range. The AK80-6 from the catalog has max_effort 12 N*m, the G1 map's ankles 35 N*m
against the Menagerie G1's actuatorfrcrange 50 N*m: (50 - 35) / 50 = 30 %.
"""

from __future__ import annotations

import argparse
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import TENDON_ARM, mujoco_with_plugin
from drive_envelope import InputError

pytestmark = pytest.mark.mujoco

MENAGERIE = Path(__file__).resolve().parents[2] / "shared" / "data" / "menagerie"

BODY = '<body pos="{x} 0 0"><joint name="{name}" axis="0 1 0" range="-1 1.5"/>' \
    '<inertial pos="0 0 0" mass="1" diaginertia="0.04 0.04 0.04"/></body>'  # fmt: skip


def _model(tmp_path: Path, actuators: str, *, joints: tuple[str, ...] = ("a", "b"), extra: str = "") -> Path:
    bodies = "".join(BODY.format(x=i, name=name) for i, name in enumerate(joints))
    text = (
        f"<mujoco><compiler angle='radian'/><option timestep='0.002'/><worldbody>{bodies}</worldbody>"
        f"{extra}<actuator>{actuators}</actuator></mujoco>"
    )
    path = tmp_path / "robot.xml"
    path.write_text(text.replace("'", '"'), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


def _cli(*argv: str) -> int:
    from drive_envelope._src.cli.commands import mujoco as command

    parser = argparse.ArgumentParser(prog="drive-envelope")
    command.register(parser.add_subparsers())
    args = parser.parse_args(argv)
    return int(args.func(args))


def _apply(model: Path, out: Path, *flags: str) -> int:
    return _cli("mujoco", "apply", str(model), *flags, "-o", str(out))


def test_dampratio_gains_and_inherited_control_ranges_are_kept(mujoco: Any, tmp_path: Path) -> None:
    """kv comes from the compiled dampratio (4 N*m*s/rad), the control range from inheritrange."""
    model = _model(
        tmp_path,
        '<position name="pa" joint="a" kp="100" dampratio="1" inheritrange="1"/>',
        joints=("a",),
    )
    out = tmp_path / "out.xml"
    assert _apply(model, out, "--joint", "a", "--datasheet", "tmotor-ak80-6") == 0
    from drive_envelope._src.adapters.mujoco.params import model_drives

    result = mujoco.MjModel.from_xml_path(str(out))
    (drive,) = model_drives(result)
    assert drive.stiffness == 100.0
    assert drive.damping == pytest.approx(4.0, rel=1e-12)
    np.testing.assert_array_equal(result.actuator_ctrlrange[0], [-1.0, 1.5])
    assert result.actuator_ctrllimited[0]


def test_a_keyframe_without_ctrl_holds_its_position_where_a_motor_becomes_a_drive(
    mujoco: Any, tmp_path: Path
) -> None:
    """H1's case: the key has qpos only; the motor's 0 N*m becomes a target of the key's 0.7 rad."""
    model = _model(
        tmp_path,
        '<motor name="ma" joint="a"/><position name="pb" joint="b" kp="10"/>',
        extra='<keyframe><key name="home" qpos="0.7 0.2"/></keyframe>',
    )
    out = tmp_path / "out.xml"
    flags = ("--joint", "a", "--datasheet", "tmotor-ak80-6", "--stiffness", "50", "--damping", "2")
    assert _apply(model, out, *flags) == 0
    result = mujoco.MjModel.from_xml_path(str(out))
    # the drive targets the key's position; the untouched position actuator keeps MuJoCo's 0
    np.testing.assert_array_equal(result.key_ctrl[0], [0.7, 0.0])


def test_a_motor_beside_a_position_actuator_becomes_its_feed_forward(mujoco: Any, tmp_path: Path) -> None:
    """Issue 25 item 6: nothing deleted, every control slot stays, the motor's key torque too."""
    model = _model(
        tmp_path,
        '<position name="pa" joint="a" kp="50" kv="2" ctrlrange="-1 1"/><motor name="ma" joint="a"'
        ' ctrlrange="-3 3"/><position name="pb" joint="b" kp="20"/>',
        extra='<keyframe><key name="k" qpos="0.5 0.25" ctrl="0.4 1.5 0.2"/></keyframe>',
    )
    out = tmp_path / "out.xml"
    assert _apply(model, out, "--joint", "a", "--datasheet", "tmotor-ak80-6") == 0
    from drive_envelope._src.adapters.mujoco.params import model_drives

    result = mujoco.MjModel.from_xml_path(str(out))
    names = [mujoco.mj_id2name(result, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(result.nu)]
    assert names == ["pa", "ma", "pb"]
    (drive,) = model_drives(result)
    assert drive.inputs == ("pos", "ff")
    np.testing.assert_array_equal(result.key_ctrl[0], [0.4, 1.5, 0.2])
    np.testing.assert_array_equal(result.actuator_ctrlrange[1], [-3.0, 3.0])


def test_a_motor_before_the_position_actuator_is_deleted_with_a_warning(
    mujoco: Any, tmp_path: Path, capsys: Any
) -> None:
    """The position actuator (with the gains) is kept; the deleted motor and the slot shift are said."""
    model = _model(
        tmp_path,
        '<motor name="ma" joint="a"/><position name="pa" joint="a" kp="50" kv="2"/>'
        '<position name="pb" joint="b" kp="20"/>',
        extra='<keyframe><key name="k" qpos="0.5 0.25" ctrl="0.4 1.5 0.2"/></keyframe>',
    )
    out = tmp_path / "out.xml"
    assert _apply(model, out, "--joint", "a", "--datasheet", "tmotor-ak80-6") == 0
    err = capsys.readouterr().err
    assert (
        "--joint: joint 'a': actuator(s) 'ma' (motor) deleted: the drive replaces 'pa' and their force "
        "would bypass the envelope; the 2 actuator(s) after them move down 1 control slot(s)"
    ) in err
    result = mujoco.MjModel.from_xml_path(str(out))
    names = [mujoco.mj_id2name(result, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(result.nu)]
    assert names == ["pa", "pb"]
    np.testing.assert_array_equal(result.key_ctrl[0], [1.5, 0.2])


def test_caps_below_the_model_rating_and_binding_frcranges_are_reported_once(
    mujoco: Any, tmp_path: Path, capsys: Any
) -> None:
    """A motor's ctrlrange 40 N*m is the model's rating (12 is 70 % below); an actuatorfrcrange of 8
    binds under the 12 N*m cap; one of 12.5 cannot bind and says nothing."""
    model = _model(
        tmp_path,
        '<motor name="ma" joint="a" ctrlrange="-40 40"/><motor name="mb" joint="b"/>',
        joints=("a", "b", "c"),
    )
    text = model.read_text(encoding="utf-8")
    text = text.replace('name="b" axis="0 1 0"', 'name="b" actuatorfrcrange="-8 8" axis="0 1 0"')
    text = text.replace('name="c" axis="0 1 0"', 'name="c" actuatorfrcrange="-12.5 12.5" axis="0 1 0"')
    model.write_text(text, encoding="utf-8")
    for joint in ("a", "b", "c"):
        flags = ("--joint", joint, "--datasheet", "tmotor-ak80-6", "--stiffness", "5", "--damping", "1")
        assert _apply(model, tmp_path / f"{joint}.xml", *flags) == 0
        err = capsys.readouterr().err
        if joint == "a":
            assert (
                "--joint: max_effort 12 N*m is 70 % below the model's own rating, 40 N*m (ctrlrange of "
                "motor 'ma') on a: the drive caps these joints at 12 N*m"
            ) in err
        elif joint == "b":
            assert "--joint: actuatorfrcrange 8 N*m on b is below the envelope's max_effort 12 N*m" in err
            assert "has an actuatorfrcrange" not in err and err.count("warning") == 1  # not the plugin's too
        else:
            assert "warning" not in err


def test_an_equality_between_driven_joints_is_a_warning(mujoco: Any, tmp_path: Path) -> None:
    """Its constraint force acts beside the drives: said once, naming both joints."""
    from drive_envelope._src.adapters.mujoco.ratings import coupled_driven_joints

    model = _model(
        tmp_path,
        '<position name="pa" joint="a" kp="50" kv="2"/><position name="pb" joint="b" kp="50" kv="2"/>',
        extra='<equality><joint name="tie" joint1="a" joint2="b"/></equality>',
    )
    compiled = mujoco.MjModel.from_xml_path(str(model))
    (line,) = coupled_driven_joints(compiled, ["a", "b"])
    assert line.startswith("equality 'tie' couples driven joint(s) 'a' and 'b': its constraint force")
    assert coupled_driven_joints(compiled, ["a"]) == []


def test_wording_of_an_actuator_without_gains_and_of_a_near_joint_name(mujoco: Any, tmp_path: Path) -> None:
    """No "is a other"; ``--joint elbo`` suggests the joints whose names contain it."""
    model = _model(
        tmp_path,
        '<general name="g" joint="left_elbow_joint" gaintype="affine" gainprm="1 2"/>',
        joints=("left_elbow_joint", "right_elbow_joint"),
    )
    out = tmp_path / "out.xml"
    with pytest.raises(InputError, match=r"its actuator 'g' is neither a motor nor a PD actuator"):
        _apply(model, out, "--joint", "left_elbow_joint", "--datasheet", "tmotor-ak80-6")
    near = "(did you mean 'left_elbow_joint', 'right_elbow_joint'?)"
    with pytest.raises(InputError, match=re.escape(near)):
        _apply(model, out, "--joint", "elbo", "--datasheet", "tmotor-ak80-6")


def test_menagerie_g1_with_the_shipped_map(mujoco: Any, tmp_path: Path, capsys: Any) -> None:
    """The done-when case: a working model, its control ranges, every cap below the model's said."""
    scene = MENAGERIE / "unitree_g1" / "scene.xml"
    if not scene.is_file():
        pytest.skip(f"needs {scene} (../shared/data/menagerie, not part of a user's clone)")
    out = tmp_path / "g1.xml"
    assert _apply(scene, out, "--map", "unitree-g1") == 0
    err = capsys.readouterr().err
    from drive_envelope._src.adapters.mujoco.params import model_drives

    original = mujoco.MjModel.from_xml_path(str(scene))
    result = mujoco.MjModel.from_xml_path(str(out))
    assert len(model_drives(result)) == 29
    np.testing.assert_array_equal(result.actuator_ctrlrange, original.actuator_ctrlrange)
    assert result.actuator_ctrllimited.all()
    lines = [line for line in err.splitlines() if "warning" in line]
    below = [line for line in lines if "% below the model's own rating, 50 N*m (actuatorfrcrange)" in line]
    assert len(below) == 4 and all("max_effort 35 N*m is 30 % below" in line for line in below)
    assert len(lines) == 4  # no actuatorfrcrange that cannot bind, no hip line (139 = 139)
    # it stands: the key's pose held for 2 s under the drives (pelvis height stays near 0.79 m)
    data = mujoco.MjData(result)
    mujoco.mj_resetDataKeyframe(result, data, 0)
    for _ in range(1000):
        mujoco.mj_step(result, data)
    assert math.isfinite(data.qpos[2]) and abs(data.qpos[2] - 0.79) < 0.03


# a new user's findings on the MuJoCo adapter: show lists tendon and site actuators, map errors name
# the file and key, a missing gain is named, every digit is written, a tighter forcerange is a warning

TENDON = '<motor name="tm" tendon="t"/><motor name="twist" site="tip" gear="0 0 0 0 1 0"/>'


def _tendon_arm(tmp_path: Path, extra: str = "") -> Path:
    """Write the arm (shoulder, elbow, slider; a tendon, a site) as arm.xml, the docs' file name."""
    path = tmp_path / "arm.xml"
    path.write_text(TENDON_ARM.format(extra=extra))
    return path


def _menagerie(name: str) -> Path:
    path = MENAGERIE / name
    if not path.is_file():
        pytest.skip(f"needs {path} (../shared/data/menagerie, not part of a user's clone)")
    return path


def test_show_lists_tendon_and_site_actuators_that_bypass_drives(
    mujoco: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A motor on a fixed tendon through two driven joints, a site motor below them: listed, warned once."""
    arm = _tendon_arm(tmp_path, TENDON)
    joint_map = tmp_path / "m2.toml"
    joint_map.write_text('[joints]\nshoulder = "tmotor-ak80-6"\nelbow = "tmotor-ak80-6"\n')
    out = tmp_path / "o2.xml"
    assert _cli("mujoco", "apply", str(arm), "--map", str(joint_map), "--stiffness", "10", "--damping", "1",
                "-o", str(out)) == 0  # fmt: skip
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "also acts on" in line]
    assert len(lines) == 2, err  # one per actuator, each naming every driven joint it reaches
    assert "actuator 'tm' (motor on tendon 't') also acts on driven joint(s) 'shoulder' (drive 'ps'), " \
        "'elbow' (drive 'el')" in lines[0]  # fmt: skip
    assert "actuator 'twist' (motor on site 'tip')" in lines[1]
    assert _cli("mujoco", "show", str(out), "--json") == 0
    others = json.loads(capsys.readouterr().out)["other_actuators"]
    reached = {(o["actuator"], o["joint"]): o["bypasses_drive"] for o in others}
    assert reached[("tm", "shoulder")] == "ps" and reached[("tm", "elbow")] == "el"
    assert reached[("twist", "shoulder")] == "ps" and reached[("twist", "elbow")] == "el"
    assert reached[("sm", "slider")] is None and ("tm", "slider") not in reached
    assert next(o for o in others if o["actuator"] == "tm")["transmission"] == "tendon 't'"
    assert _cli("mujoco", "show", str(out)) == 0
    text = capsys.readouterr().out
    assert re.search(r"shoulder\s+tm\s+motor\s+tendon 't'\s+ps", text), text


def test_a_map_error_names_the_map_file_and_key(mujoco: Any, tmp_path: Path) -> None:
    """A revolute envelope on a slide joint: the map file and key, then the joint and the reason."""
    joint_map = tmp_path / "m.toml"
    joint_map.write_text('[joints]\nslider = "tmotor-ak80-6"\n')
    out = tmp_path / "o4.xml"
    argv = ("mujoco", "apply", str(_tendon_arm(tmp_path)), "--map", str(joint_map), "--stiffness", "10",
            "--damping", "1", "-o", str(out))  # fmt: skip
    with pytest.raises(InputError) as info:
        _cli(*argv)
    assert str(info.value) == (
        f"{joint_map}: key 'joints.slider': joint 'slider': the envelope is for a revolute joint but "
        "'slider' is prismatic"
    )
    assert not out.exists()


@pytest.mark.parametrize(
    ("given", "asked"),
    [
        (("--stiffness", "60"), "give --damping too (--stiffness is given)"),
        (("--damping", "2"), "give --stiffness too (--damping is given)"),
        ((), "give --stiffness and --damping"),
    ],
)
def test_a_motor_without_gains_names_the_missing_one(
    mujoco: Any, tmp_path: Path, given: tuple[str, ...], asked: str
) -> None:
    """Say which of --stiffness and --damping is missing, not both when one was given."""
    argv = ("mujoco", "apply", str(_tendon_arm(tmp_path)), "--joint", "elbow", "--datasheet", "tmotor-ak80-6",
            *given, "-o", str(tmp_path / "o.xml"))  # fmt: skip
    with pytest.raises(
        InputError, match=re.escape(f"its actuator 'el' is a motor (no position gains to keep); {asked}")
    ):
        _cli(*argv)


NEVER_NEGATIVE = "(a drive gain is never negative)"


@pytest.mark.parametrize(
    ("given", "message"),
    [
        (("--stiffness", "-60", "--damping", "2"),
         f"--stiffness '-60': expected a number in [0, 1e12] [N*m/rad] {NEVER_NEGATIVE}, got -60.0"),
        (("--stiffness", "60", "--damping", "-2"),
         f"--damping '-2': expected a number in [0, 1e12] [N*m*s/rad] {NEVER_NEGATIVE}, got -2.0"),
        (("--stiffness", "inf", "--damping", "2"),
         "--stiffness 'inf': expected a number in [0, 1e12] [N*m/rad], got inf"),
        (("--stiffness", "60 N", "--damping", "2"), "--stiffness '60 N': "),
    ],
)  # fmt: skip
def test_a_bad_gain_flag_names_the_flag_not_the_map_key(
    mujoco: Any, tmp_path: Path, given: tuple[str, ...], message: str
) -> None:
    """`mujoco apply --map ... --stiffness -60` (issue 26): the flag, its value and range, not the map key."""
    joint_map = tmp_path / "m.toml"
    joint_map.write_text('[joints]\nelbow = "tmotor-ak80-6"\n')
    out = tmp_path / "o.xml"
    for source in (("--map", str(joint_map)), ("--joint", "elbow", "--datasheet", "tmotor-ak80-6")):
        with pytest.raises(InputError) as info:
            _cli("mujoco", "apply", str(_tendon_arm(tmp_path)), *source, *given, "-o", str(out))
        assert str(info.value).startswith(message) and "\n" not in str(info.value)
    assert not out.exists()


def test_go2_hip_with_only_stiffness_asks_for_damping(mujoco: Any, tmp_path: Path) -> None:
    """The user's command on the Menagerie Go2."""
    argv = ("mujoco", "apply", str(_menagerie("go2.xml")), "--joint", "FL_hip_joint", "--datasheet",
            "tmotor-ak80-6", "--stiffness", "60", "-o", str(tmp_path / "o.xml"))  # fmt: skip
    with pytest.raises(
        InputError, match=r"'FL_hip' is a motor .*; give --damping too \(--stiffness is given\)$"
    ):
        _cli(*argv)


DEGREES = """<mujoco><compiler angle="degree"/><worldbody><body><joint name="j" range="-90 90"
armature="0.0123456789012345"/><geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"
mass="0.123456789012345"/></body></worldbody><actuator><position name="a" joint="j" kp="10"/>
</actuator></mujoco>"""


def test_apply_writes_every_number_with_every_digit(mujoco: Any, tmp_path: Path, capsys: Any) -> None:
    """Degrees become radians with all 17 digits; masses and armatures keep theirs; no notice."""
    source = tmp_path / "deg.xml"
    source.write_text(DEGREES)
    out = tmp_path / "deg_env.xml"
    assert _cli("mujoco", "apply", str(source), "--joint", "j", "--datasheet", "tmotor-ak80-6",
                "-o", str(out)) == 0  # fmt: skip
    assert "digits" not in capsys.readouterr().err
    original, written = mujoco.MjModel.from_xml_path(str(source)), mujoco.MjModel.from_xml_path(str(out))
    assert written.jnt_range[0, 1] == 1.5707963267948966 == original.jnt_range[0, 1]
    assert written.body_mass[1] == original.body_mass[1] and written.dof_armature[0] == 0.0123456789012345
    text = out.read_text()
    assert 'range="-1.5707963267948966 1.5707963267948966"' in text and "0000000000" not in text


def test_a_writer_that_rounds_is_one_line_on_stderr(
    mujoco: Any, tmp_path: Path, capsys: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without MuJoCo's precision entry point the written numbers lose digits: say so, on one line."""
    from drive_envelope._src.adapters.mujoco import precision

    monkeypatch.setattr(precision, "_setter", lambda: None)
    source = tmp_path / "deg.xml"
    source.write_text(DEGREES)
    out = tmp_path / "deg_env.xml"
    assert _cli("mujoco", "apply", str(source), "--joint", "j", "--datasheet", "tmotor-ak80-6",
                "-o", str(out)) == 0  # fmt: skip
    notices = [line for line in capsys.readouterr().err.splitlines() if "digits" in line]
    assert len(notices) == 1 and re.search(r"differ by up to \S+ relative \(e\.g\. \w+\[", notices[0]), (
        notices
    )
    assert mujoco.MjModel.from_xml_path(str(out)).jnt_range[0, 1] == 1.5708


def test_panda_compiles_to_the_same_numbers_after_apply(mujoco: Any, tmp_path: Path) -> None:
    """The Menagerie Panda's masses, inertias, ranges and geom sizes survive apply exactly."""
    panda = _menagerie("panda.xml")
    out = tmp_path / "panda_env.xml"
    assert _cli("mujoco", "apply", str(panda), "--map", "franka-panda", "-o", str(out)) == 0
    original, written = mujoco.MjModel.from_xml_path(str(panda)), mujoco.MjModel.from_xml_path(str(out))
    for field in ("body_mass", "body_inertia", "jnt_range", "geom_size", "body_quat", "body_iquat"):
        np.testing.assert_allclose(getattr(written, field), getattr(original, field), rtol=1e-12, atol=0)


FORCE_RANGE = """<mujoco><worldbody><body><joint name="shoulder" type="hinge"/><geom size="0.1" mass="1"/>
</body><body pos="1 0 0"><joint name="elbow" type="hinge"/><geom size="0.1" mass="1"/></body></worldbody>
<actuator><motor name="ms" joint="shoulder" forcerange="-5 5"/>
<motor name="me" joint="elbow" forcerange="-20 20"/></actuator></mujoco>"""


def test_a_tighter_force_range_that_the_drive_replaces_is_a_warning(
    mujoco: Any, tmp_path: Path, capsys: Any
) -> None:
    """The AK80-6's 12 N*m replaces a 5 N*m forcerange (warned) and a 20 N*m one (nothing to say)."""
    model = tmp_path / "fr.xml"
    model.write_text(FORCE_RANGE, encoding="utf-8")
    for joint in ("shoulder", "elbow"):
        out = tmp_path / f"{joint}.xml"
        argv = ["mujoco", "apply", str(model), "--joint", joint, "--datasheet", "tmotor-ak80-6",
                "--stiffness", "10", "--damping", "1", "-o", str(out)]  # fmt: skip
        assert _cli(*argv) == 0
        err = capsys.readouterr().err
        if joint == "shoulder":
            assert (
                "actuator 'ms' had forcerange [-5, 5] N*m, tighter than the envelope's max_effort 12 N*m"
                in err
            )
        else:  # not tighter, but 40 % above the cap: the report says the sources disagree
            assert "had forcerange" not in err
            rating = "max_effort 12 N*m is 40 % below the model's own rating, 20 N*m (forcerange of 'me')"
            assert f"{rating} on elbow" in err

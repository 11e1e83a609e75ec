"""Regression tests for a new user's findings on the MuJoCo adapter, one group per finding.

1. Every function that takes a drive finds it the same way (MjDrive, MjDriveInfo, names, indices).
2. ``mujoco show`` lists tendon and site actuators that reach a driven joint; ``apply`` says it once.
3. A map error names the map file and key.
4. A missing gain is named.
5. ``mujoco apply`` writes every number with every digit (or says that it could not).
6. ``MjData`` refused by the plugin: the reason is the warning before MuJoCo's FatalError.
7. The documented snippet runs as written; set_envelope & co. take a joint name.
8. Constraint forces act after the drives: the coupled solve is exact at the velocity it predicts.

Real inputs: the Menagerie Go2 and Panda in ``../shared/data/menagerie`` (skipped when absent).
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import InputError, PerformanceEnvelope

pytestmark = pytest.mark.mujoco

ROOT = Path(__file__).resolve().parents[1]
MENAGERIE = ROOT.parent / "shared" / "data" / "menagerie"

ARM = """<mujoco model="arm"><compiler angle="radian"/><option timestep="0.002"/>
<worldbody><body name="l1" pos="0 0 1"><joint name="shoulder" axis="0 1 0" range="-1.5 1.5"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="elbow" axis="0 1 0" range="-2 0"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="slider" type="slide" axis="1 0 0" range="-0.1 0.1"/>
<geom type="sphere" size="0.03"/><site name="tip"/></body></body></body></worldbody>
<tendon><fixed name="t"><joint joint="shoulder" coef="1"/><joint joint="elbow" coef="-1"/></fixed></tendon>
<actuator><position name="ps" joint="shoulder" kp="100" kv="5"/><motor name="el" joint="elbow"/>
<motor name="sm" joint="slider"/>{extra}</actuator></mujoco>"""
TENDON = '<motor name="tm" tendon="t"/><motor name="twist" site="tip" gear="0 0 0 0 1 0"/>'


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


def _cli(*argv: str) -> int:
    from drive_envelope._src.cli.commands import mujoco as command

    parser = argparse.ArgumentParser(prog="drive-envelope")
    command.register(parser.add_subparsers())
    args = parser.parse_args(argv)
    return int(args.func(args))


def _menagerie(name: str) -> Path:
    path = MENAGERIE / name
    if not path.is_file():
        pytest.skip(f"needs {path} (../shared/data/menagerie, not part of a user's clone)")
    return path


def _arm(tmp_path: Path, extra: str = "") -> Path:
    path = tmp_path / "arm.xml"
    path.write_text(ARM.format(extra=extra))
    return path


def _driven_arm(mujoco: Any) -> tuple[Any, Any, tuple[Any, ...]]:
    from drive_envelope.mujoco import add_drives

    spec = mujoco.MjSpec.from_string(ARM.format(extra=""))
    drives = add_drives(
        spec, ["shoulder", "elbow"], datasheet="tmotor-ak80-6", stiffness=30, damping=1, replace=True
    )
    return spec, spec.compile(), drives


# -- 1. one lookup for every function that takes a drive ----------------------------------------


def test_drive_state_takes_every_kind_of_drive_reference(mujoco: Any) -> None:
    """MjDriveInfo from model_drives, MjDrive, actuator name, index (numpy too) and joint name agree."""
    from drive_envelope.mujoco import drive_state, get_envelope, get_gains, model_drives

    _, model, drives = _driven_arm(mujoco)
    data = mujoco.MjData(model)
    drives[1].set_targets(model, data, position=-1.0)
    mujoco.mj_step(model, data)
    info = model_drives(model)[1]
    index = info.actuator
    refs = [drives[1], info, "el", index, np.int64(index), "elbow"]
    states = {drive_state(model, data, ref) for ref in refs}
    assert len(states) == 1 and next(iter(states))[1] != 0.0
    assert {get_gains(model, ref) for ref in refs} == {(30.0, 1.0)}
    assert {get_envelope(model, ref).max_effort for ref in refs} == {info.envelope.max_effort}


@pytest.mark.parametrize("bad", [1.5, None, ["el"], True])
def test_a_drive_of_another_type_is_an_input_error_naming_argument_and_type(mujoco: Any, bad: Any) -> None:
    """Never a TypeError from mj_name2id: one line naming the argument and the type given."""
    from drive_envelope.mujoco import drive_state, set_envelope

    _, model, _ = _driven_arm(mujoco)
    data = mujoco.MjData(model)
    kind = type(bad).__name__
    with pytest.raises(InputError, match=rf"drive_state: argument 'drive': expected .* got {kind}$"):
        drive_state(model, data, bad)
    with pytest.raises(InputError, match=rf"argument 'actuator': expected .* got {kind}$"):
        set_envelope(model, bad, "tmotor-ak80-6")


def test_a_handle_of_another_model_is_refused(mujoco: Any) -> None:
    """An MjDriveInfo or MjDrive that is not a drive of this model is named, with the model's drives."""
    from drive_envelope.mujoco import add_drive, drive_state, model_drives, rollout_operating_points

    _, model, _ = _driven_arm(mujoco)
    spec = mujoco.MjSpec.from_string(ARM.format(extra=""))
    slider = add_drive(spec, "slider", datasheet="actuonix-l16-35-6-r", stiffness=10, damping=1, replace=True)
    other = spec.compile()
    with pytest.raises(InputError, match=r"MjDriveInfo 'sm' \(joint 'slider'\) is not a drive of this model"):
        drive_state(model, mujoco.MjData(model), model_drives(other)[0])
    with pytest.raises(InputError, match=r"MjDrive 'sm' .* its drives: 'ps', 'el'"):
        drive_state(model, mujoco.MjData(model), slider)
    # rollouts find the effort sensor from any reference
    states = np.zeros((1, 3, 1 + other.nq + other.nv))
    sensors = np.arange(3.0).reshape(1, 3, 1)
    velocity, effort = rollout_operating_points(other, "slider", states, sensors)
    assert effort.tolist() == [[0.0, 1.0, 2.0]] and velocity.shape == (1, 3)


# -- 2. show lists the actuators that reach a driven joint; apply says it once ------------------


def test_show_lists_tendon_and_site_actuators_that_bypass_drives(
    mujoco: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A motor on a fixed tendon through two driven joints, a site motor below them: listed, warned once."""
    arm = _arm(tmp_path, TENDON)
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


# -- 3. a map error names the map file and key --------------------------------------------------


def test_a_map_error_names_the_map_file_and_key(mujoco: Any, tmp_path: Path) -> None:
    """A revolute envelope on a slide joint: the map file and key, then the joint and the reason."""
    joint_map = tmp_path / "m.toml"
    joint_map.write_text('[joints]\nslider = "tmotor-ak80-6"\n')
    out = tmp_path / "o4.xml"
    argv = ("mujoco", "apply", str(_arm(tmp_path)), "--map", str(joint_map), "--stiffness", "10",
            "--damping", "1", "-o", str(out))  # fmt: skip
    with pytest.raises(InputError) as info:
        _cli(*argv)
    assert str(info.value) == (
        f"{joint_map}: key 'joints.slider': joint 'slider': the envelope is for a revolute joint but "
        "'slider' is prismatic"
    )
    assert not out.exists()


# -- 4. the missing gain is named ---------------------------------------------------------------


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
    argv = ("mujoco", "apply", str(_arm(tmp_path)), "--joint", "elbow", "--datasheet", "tmotor-ak80-6",
            *given, "-o", str(tmp_path / "o.xml"))  # fmt: skip
    with pytest.raises(
        InputError, match=re.escape(f"its actuator 'el' is a motor (no position gains to keep); {asked}")
    ):
        _cli(*argv)


def test_go2_hip_with_only_stiffness_asks_for_damping(mujoco: Any, tmp_path: Path) -> None:
    """The user's command on the Menagerie Go2."""
    argv = ("mujoco", "apply", str(_menagerie("go2.xml")), "--joint", "FL_hip_joint", "--datasheet",
            "tmotor-ak80-6", "--stiffness", "60", "-o", str(tmp_path / "o.xml"))  # fmt: skip
    with pytest.raises(
        InputError, match=r"'FL_hip' is a motor .*; give --damping too \(--stiffness is given\)$"
    ):
        _cli(*argv)


# -- 5. every digit -----------------------------------------------------------------------------

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


# -- 6. an MjData the plugin refuses ------------------------------------------------------------


def test_the_reason_for_a_refused_mjdata_is_the_warning_before_it(mujoco: Any) -> None:
    """timestep = 0 after compiling: MuJoCo's FatalError, the plugin's reason just before; documented."""
    _, model, _ = _driven_arm(mujoco)
    model.opt.timestep = 0.0
    seen: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(seen.append)
    try:
        with pytest.raises(mujoco.FatalError, match="plugin->init failed"):
            mujoco.MjData(model)
    finally:
        mujoco.set_mju_user_warning(previous)
    assert any("option 'timestep' = 0: expected a finite number > 0 [s]" in w for w in seen)
    docs = (ROOT / "docs" / "mujoco.md").read_text()
    assert "initPluginOrFree: plugin->init failed" in docs and "option 'timestep' = 0" in docs


# -- 7. the documented snippet; joint names -----------------------------------------------------


def test_the_documented_snippet_runs_as_written(
    mujoco: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Run the first python block of docs/mujoco.md on an arm whose elbow has a motor named 'el'."""
    docs = (ROOT / "docs" / "mujoco.md").read_text()
    snippet = re.search(r"```python\n(.*?)```", docs, flags=re.DOTALL)
    assert snippet is not None
    _arm(tmp_path)
    monkeypatch.chdir(tmp_path)
    scope: dict[str, Any] = {}
    exec(compile(snippet.group(1), "docs/mujoco.md", "exec"), scope)  # our own docs
    from drive_envelope.mujoco import get_envelope

    assert scope["elbow"].name == "el" and scope["elbow"].replaced == ("el",)
    assert scope["elbow"].envelope.contains(scope["velocity"], scope["effort"], atol=1e-9).item()
    assert get_envelope(scope["model"], "el").max_effort == get_envelope(scope["model"], "elbow").max_effort
    assert get_envelope(scope["model"], "el").max_effort != scope["elbow"].envelope.max_effort


def test_set_envelope_and_gains_take_a_joint_name_and_suggest_near_names(mujoco: Any) -> None:
    """Actuator name first, then the driven joint; an unknown name gets the nearest ones."""
    from drive_envelope.mujoco import get_gains, set_envelope, set_gains

    _, model, _ = _driven_arm(mujoco)
    set_gains(model, "elbow", stiffness=12.0)
    assert get_gains(model, "el") == (12.0, 1.0)
    set_envelope(model, "shoulder", PerformanceEnvelope(max_effort=3.0))
    assert model.actuator_dynprm[0, 0] == 3.0
    with pytest.raises(InputError, match=r"no actuator named 'elbw' and no driven joint .*'elbow'"):
        set_envelope(model, "elbw", PerformanceEnvelope(max_effort=1.0))
    with pytest.raises(
        InputError, match=r"joint 'slider' has no envelope drive; its drives .*'el' on 'elbow'"
    ):
        get_gains(model, "slider")
    with pytest.raises(InputError, match=r"actuator 'sm' is not a drive"):
        get_gains(model, "sm")


# -- 8. constraints act after the drives --------------------------------------------------------

WHIP = """<mujoco><compiler angle="radian"/><option timestep="0.002" gravity="0 0 0" integrator="Euler"/>
<extension><plugin plugin="drive_envelope.envelope"><instance name="v"><config key="input" value="vel"/>
</instance></plugin></extension>
<worldbody><body><joint name="a" axis="0 0 1" range="-0.2 0.2"/>
<geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.03" mass="1"/>
<body pos="0.5 0 0"><joint name="b" axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.03"
mass="1"/></body></body></worldbody>
<actuator><plugin name="drive" joint="b" instance="v" dynprm="20 1 0 0 0 50"/></actuator></mujoco>"""


def _free_step(mujoco: Any, free: Any, free_data: Any, data: Any) -> None:
    """Step ``free`` (constraints disabled) from the state of ``data``."""
    free_data.qpos[:], free_data.qvel[:], free_data.ctrl[:] = data.qpos, data.qvel, data.ctrl
    free_data.time = data.time
    mujoco.mj_step(free, free_data)


def test_a_joint_limit_moves_a_coupled_drive_past_its_envelope(mujoco: Any) -> None:
    """The drive is inside at the velocity it predicts; the limit's impulse, solved after it, is not."""
    model = mujoco.MjModel.from_xml_string(WHIP)
    free = mujoco.MjModel.from_xml_string(WHIP)
    free.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    data, free_data = mujoco.MjData(model), mujoco.MjData(free)
    data.qvel[0], data.ctrl[0] = 4.0, 0.9  # joint a swings into its limit; b's drive holds 0.9 < 1 rad/s
    env = PerformanceEnvelope(max_effort=20.0, max_actuator_velocity=1.0)
    while data.nefc == 0:
        _free_step(mujoco, free, free_data, data)
        mujoco.mj_step(model, data)
        assert data.time < 0.2
    # the step the limit acts: same effort, inside at the predicted velocity, outside after the limit
    assert data.actuator_force[0] == free_data.actuator_force[0] > 0.0
    assert env.contains(free_data.qvel[1], free_data.actuator_force[0]).item()
    assert data.qvel[1] > 2.5 and not env.contains(data.qvel[1], data.actuator_force[0]).item()


def test_panda_leaves_its_envelope_only_through_constraint_forces(mujoco: Any, tmp_path: Path) -> None:
    """The user's Panda run (Euler): outside samples only with constraint rows; 0 replayed without them."""
    from drive_envelope.mujoco import model_drives

    out = tmp_path / "panda_env.xml"
    assert _cli("mujoco", "apply", str(_menagerie("panda.xml")), "--map", "franka-panda", "-o", str(out)) == 0
    model, free = mujoco.MjModel.from_xml_path(str(out)), mujoco.MjModel.from_xml_path(str(out))
    for m in (model, free):
        m.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    free.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    data, free_data = mujoco.MjData(model), mujoco.MjData(free)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    drives = model_drives(model)
    acts = [d.actuator for d in drives]
    dofs = [int(model.jnt_dofadr[model.actuator_trnid[a, 0]]) for a in acts]
    home = data.ctrl[acts].copy()

    def outside(velocity: float, effort: float, env: PerformanceEnvelope) -> float:
        if abs(effort) <= 1e-6 * env.max_effort and abs(velocity) > env.max_actuator_velocity:
            return 0.0  # released
        effort_margin, velocity_margin = env.margins(velocity, effort)
        return float(max(-effort_margin / env.max_effort, -velocity_margin / env.max_actuator_velocity))

    count, worst, free_worst = 0, 0.0, 0.0
    for _ in range(1500):
        data.ctrl[acts] = home + 0.6 * np.sin(2 * np.pi * 3 * data.time)
        _free_step(mujoco, free, free_data, data)
        mujoco.mj_step(model, data)
        np.testing.assert_array_equal(free_data.actuator_force[acts], data.actuator_force[acts])
        for dof, a, drive in zip(dofs, acts, drives, strict=True):
            assert drive.envelope is not None
            free_worst = max(
                free_worst, outside(free_data.qvel[dof], free_data.actuator_force[a], drive.envelope)
            )
            miss = outside(data.qvel[dof], data.actuator_force[a], drive.envelope)
            if miss > 1e-6:
                assert data.nefc > 0
                count, worst = count + 1, max(worst, miss)
    assert free_worst <= 1e-6  # the coupled solve is exact at the velocity it predicts
    assert count > 100 and worst > 0.15  # docs/mujoco.md: 869 of 14000 in 2000 steps, worst 18.8 %


def test_the_docs_give_the_panda_numbers_and_the_cause() -> None:
    """docs/mujoco.md names the constraint rows behind the Panda's samples outside."""
    docs = (ROOT / "docs" / "mujoco.md").read_text()
    section = docs.split("### Constraints act after the drives", 1)[1].split("###", 1)[0]
    for fact in ("869", "18.8 %", "1803", "727", "joint limits", "equality", "0 samples outside"):
        assert fact in section, fact
    assert section.count("|") > 10  # the table


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

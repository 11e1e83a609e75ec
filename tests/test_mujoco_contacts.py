"""``mujoco apply`` says where a driven joint's body overlaps its parent in the model's own poses.

Golden values by hand: a base box of half-size 0.05 m at z = 0, welded to the world, and a link box
of the same size at z = 0.09 m on a hinge about z: the boxes overlap by 0.05 + 0.05 - 0.09 = 0.01 m
in every angle of the hinge. Real input: Menagerie's Kinova Gen3, whose base_link and shoulder_link
meshes overlap in every pose (skipped when ``../shared`` is absent).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import pytest

from _mujoco_plugin import mujoco_with_plugin

pytestmark = pytest.mark.mujoco

MENAGERIE = Path(__file__).resolve().parents[2] / "shared" / "data" / "menagerie"
ENVELOPE = "max_effort = 8.0\nmax_actuator_velocity = 12.0\n"


def _arm(base_joint: str = "", extra: str = "") -> str:
    return (
        "<mujoco><worldbody><body name='base'>" + base_joint + "<geom type='box' size='0.05 0.05 0.05'/>"
        "<body name='link' pos='0 0 0.09'><joint name='turn' axis='0 0 1'/>"
        "<geom type='box' size='0.05 0.05 0.05'/></body></body></worldbody>"
        f"{extra}<actuator><position name='p' joint='turn' kp='50'/></actuator>"
        "<keyframe><key name='home' qpos='"
        + ("0 0 0 1 0 0 0 " if base_joint else "")
        + "0.5'/></keyframe></mujoco>"
    ).replace("'", '"')


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


def _apply(model: Path, out: Path, envelope: Path) -> int:
    from drive_envelope._src.cli.commands import mujoco as command

    parser = argparse.ArgumentParser(prog="drive-envelope")
    command.register(parser.add_subparsers())
    args = parser.parse_args(
        ["mujoco", "apply", str(model), "--joint", "turn", "--envelope", str(envelope), "-o", str(out)]
    )
    return int(args.func(args))


def test_a_link_overlapping_its_world_welded_base_is_found_in_every_pose(mujoco: Any) -> None:
    """Name the pair, its joint, the poses, the contact count and the 10 mm depth."""
    from drive_envelope._src.adapters.mujoco.contacts import neighbour_contact_warnings, neighbour_contacts

    model = mujoco.MjModel.from_xml_string(_arm())
    (found,) = neighbour_contacts(model)
    assert (found.parent, found.child, found.joints) == ("base", "link", ("turn",))
    assert found.poses == ("qpos0", "keyframe 'home'")
    assert found.contacts >= 1
    assert found.depth == pytest.approx(0.01, abs=1e-9)
    (line,) = neighbour_contact_warnings([found], ["turn"])
    assert line.startswith("bodies 'base' and 'link' (driven joint 'turn' between them) overlap at qpos0, ")
    assert "10 mm deep" in line and '<contact><exclude body1="base" body2="link"/></contact>' in line
    assert neighbour_contact_warnings([found], ["other"]) == []  # an undriven joint: not ours to say


@pytest.mark.parametrize(
    ("base_joint", "extra"),
    [
        ("", "<contact><exclude body1='base' body2='link'/></contact>"),  # the fix the warning gives
        ("<freejoint/>", ""),  # a floating base: MuJoCo's parent filter skips the pair itself
    ],
    ids=["excluded", "floating-base"],
)
def test_pairs_mujoco_does_not_collide_are_not_reported(mujoco: Any, base_joint: str, extra: str) -> None:
    """Say nothing where MuJoCo makes no contact between the pair."""
    from drive_envelope._src.adapters.mujoco.contacts import neighbour_contacts

    model = mujoco.MjModel.from_xml_string(_arm(base_joint, extra))
    assert neighbour_contacts(model) == []


def test_apply_warns_about_the_overlap_naming_the_input(
    mujoco: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One stderr line naming the input model; the output is written all the same."""
    model, out, envelope = tmp_path / "arm.xml", tmp_path / "out.xml", tmp_path / "joint.toml"
    model.write_text(_arm(), encoding="utf-8")
    envelope.write_text(ENVELOPE, encoding="utf-8")
    assert _apply(model, out, envelope) == 0
    (line,) = [line for line in capsys.readouterr().err.splitlines() if "overlap at" in line]
    prefix = f"drive-envelope: warning: {model}: bodies 'base' and 'link' (driven joint 'turn' between them) "
    assert line.startswith(prefix + "overlap at qpos0, keyframe 'home' (")
    assert line.endswith(
        " contacts, 10 mm deep): MuJoCo filters parent-child contacts only where the parent is not welded "
        "to the world, so the joint grinds on its parent and its drive saturates; add <contact><exclude "
        'body1="base" body2="link"/></contact> if the overlap is not meant'
    )
    assert out.exists()


def test_menagerie_gen3_base_and_shoulder_overlap(mujoco: Any) -> None:
    """Menagerie's Gen3: base_link and shoulder_link, 4 contacts, 12 mm, at qpos0 and both keyframes."""
    scene = MENAGERIE / "kinova_gen3" / "scene.xml"
    if not scene.exists():
        pytest.skip(f"{scene} is absent (see ../shared/data/README.md)")
    from drive_envelope._src.adapters.mujoco.contacts import neighbour_contacts

    (found,) = neighbour_contacts(mujoco.MjModel.from_xml_path(str(scene)))
    assert (found.parent, found.child, found.joints) == ("base_link", "shoulder_link", ("joint_1",))
    assert found.poses == ("qpos0", "keyframe 'home'", "keyframe 'retract'")
    assert found.contacts == 4
    assert found.depth == pytest.approx(0.012, abs=1e-4)

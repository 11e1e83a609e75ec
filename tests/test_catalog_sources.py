"""Catalog entries from machine-readable vendor files against a transcription of each element (issue 23).

Every entry whose source is a machine-readable file (a URDF, a xacro, ROBOTIS' e-Manual data file, a
Python config module such as Isaac Lab's actuator configs) must name the file at a pinned revision and
the element, and its numbers must be the element's. The element texts below were copied from the files
at the revisions named (read on 2026-12-02 from unitreerobotics/unitree_ros @ d6f13aad and
ROBOTIS-GIT/emanual @ 00280385 and @ 1a5e5fbe, on 2026-12-03 from Kinovarobotics/ros_kortex @ 5fce8b7a
and isaac-sim/IsaacLab @ f0ca71b4); fetched files are not committed, so the transcription lives here.
The numbers are read back from the quoted text with the library's own unit reader, and compared with
what the catalog entry derives.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

import pytest

from drive_envelope._src.datasheet.catalog import load_catalog_datasheet
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.units import to_si

CATALOG = Path(__file__).resolve().parents[1] / "src" / "drive_envelope" / "catalog"
UNITREE = (
    "https://github.com/unitreerobotics/unitree_ros/blob/d6f13aad60320ce1d60a07b82a76b5a553f2a0a9/robots/"
)
DXL_X = "https://github.com/ROBOTIS-GIT/emanual/blob/00280385680aba081862d0854c95de523c6391e6/_data/dxl_x_info.yml"
DXL_P = "https://github.com/ROBOTIS-GIT/emanual/blob/1a5e5fbeb6c41e261a1c67ba74e1cb3ec728072e/_data/dxl_p_info.yml"
KORTEX_GEN3 = (
    "https://github.com/Kinovarobotics/ros_kortex/blob/5fce8b7ab9b957834696d02c725f44efc931392b/"
    "kortex_description/arms/gen3/7dof/urdf/gen3_macro.xacro"
)
ISAACLAB_ANYMAL = (
    "https://github.com/isaac-sim/IsaacLab/blob/f0ca71b4aa58c3d4284b0ca39500762fbda5d3dd/"
    "source/isaaclab_assets/isaaclab_assets/robots/anymal.py"
)


class Element(NamedTuple):
    """One vendor element: the file at its revision, the element's name, its text as the file has it."""

    url: str
    name: str
    text: str


def urdf(path: str, joint: str, limit: str) -> Element:
    return Element(UNITREE + path, joint, limit)


def dxl(key: str, stall: str, no_load: str) -> Element:
    """The e-Manual's entry ``key``: the stall torque and no-load speed at the rated voltage."""
    return Element(DXL_X, key, f'stalltorque: "{stall}" noloadspeed: "{no_load}"')


def dxl_p(key: str, no_load: str, cont_speed: str, cont_torque: str) -> Element:
    """The DYNAMIXEL-P entry ``key``: no-load speed and the continuous point (speed at its torque)."""
    text = f'noloadspeed: "{no_load}" contspeed: "{cont_speed}" conttorque: "{cont_torque}"'
    return Element(DXL_P, key, text)


G1 = "g1_description/g1_29dof.urdf"
GO2 = "go2_description/urdf/go2_description.urdf"
H1 = "h1_description/urdf/h1.urdf"

TRANSCRIPTION: dict[str, Element] = {
    "unitree-g1-4010": urdf(
        G1,
        "left_wrist_pitch_joint",
        '<limit effort="5" velocity="22" lower="-1.614429558" upper="1.614429558"/>',
    ),
    "unitree-g1-5020": urdf(
        G1, "left_shoulder_pitch_joint", '<limit lower="-3.0892" upper="2.6704" effort="25" velocity="37"/>'
    ),
    "unitree-g1-7520-14": urdf(
        G1, "left_hip_pitch_joint", '<limit lower="-2.5307" upper="2.8798" effort="88" velocity="32"/>'
    ),
    "unitree-g1-7520-22": urdf(
        G1, "left_knee_joint", '<limit lower="-0.087267" upper="2.8798" effort="139" velocity="20"/>'
    ),
    "unitree-g1-ankle": urdf(
        G1, "left_ankle_pitch_joint", '<limit lower="-0.87267" upper="0.5236" effort="35" velocity="30"/>'
    ),
    "unitree-go-m8010-6": urdf(
        GO2, "FL_hip_joint", '<limit lower="-1.0472" upper="1.0472" effort="23.7" velocity="30.1" />'
    ),
    "unitree-go2-calf": urdf(
        GO2, "FL_calf_joint", '<limit lower="-2.7227" upper="-0.83776" effort="45.43" velocity="15.70" />'
    ),
    "unitree-h1-ankle": urdf(
        H1, "left_ankle_joint", '<limit lower="-0.87" upper="0.52" effort="40" velocity="9"/>'
    ),
    "unitree-h1-arm": urdf(
        H1, "left_elbow_joint", '<limit lower="-1.25" upper="2.61" effort="18" velocity="20"/>'
    ),
    "unitree-h1-hip": urdf(
        H1, "left_hip_pitch_joint", '<limit lower="-3.14" upper="2.53" effort="200" velocity="23"/>'
    ),
    "unitree-h1-knee": urdf(
        H1, "left_knee_joint", '<limit lower="-0.26" upper="2.05" effort="300" velocity="14"/>'
    ),
    "unitree-a1-motor": Element(
        UNITREE + "a1_description/xacro/const.xacro",
        "hip_torque_max",
        '<xacro:property name="hip_velocity_max" value="21"/> '
        '<xacro:property name="hip_torque_max" value="33.5"/>',
    ),
    "unitree-go1-joint": Element(
        UNITREE + "go1_description/xacro/const.xacro",
        "hip_torque_max",
        '<xacro:property name="hip_velocity_max" value="30.1"/> '
        '<xacro:property name="hip_torque_max" value="23.7"/>',
    ),
    # Kinova's Gen3 xacro: the joints are named "${prefix}joint_N"; joint_2 and joint_6 print their limit on
    # one line (joint_1, 3, 4 and 5, 7 print the same effort and velocity)
    "kinova-gen3-large": Element(
        KORTEX_GEN3,
        "${prefix}joint_2",
        '<limit lower="-2.41" upper="2.41" effort="39" velocity="1.3963" />',
    ),
    "kinova-gen3-small": Element(
        KORTEX_GEN3,
        "${prefix}joint_6",
        '<limit lower="-2.23" upper="2.23" effort="9" velocity="1.2218" />',
    ),
    # Isaac Lab's ANYdrive 3 DC motor config (NVIDIA's actuator model, SI joint units)
    "anybotics-anydrive-3": Element(
        ISAACLAB_ANYMAL,
        "ANYDRIVE_3_SIMPLE_ACTUATOR_CFG",
        "ANYDRIVE_3_SIMPLE_ACTUATOR_CFG = DCMotorCfg("
        ' joint_names_expr=[".*HAA", ".*HFE", ".*KFE"],'
        " saturation_effort=120.0, effort_limit=80.0, velocity_limit=7.5,"
        ' stiffness={".*": 40.0}, damping={".*": 5.0}, )',
    ),
    # ROBOTIS: the bold (recommended-voltage) entry of each multi-voltage line, or the one at 12 V
    "dynamixel-xl330-m077": dxl(
        "xl330-m077", "0.215 [N.m] (at 5.0 [V], 1.47 [A])", "383 [rev/min] (at 5.0 [V])"
    ),
    "dynamixel-xl330-m288": dxl(
        "xl330-m288", "0.52 [N.m] (at 5.0 [V], 1.47 [A])", "103 [rev/min] (at 5.0 [V])"
    ),
    "dynamixel-xc330-m288": dxl(
        "xc330-m288", "0.93 [N.m] (at 5.0 [V], 1.80 [A])", "81 [rev/min] (at 5.0 [V])"
    ),
    "dynamixel-xl430-w250": dxl(
        "xl430-w250", "1.4 [N.m] (at 11.1 [V], 1.3 [A])", "57 [rev/min] (at 11.1 [V])"
    ),
    "dynamixel-xc430-w240": dxl(
        "xc430-w240", "1.9 [N.m] (at 12.0 [V], 1.4 [A])", "70 [rev/min] (at 12.0 [V])"
    ),
    "dynamixel-xm430-w210": dxl(
        "xm430-w210", "3.0 [N.m] (at 12.0 [V], 2.3 [A])", "77 [rev/min] (at 12.0 [V])"
    ),
    "dynamixel-xm430-w350": dxl(
        "xm430-w350", "4.1 [N.m] (at 12.0 [V], 2.3 [A])", "46 [rev/min] (at 12.0 [V])"
    ),
    "dynamixel-xh430-w350": dxl(
        "xh430-w350", "3.4 [N.m] (at 12.0 [V], 1.3 [A])", "30 [rev/min] (at 12.0 [V])"
    ),
    "dynamixel-xh540-w150": dxl(
        "xh540-w150", "7.1 [N.m] (at 12.0 [V], 4.9 [A])", "70 [rev/min]) (at 12.0 [V])"
    ),
    "dynamixel-xh540-w270": dxl(
        "xh540-w270", "9.9 [N.m] (at 12.0 [V], 4.9 [A])", "39 [rev/min] (at 12.0 [V])"
    ),
    "dynamixel-xw540-t260": dxl(
        "xw540-t260", "9.5 [N.m] (at 12.0 [V], 4.9 [A])", "40 [rev/min] (at 12.0 [V])"
    ),
    "dynamixel-xm540-w150": dxl(
        "xm540-w150", "7.3 [N.m] (at 12.0 [V], 4.4 [A])", "53 [rev/min] (at 12.0 [V])"
    ),
    "dynamixel-xm540-w270": dxl(
        "xm540-w270", "10.6 [N.m] (at 12.0 [V], 4.4 [A])", "30 [rev/min] (at 12.0 [V])"
    ),
    # dxl_p_info.yml @ 1a5e5fbe, keys 'ph42-020-s300-r' and 'ph54-200-s500-r' (read 2026-12-02)
    "dynamixel-ph42-020-s300-r": dxl_p("ph42-020-s300-r", "32.7 [rev/min]", "29.2 [rev/min]", "5.1 [N.m]"),
    "dynamixel-ph54-200-s500-r": dxl_p("ph54-200-s500-r", "33.1 [rev/min]", "29.0 [rev/min]", "44.7 [N.m]"),
}


NOT_TRANSCRIBED: dict[str, str] = {}
"""Entries from a vendor file whose element is still to be transcribed here, and why (none now; a
new gap goes here with its reason, and test_catalog_entries.py then compares it with the quotes in its
own comments only)."""


def _numbers(element: Element) -> tuple[float, float]:
    """(effort [N*m], speed [rad/s]) read from the element's text, with the library's unit reader."""
    text = element.text
    if text.startswith("<limit"):
        effort = re.search(r'effort="([^"]+)"', text)
        speed = re.search(r'velocity="([^"]+)"', text)
        assert effort and speed
        return to_si(f"{effort.group(1)} N*m", "N*m", "urdf"), to_si(
            f"{speed.group(1)} rad/s", "rad/s", "urdf"
        )
    if "DCMotorCfg(" in text:  # Isaac Lab, SI joint units: effort_limit caps, velocity_limit is no-load
        effort = re.search(r"effort_limit=([\d.]+)", text)
        speed = re.search(r"velocity_limit=([\d.]+)", text)
        assert effort and speed
        return float(effort.group(1)), float(speed.group(1))
    if text.startswith("<xacro"):
        torque = re.search(r'name="\w+_torque_max" value="([^"]+)"', text)
        speed = re.search(r'name="\w+_velocity_max" value="([^"]+)"', text)
        assert torque and speed
        return float(torque.group(1)), float(speed.group(1))  # URDF units: N*m, rad/s
    if "conttorque" in text:  # DYNAMIXEL-P: the continuous torque caps peak duty too
        torque = re.search(r'conttorque: "([\d.]+ \[[^\]]+\])', text)
        no_load = re.search(r'noloadspeed: "([\d.]+ \[[^\]]+\])', text)
        assert torque and no_load
        return to_si(torque.group(1), "N*m", "yml"), to_si(no_load.group(1), "rad/s", "yml")
    stall = re.search(r'stalltorque: "([\d.]+ \[[^\]]+\])', text)
    no_load = re.search(r'noloadspeed: "([\d.]+ \[[^\]]+\])', text)
    assert stall and no_load
    # the e-Manual's bracketed units ('[N.m]', '[rev/min]') as the library reads them
    return to_si(stall.group(1), "N*m", "yml"), to_si(no_load.group(1), "rad/s", "yml")


def _machine_readable(path: Path) -> bool:
    text = path.read_text(encoding="utf-8")
    return bool(re.search(r"sources = \[?[^\]]*(\.urdf|\.xacro|\.yml|\.py)\"", text, re.DOTALL))


def test_every_machine_readable_entry_is_transcribed() -> None:
    """A new entry from a vendor file needs its element here too."""
    entries = {p.stem for p in CATALOG.glob("*.toml") if _machine_readable(p)}
    assert entries - set(TRANSCRIPTION) == set(NOT_TRANSCRIBED)


@pytest.mark.parametrize("name", sorted(TRANSCRIPTION))
def test_entry_names_file_revision_element_and_has_its_numbers(name: str) -> None:
    element = TRANSCRIPTION[name]
    text = (CATALOG / f"{name}.toml").read_text(encoding="utf-8")
    sheet = load_catalog_datasheet(name)
    assert element.url in sheet.sources, "the file at its pinned revision"
    assert re.search(r"/blob/[0-9a-f]{40}/", element.url)
    assert element.name in text, "the element is named"
    effort, speed = _numbers(element)
    env = derive(sheet).envelope
    assert env.max_effort == pytest.approx(effort, rel=1e-12)
    assert env.max_actuator_velocity == pytest.approx(speed, rel=1e-12)


@pytest.mark.parametrize("name", sorted(n for n, e in TRANSCRIPTION.items() if e.url == DXL_P))
def test_dynamixel_p_gradient_is_the_line_through_its_continuous_point(name: str) -> None:
    """(no-load speed - continuous speed) / continuous torque, from the element's own text."""
    text = TRANSCRIPTION[name].text
    no_load, cont_speed, torque = (
        to_si(m, unit, "yml")
        for m, unit in zip(re.findall(r'"([\d.]+ \[[^\]]+\])"', text), ("rad/s", "rad/s", "N*m"), strict=True)
    )
    env = derive(load_catalog_datasheet(name)).envelope
    assert env.speed_effort_gradient == pytest.approx((no_load - cont_speed) / torque, rel=1e-12)


def test_isaac_lab_dc_motor_is_the_line_from_saturation_to_velocity_limit() -> None:
    """DCMotor: effort from saturation_effort at rest to 0 at velocity_limit, capped at effort_limit."""
    text = TRANSCRIPTION["anybotics-anydrive-3"].text
    keys = ("saturation_effort", "effort_limit", "velocity_limit")
    found = [re.search(rf"{key}=([\d.]+)", text) for key in keys]
    saturation, limit, speed = (float(m.group(1)) for m in found if m)
    d = derive(load_catalog_datasheet("anybotics-anydrive-3"))
    env = d.envelope
    assert env.speed_effort_gradient == pytest.approx(speed / saturation, rel=1e-12)
    assert d.max_effort_limited_by == "output_rating"
    assert d.max_actuator_velocity_limited_by == "output_no_load"
    # Isaac Lab's corner, where saturation * (1 - v / velocity_limit) meets effort_limit
    corner = speed * (1.0 - limit / saturation)
    assert env.max_actuator_velocity - env.speed_effort_gradient * env.max_effort == pytest.approx(corner)

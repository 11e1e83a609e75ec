"""The shipped robot maps against the joint names of the robots' published models.

Joint names come from the real models where ../shared/data has them (MuJoCo Menagerie's go2.xml,
panda.xml, kinova_gen3/gen3.xml and anybotics_anymal_c/anymal_c.xml, read with a small MJCF parser
here; Newton's FR3 USD asset, read as text), and are typed from the vendor's model otherwise (G1,
SO-101), citing the file. The rule tested is the map format's: a pattern without "/" is an
fnmatchcase glob on the joint's own name (the part after the last "/" of a USD prim path); each
pattern must match at least one joint and no joint may match two patterns. Every value must resolve
to an envelope, and the envelope must be the catalog entry's.
"""

from __future__ import annotations

import fnmatch
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import drive_envelope
from drive_envelope._src.datasheet.catalog import load_catalog_datasheet
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.maps import robot_map_path, robot_maps
from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.io.files import read_mapping
from drive_envelope.errors import InputError

MAPS = Path(drive_envelope.__file__).parent / "maps"
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"

# Unitree g1_description/g1_29dof.xml (unitreerobotics/unitree_ros @d6f13aad, robots/g1_description),
# the 29 actuated joints in file order.
G1_29DOF = (
    [
        f"{side}_{name}"
        for side in ("left", "right")
        for name in (
            "hip_pitch_joint",
            "hip_roll_joint",
            "hip_yaw_joint",
            "knee_joint",
            "ankle_pitch_joint",
            "ankle_roll_joint",
        )
    ]
    + ["waist_yaw_joint", "waist_roll_joint", "waist_pitch_joint"]
    + [
        f"{side}_{name}"
        for side in ("left", "right")
        for name in (
            "shoulder_pitch_joint",
            "shoulder_roll_joint",
            "shoulder_yaw_joint",
            "elbow_joint",
            "wrist_roll_joint",
            "wrist_pitch_joint",
            "wrist_yaw_joint",
        )
    ]
)
# TheRobotStudio/SO-ARM100 @fda892cb, Simulation/SO101/so101_new_calib.xml: the six joints.
SO101 = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]


def mjcf_joint_names(path: Path) -> list[str]:
    """Names of the non-free joints in an MJCF file's worldbody (<joint name=...>, not <freejoint>)."""
    root = ET.parse(path).getroot()
    worldbody = root.find("worldbody")
    assert worldbody is not None, f"{path}: no <worldbody>"
    return [
        joint.attrib["name"]
        for joint in worldbody.iter("joint")
        if "name" in joint.attrib and joint.attrib.get("type") != "free"
    ]


def usd_joint_paths(path: Path) -> list[str]:
    """``/fr3/Physics/fr3_joint1``-style paths of the revolute and prismatic joint prims in a .usda file."""
    names = re.findall(r'def Physics(?:Revolute|Prismatic)Joint "([^"]+)"', path.read_text(encoding="utf-8"))
    return [f"/fr3/Physics/{name}" for name in names]  # the prim paths of fr3.usda


def map_patterns(key: str) -> dict[str, object]:
    """The [joints] table of a shipped map."""
    table = read_mapping(MAPS / f"{key}.toml")["joints"]
    assert isinstance(table, dict)
    return table


def matches(pattern: str, joint: str) -> bool:
    """The map format's rule: without "/", the glob is matched against the joint's own name."""
    subject = joint if "/" in pattern else joint.rsplit("/", 1)[-1]
    return fnmatch.fnmatchcase(subject, pattern)


def check_map(key: str, joints: list[str], patterns: dict[str, object] | None = None) -> dict[str, str]:
    """Assert every pattern matches and no joint matches twice; return joint -> catalog entry."""
    patterns = map_patterns(key) if patterns is None else patterns
    assigned: dict[str, str] = {}
    for pattern, value in patterns.items():
        hit = [j for j in joints if matches(pattern, j)]
        assert hit, f"{key}: pattern {pattern!r} matches no joint of {joints}"
        for joint in hit:
            assert joint not in assigned, (
                f"{key}: joint {joint!r} matched twice (also by {assigned[joint]!r})"
            )
            assigned[joint] = str(value)
    return assigned


def need(path: Path) -> Path:
    """``path``, or skip with a message when the shared data is absent."""
    if not path.exists():
        pytest.skip(f"shared data not found: {path} (see ../shared/data/README.md)")
    return path


def test_go2_map_covers_every_menagerie_joint() -> None:
    """Menagerie go2.xml: 12 joints, hip and thigh on the GO-M8010-6, calf on the knee reduction."""
    joints = mjcf_joint_names(need(SHARED / "menagerie" / "go2.xml"))
    assert len(joints) == 12
    assigned = check_map("unitree-go2", joints)
    assert set(assigned) == set(joints)
    assert assigned["FL_calf_joint"] == "unitree-go2-calf"
    assert assigned["RR_hip_joint"] == assigned["RR_thigh_joint"] == "unitree-go-m8010-6"


def test_panda_map_covers_the_arm_of_menagerie_panda() -> None:
    """Menagerie panda.xml: joint1..7 mapped, the two finger joints left to the gripper model."""
    joints = mjcf_joint_names(need(SHARED / "menagerie" / "panda.xml"))
    assigned = check_map("franka-panda", joints)
    assert sorted(set(joints) - set(assigned)) == ["finger_joint1", "finger_joint2"]
    assert [assigned[f"joint{i}"] for i in (1, 4, 5, 7)] == [
        "franka-panda-joint1-4",
        "franka-panda-joint1-4",
        "franka-panda-joint5-7",
        "franka-panda-joint5-7",
    ]


def test_fr3_map_covers_newtons_fr3_usd_prim_paths() -> None:
    """Newton's fr3 USD asset: prims fr3_joint1..7 (as paths); joint6 has its own limit."""
    joints = usd_joint_paths(need(SHARED / "newton-assets" / "fr3" / "fr3_usd" / "Payload" / "Physics.usda"))
    assert len(joints) == 7
    assigned = check_map("franka-fr3", joints)
    assert set(assigned) == set(joints)
    assert assigned["/fr3/Physics/fr3_joint6"] == "franka-fr3-joint6"
    assert assigned["/fr3/Physics/fr3_joint7"] == "franka-fr3-joint5-7"


def test_g1_map_covers_the_29_dof_model() -> None:
    """Unitree g1_29dof: all 29 joints mapped, each to the motor unitree_rl_mjlab names for it."""
    assigned = check_map("unitree-g1", G1_29DOF)
    assert set(assigned) == set(G1_29DOF)
    assert assigned["left_knee_joint"] == "unitree-g1-7520-22"
    assert assigned["right_wrist_yaw_joint"] == "unitree-g1-4010"
    assert assigned["waist_pitch_joint"] == "unitree-g1-ankle"


def test_gen3_map_covers_the_menagerie_arm() -> None:
    """Menagerie kinova_gen3/gen3.xml: joint_1..7, large actuators on 1-4, small on 5-7."""
    joints = mjcf_joint_names(need(SHARED / "menagerie" / "kinova_gen3" / "gen3.xml"))
    assert joints == [f"joint_{i}" for i in range(1, 8)]
    assigned = check_map("kinova-gen3", joints)
    assert set(assigned) == set(joints)
    assert [assigned[f"joint_{i}"] for i in (1, 4, 5, 7)] == [
        "kinova-gen3-large",
        "kinova-gen3-large",
        "kinova-gen3-small",
        "kinova-gen3-small",
    ]


def test_anymal_c_map_covers_the_menagerie_quadruped() -> None:
    """Menagerie anybotics_anymal_c/anymal_c.xml: 12 leg joints (the free joint aside), all ANYdrive 3."""
    joints = mjcf_joint_names(need(SHARED / "menagerie" / "anybotics_anymal_c" / "anymal_c.xml"))
    assert len(joints) == 12
    assigned = check_map("anybotics-anymal-c", joints)
    assert set(assigned) == set(joints)
    assert set(assigned.values()) == {"anybotics-anydrive-3"}


@pytest.mark.parametrize("key", ["so101", "so101-12v"])
def test_so101_maps_cover_the_six_joints(key: str) -> None:
    """SO-101: the six joints of so101_new_calib.xml, all one servo model."""
    assigned = check_map(key, SO101)
    assert set(assigned) == set(SO101) and len(set(assigned.values())) == 1


def test_g1_map_on_usd_prim_paths() -> None:
    """A USD asset of the G1 names prims /g1/joints/<name>: the bare-name patterns match them the same."""
    paths = [f"/g1/joints/{name}" for name in G1_29DOF]
    assert set(check_map("unitree-g1", paths)) == set(paths)


@pytest.mark.parametrize("key", sorted(p.stem for p in MAPS.glob("*.toml")))
def test_every_value_is_a_catalog_actuator_that_resolves(key: str) -> None:
    """Each map value names a catalog entry; resolve_envelope gives that entry's derived envelope."""
    for pattern, value in map_patterns(key).items():
        assert isinstance(value, str), f"{key}: {pattern!r}: expected a catalog name"
        env = resolve_envelope(value, base=MAPS, where=f"{key}.toml: key 'joints.{pattern}'")
        assert env == derive(load_catalog_datasheet(value)).envelope


def test_map_listing_and_lookup() -> None:
    """robot_maps lists every file with its robot; robot_map_path finds one by key or file name."""
    listed = {m.key: m for m in robot_maps()}
    assert {"unitree-go2", "unitree-g1", "so101", "franka-panda", "franka-fr3"} <= set(listed)
    assert {"kinova-gen3", "anybotics-anymal-c"} <= set(listed)
    assert listed["unitree-go2"].title.startswith("Unitree Go2")
    assert listed["kinova-gen3"].title == "Kinova Gen3 arm (7 DoF)"
    assert listed["anybotics-anymal-c"].title == "ANYbotics ANYmal C quadruped"
    assert robot_map_path("unitree-go2") == robot_map_path("unitree-go2.toml") == MAPS / "unitree-go2.toml"


def test_unknown_map_name_suggests_the_nearest() -> None:
    """A misspelt map name is one line with the nearest shipped map."""
    with pytest.raises(InputError, match="did you mean 'unitree-go2'"):
        robot_map_path("unitree-go3")


def test_a_map_pattern_that_matches_nothing_is_caught() -> None:
    """The checker itself fails on a dead pattern (the G1 map on the Go2's joints)."""
    with pytest.raises(AssertionError, match="matches no joint"):
        check_map("unitree-g1", ["FL_hip_joint"])


def test_a_joint_matched_twice_is_caught() -> None:
    """The checker fails on overlapping patterns ("FL_*" also takes FL_hip_joint from "*_hip_joint")."""
    overlapping: dict[str, object] = {"*_hip_joint": "a", "FL_*": "b"}
    with pytest.raises(AssertionError, match="matched twice"):
        check_map("test", ["FL_hip_joint", "FL_thigh_joint"], overlapping)

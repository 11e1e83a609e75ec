"""Map files without USD: parsing, glob matching over plain joint lists, and every map mistake.

The joint lists are the real ones: Menagerie's Unitree Go2 joint names (``go2.xml``) and the prim
paths of Newton's ``anymal_c.usd`` (read from the file when ``../shared/data`` is present).
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

from drive_envelope import InputError, PerformanceEnvelope, save_envelope
from drive_envelope._src.adapters.usd.joint_map import match_joints, read_map, resolve_envelopes

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
GO2 = [f"{leg}_{part}_joint" for leg in ("FL", "FR", "RL", "RR") for part in ("hip", "thigh", "calf")]
ANYMAL = [f"/anymal/{leg}_{link}/{leg}_{dof}" for leg in ("LF", "RF", "LH", "RH") for link, dof in
          (("HIP", "HFE"), ("THIGH", "KFE"), ("base", "HAA"))]  # fmt: skip


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A map folder with two envelope files."""
    (tmp_path / "act").mkdir()
    save_envelope(
        PerformanceEnvelope(max_effort=23.7, max_actuator_velocity=30.1), tmp_path / "act" / "hip.toml"
    )
    save_envelope(
        PerformanceEnvelope(max_effort=45.4, max_actuator_velocity=15.7), tmp_path / "act" / "knee.toml"
    )
    return tmp_path


def _map(folder: Path, body: str, name: str = "map.toml") -> Path:
    path = folder / name
    path.write_text("[joints]\n" + body, encoding="utf-8")
    return path


def test_bare_names_on_menagerie_go2(folder: Path) -> None:
    """Match the Go2's 12 joints by name; relative files resolve against the map's folder."""
    body = '"*_hip_joint" = "act/hip.toml"\n"*_thigh_joint" = "act/hip.toml"\n'
    path = _map(folder, body + '"*_calf_joint" = "act/knee.toml"\n')
    match = match_joints(read_map(path), GO2)
    assert [item.joint for item in match.joints] == GO2 and match.warnings == ()
    resolved = {item.joint: item.envelope for item in resolve_envelopes(match)}
    assert resolved["RL_calf_joint"] is not None and resolved["RL_calf_joint"].max_effort == 45.4
    assert resolved["FR_thigh_joint"] is resolved["FR_hip_joint"]  # one source, read once
    assert match.joints[0].entry.source == str(folder / "act" / "hip.toml")


def test_bare_name_matches_the_last_part_of_a_prim_path(folder: Path) -> None:
    """Match a pattern without '/' against the prim's name, and one with '/' against the whole path."""
    path = _map(folder, '"*_KFE" = "act/knee.toml"\n"/anymal/*_base/*" = "act/hip.toml"\n')
    match = match_joints(read_map(path), ANYMAL)
    by_joint = {item.joint: item.entry.pattern for item in match.joints}
    assert by_joint["/anymal/LF_THIGH/LF_KFE"] == "*_KFE"
    assert by_joint["/anymal/RH_base/RH_HAA"] == "/anymal/*_base/*"
    assert "/anymal/LF_HIP/LF_HFE" not in by_joint  # no pattern names it: left alone
    assert len(by_joint) == 8


@pytest.mark.skipif(not (SHARED / "newton-assets" / "anymal_c.usd").is_file(), reason="needs ../shared/data")
def test_anymal_paths_from_the_real_asset(folder: Path) -> None:
    """Match the real ANYmal's revolute joints by the DOF name pattern its URDF import uses."""
    pytest.importorskip("pxr")
    if importlib.util.find_spec("physx_usd_schemas") is not None:
        # before the first stage: USD builds its schema registry once per process, and the USD
        # tests that run after this one in the process need the PhysX schemas in it
        from drive_envelope.usd import register_schemas

        register_schemas()
    from pxr import Usd, UsdPhysics

    stage = Usd.Stage.Open(str(SHARED / "newton-assets" / "anymal_c.usd"))
    joints = [str(p.GetPath()) for p in stage.Traverse() if p.IsA(UsdPhysics.RevoluteJoint)]
    path = _map(folder, '"*_HAA" = "act/hip.toml"\n"*_HFE" = "act/hip.toml"\n"*_KFE" = "act/knee.toml"\n')
    match = match_joints(read_map(path), joints)
    assert len(match.joints) == 12 == len(joints)


def test_first_match_wins_and_overlap_is_reported(folder: Path) -> None:
    """Warn once per pattern pair when a later pattern with another source matches taken joints."""
    path = _map(folder, '"FL_*" = "act/hip.toml"\n"*_calf_joint" = "act/knee.toml"\n')
    match = match_joints(read_map(path), GO2)
    assert {i.joint: i.entry.pattern for i in match.joints}["FL_calf_joint"] == "FL_*"
    assert len(match.warnings) == 1
    assert "key 'joints.*_calf_joint'" in match.warnings[0] and "'FL_calf_joint'" in match.warnings[0]
    assert "first match wins" in match.warnings[0]


def test_fully_shadowed_entry_is_an_error(folder: Path) -> None:
    """Refuse an entry all of whose joints an earlier pattern with another source already took."""
    path = _map(folder, '"*_calf_joint" = "act/knee.toml"\n"FL_calf_joint" = "act/hip.toml"\n')
    with pytest.raises(InputError, match=r"key 'joints\.FL_calf_joint': never used.*'\*_calf_joint'"):
        match_joints(read_map(path), GO2)


def test_shadowed_entry_with_the_same_source_is_only_redundant(folder: Path) -> None:
    """Warn (not fail) for an entry that repeats what earlier patterns already assign."""
    path = _map(folder, '"*_calf_joint" = "act/knee.toml"\n"FL_calf_joint" = "act/knee.toml"\n')
    match = match_joints(read_map(path), GO2)
    assert match.warnings == (f"{path}: key 'joints.FL_calf_joint': redundant: earlier patterns "
                              "with the same source match all its joints",)  # fmt: skip


def test_pattern_matching_nothing_names_the_key_and_close_names(folder: Path) -> None:
    """Refuse a pattern that matches no joint, naming the key and the nearest joint names."""
    path = _map(folder, '"FL_hip" = "act/hip.toml"\n')
    with pytest.raises(InputError) as info:
        match_joints(read_map(path), GO2)
    message = str(info.value)
    assert message.startswith(f"{path}: key 'joints.FL_hip': matches no joint name")
    assert "'FL_hip_joint'" in message and "\n" not in message
    assert "after the last '/'" not in message  # MJCF joint names: no prim paths to explain
    with pytest.raises(
        InputError, match=r"matches no joint name \(the part after the last '/'\) of the 1 joints"
    ):
        match_joints(read_map(path), ["/Robot/FL_hip_joint"])


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (
            '"a" = { envelope = "act/hip.toml", datasheet = "x.toml" }\n',
            "exactly one of 'envelope' or 'datasheet'",
        ),
        ('"a" = { envelope = "act/hip.toml", gain = 3 }\n', "unknown key 'gain'"),
        ('"a" = { envelope = "act/hip.toml", instance = 3 }\n', "key 'instance': expected a string"),
        ('"a" = 12\n', "expected an envelope file, datasheet file or catalog name, got 12"),
        ('"a" = "act/missing.toml"\n', "no such file 'act/missing.toml'"),
        ('"" = "act/hip.toml"\n', "got an empty key"),
    ],
)
def test_bad_entries_name_the_map_key(folder: Path, body: str, message: str) -> None:
    """Name the map file and the key for every malformed entry, in one line."""
    path = _map(folder, body)
    with pytest.raises(InputError, match=message) as info:
        read_map(path)
    assert str(info.value).startswith(f"{path}: key 'joints.") and "\n" not in str(info.value)


def test_bad_top_level(folder: Path) -> None:
    """Refuse a map without a [joints] table or with another top-level key."""
    (folder / "a.toml").write_text('[joint]\n"/a" = "x"\n', encoding="utf-8")
    with pytest.raises(InputError, match="unknown key 'joint'"):
        read_map(folder / "a.toml")
    (folder / "b.json").write_text(json.dumps({"joints": {}}), encoding="utf-8")
    with pytest.raises(InputError, match=r"b\.json: missing \[joints\] table"):
        read_map(folder / "b.json")


def test_unknown_catalog_name_names_the_key(folder: Path) -> None:
    """Report an unknown catalog actuator with the map key in front of the resolver's message."""
    path = _map(folder, '"*" = "no-such-actuator-x9"\n')
    with pytest.raises(InputError, match=r"key 'joints\.\*': .*no-such-actuator-x9"):
        resolve_envelopes(match_joints(read_map(path), GO2))


def test_catalog_name_resolves(folder: Path) -> None:
    """Resolve a catalog name (not a file) through the one resolver."""
    path = _map(folder, '"*" = "tmotor-ak80-6"\n')
    items = resolve_envelopes(match_joints(read_map(path), GO2))
    assert len(items) == 12 and items[0].envelope is not None and items[0].envelope.max_effort > 0


def test_module_imports_no_usd() -> None:
    """Keep the map module free of pxr so the MuJoCo side can use it without the usd extra."""
    code = (
        "import sys\nimport drive_envelope._src.adapters.usd.joint_map\n"
        "assert 'pxr' not in sys.modules, 'pxr imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_shipped_map_by_name() -> None:
    """Read a robot map shipped with the package by its name, and say which names exist otherwise."""
    joint_map = read_map("unitree-go2")
    assert joint_map.path.endswith("unitree-go2.toml")
    match = match_joints(joint_map, GO2)
    assert len(match.joints) == 12
    with pytest.raises(InputError, match=r"unitree-go3: no such map file, and .*did you mean 'unitree-go2'"):
        read_map("unitree-go3")


# map files take inline envelope tables; regex and case hints for unmatched patterns (a new user's
# findings)

FR3 = [f"/fr3/Physics/fr3_joint{i}" for i in range(1, 8)]  # Newton's fr3.usda prim paths


def test_map_file_takes_an_inline_envelope(tmp_path: Path) -> None:
    """Read the inline form of docs/analysis.md in a usd/mujoco map (was: unknown key 'max_effort')."""
    body = (
        '"fr3_joint1" = { max_effort = "12 N*m", max_actuator_velocity = "2.6 rad/s" }\n'
        '"fr3_joint[2-7]" = { max_effort = 87, max_actuator_velocity = "150 deg/s", instance = "angular" }\n'
    )
    match = match_joints(read_map(_map(tmp_path, body)), FR3)
    resolved = {item.joint.rpartition("/")[2]: item for item in resolve_envelopes(match)}
    first = resolved["fr3_joint1"]
    assert first.envelope == PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=2.6)
    assert first.entry.instance is None and first.entry.source == ""
    seventh = resolved["fr3_joint7"]
    assert seventh.envelope is not None and seventh.envelope.max_actuator_velocity == pytest.approx(
        2.6179938779914944
    )
    assert seventh.entry.instance == "angular" and match.warnings == ()


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (
            '{ envelope = "x.toml", max_effort = "12 N*m" }',
            "key 'envelope' with inline envelope key(s) 'max_effort'",
        ),
        (
            '{ datasheet = "x.toml", joint = "revolute" }',
            "key 'datasheet' with inline envelope key(s) 'joint'",
        ),
        ("{ max_efort = 3 }", "unknown key 'max_efort' (did you mean 'max_effort'?)"),
        ('{ max_effort = "12 m/s" }', "key 'max_effort'"),
        ('{ instance = "rotX" }', "expected exactly one of 'envelope' or 'datasheet', or an inline envelope"),
        ("{ max_actuator_velocity = 3 }", "missing required key 'max_effort'"),
        (  # a slide's numbers without joint = "prismatic" (the default is revolute): say so
            '{ max_effort = "120 N", max_actuator_velocity = "0.25 m/s" }',
            "'120 N' is not a torque in N*m (e.g. '2.5 Nm'); its dimension is [mass] * [length] / [time] "
            '** 2; a prismatic joint\'s envelope says so: add joint = "prismatic"',
        ),
    ],
)
def test_bad_inline_entries_name_the_key(tmp_path: Path, value: str, message: str) -> None:
    """Refuse a source mixed with envelope keys, an unknown key and bad values, in one line."""
    path = _map(tmp_path, f'"fr3_joint1" = {value}\n')
    with pytest.raises(InputError) as info:
        read_map(path)
    text = str(info.value)
    assert text.startswith(f"{path}: key 'joints.fr3_joint1': ") and message in text and "\n" not in text


def test_unmatched_map_pattern_hints_globs_and_case(tmp_path: Path) -> None:
    """Add the glob hint to a regex pattern's error and 'did you mean' to a name off only by case."""
    regex = _map(tmp_path, '"fr3_joint\\\\d" = { max_effort = 1.0 }\n', "re.toml")
    with pytest.raises(InputError, match="patterns are globs") as info:
        match_joints(read_map(regex), FR3)
    assert "matches no joint name" in str(info.value)
    upper = _map(tmp_path, '"FR3_JOINT1" = { max_effort = 1.0 }\n', "up.toml")
    with pytest.raises(InputError, match=r"did you mean 'fr3_joint1'\?") as info:
        match_joints(read_map(upper), FR3)
    assert "not regular expressions" not in str(info.value)
    glob = _map(tmp_path, '"FR3_*" = { max_effort = 1.0 }\n', "glob.toml")
    with pytest.raises(
        InputError, match=r"did you mean 'fr3_joint1', 'fr3_joint2', 'fr3_joint3' and 4 more\?"
    ):
        match_joints(read_map(glob), FR3)

"""A new user's findings on joint mappings, log columns and map files (regressions).

1. ``check`` with a joint mapping warns about keys no joint of the log took (no match, a regex
   written as a glob, a key shadowed by an earlier one), on stderr and in ``--json``.
2. Log columns are found up to case (``Velocity [RPM]``, ``Time,Position,Velocity,Effort``); two
   columns that differ only in case stay ambiguous; identify's bench logs follow the same rule.
3. Map files (``usd apply --map``, ``mujoco apply --map``) take inline envelope tables, read by the
   one entry reader that ``check``'s mappings use too; regex and case hints for unmatched patterns.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from drive_envelope import InputError, PerformanceEnvelope
from drive_envelope._src.adapters.usd.joint_map import match_joints, read_map, resolve_envelopes
from drive_envelope._src.analysis.api import check_log
from drive_envelope._src.analysis.log_model import ColumnPlan, LogColumns
from drive_envelope._src.analysis.mapping import JointMapping, load_joint_mapping
from drive_envelope._src.cli.main import main
from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.identify.logs import _plan

LOG = "time,joint,velocity,effort\n0,elbow_l,0,1\n0,elbow_r,0,1\n0,knee,0,1\n"
FR3 = [f"/fr3/Physics/fr3_joint{i}" for i in range(1, 8)]  # Newton's fr3.usda prim paths


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


# -- 1. keys no joint of the log took ---------------------------------------------------------------


def test_regex_key_warns_once_with_the_glob_hint(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Warn after the log is read that a regex key matches nothing, and say patterns are globs."""
    jm = _write(
        tmp_path, "jm.toml", '[joints]\n"elbow_.*" = "cubemars-ak80-9-v3"\n"*" = "damiao-dm-j4310-2ec"\n'
    )
    log = _write(tmp_path, "lj.csv", LOG)
    assert main(["check", str(jm), str(log), "--json"]) == 0
    captured = capsys.readouterr()
    warnings = captured.err.splitlines()
    assert warnings == [
        f"drive-envelope: warning: {jm}: key 'joints.elbow_.*': matches no joint of the log; patterns are "
        "globs (*, ?, [...]), not regular expressions (write 'elbow_*', not 'elbow_.*')"
    ]
    report = json.loads(captured.out)
    assert [u["key"] for u in report["unused_keys"]] == ["elbow_.*"]
    assert report["unused_keys"][0]["reason"].startswith("matches no joint of the log; patterns are globs")
    rs = resolve_envelope("damiao-dm-j4310-2ec")  # every joint, elbows too, got the '*' envelope
    assert {j["envelope"]["max_effort"] for j in report["joints"]} == {rs.max_effort}


@pytest.mark.parametrize("key", ["elbow_\\d", "elbow_.+", "^elbow", "elbow$", "a|b", "(elbow)", "e{2}"])
def test_every_regex_marker_gets_the_hint(key: str) -> None:
    """Name the glob rule for each piece of regular-expression syntax."""
    mapping = JointMapping.from_envelopes({key: PerformanceEnvelope(max_effort=1.0)})
    (unused,) = mapping.unused_keys(["elbow_1"])
    assert "not regular expressions" in unused.reason


def test_plain_unmatched_key_has_no_regex_hint_and_case_gets_did_you_mean() -> None:
    """Say only "matches no joint" for a plain key; suggest the joint that differs only in case."""
    env = PerformanceEnvelope(max_effort=1.0)
    mapping = JointMapping.from_envelopes({"wrist_*": env, "Knee": env, "*": env})
    reasons = {u.key: u.reason for u in mapping.unused_keys(["knee", "elbow_l"])}
    assert reasons == {
        "wrist_*": "matches no joint of the log",
        "Knee": "matches no joint of the log; did you mean 'knee'? (names are case-sensitive)",
    }


def test_shadowed_key_warns_as_never_used(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Warn that '*_l' is never used: elbow_l takes 'elbow_*' (globs in file order), knee takes '*'."""
    body = '[joints]\n"elbow_*" = { max_effort = 10.0 }\n"*_l" = { max_effort = 20.0 }\n'
    body += '"*" = { max_effort = 30.0 }\n'
    jm = _write(tmp_path, "jm.toml", body)
    log = _write(tmp_path, "lj.csv", LOG)
    assert main(["check", str(jm), str(log)]) == 0
    err = capsys.readouterr().err
    assert err == (
        f"drive-envelope: warning: {jm}: key 'joints.*_l': never used: every joint of the log it matches "
        "('elbow_l') takes 'elbow_*' first (exact names first, then globs in file order)\n"
    )
    report = check_log(jm, log)
    assert [(u.key, u.reason.split(":")[0]) for u in report.unused_keys] == [("*_l", "never used")]
    assert {j.joint: j.envelope.max_effort for j in report.joints} == {
        "elbow_l": 10.0,
        "elbow_r": 10.0,
        "knee": 30.0,
    }


def test_exact_name_later_in_the_file_shadows_an_earlier_glob() -> None:
    """Count an exact key as taking its joint first, whatever its place in the file."""
    env = PerformanceEnvelope(max_effort=1.0)
    mapping = JointMapping.from_envelopes({"knee*": env, "knee": env})
    (unused,) = mapping.unused_keys(["knee"])
    assert unused.key == "knee*" and "takes 'knee' first" in unused.reason


def test_every_key_used_and_single_envelope_report_no_unused_keys(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Print no warning and an empty list when each key gave some joint its envelope."""
    jm = _write(
        tmp_path, "jm.toml", '[joints]\n"elbow_*" = { max_effort = 10.0 }\nknee = { max_effort = 3.0 }\n'
    )
    log = _write(tmp_path, "lj.csv", LOG)
    assert main(["check", str(jm), str(log), "--json"]) == 0
    captured = capsys.readouterr()
    assert captured.err == "" and json.loads(captured.out)["unused_keys"] == []
    single = check_log(PerformanceEnvelope(max_effort=5.0), {"velocity": [0.0], "effort": [1.0]})
    assert single.unused_keys == () and single.to_dict()["unused_keys"] == []


def test_check_mapping_values_share_the_map_reader(tmp_path: Path) -> None:
    """Read a check mapping's tables as map files are read: envelope/datasheet tables, instance ignored."""
    _write(tmp_path, "big.toml", "max_effort = 100.0\n")
    body = (
        '[joints]\n"elbow_*" = { envelope = "big.toml", instance = "angular" }\n'
        'knee = { max_effort = "3 N*m", instance = "rotX" }\n'
    )
    mapping = load_joint_mapping(_write(tmp_path, "jm.toml", body))
    assert [(key, env.max_effort) for key, env in mapping.entries] == [("elbow_*", 100.0), ("knee", 3.0)]
    bad = _write(tmp_path, "bad.toml", '[joints]\nknee = { envelope = "big.toml", max_effort = 3.0 }\n')
    with pytest.raises(InputError, match=r"key 'joints\.knee': key 'envelope' with inline envelope key"):
        load_joint_mapping(bad)


# -- 2. columns up to case ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "header",
    [
        "time,position,Velocity [RPM],effort",
        "Time,Position,Velocity [rpm],Effort",
        "TIME, VELOCITY [Rpm], EFFORT",
    ],
)
def test_columns_are_found_up_to_case_and_rpm_is_read(tmp_path: Path, header: str) -> None:
    """Find 'velocity' in 'Velocity [RPM]' and read the unit as rpm (the units parser's vendor spelling)."""
    ak = _write(tmp_path, "ak.toml", 'max_effort = "12 N*m"\nmax_actuator_velocity = "300 rpm"\n')
    row = ["0.1", "100", "2"] if header.count(",") == 2 else ["0.1", "0", "100", "2"]
    log = _write(tmp_path, "c1.csv", header + "\n" + ",".join(row) + "\n")
    (joint,) = check_log(ak, log).joints
    assert joint.samples == 1 and joint.velocity is not None
    assert joint.velocity.minimum == pytest.approx(200 * 2 * 3.141592653589793 / 60)  # 300 - 100 rpm


def test_plain_capitalised_header_checks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Check 'Time,Position,Velocity,Effort' (was: exit 2, no column 'velocity')."""
    ak = _write(tmp_path, "ak.toml", 'max_effort = "12 N*m"\n')
    log = _write(tmp_path, "c2.csv", "Time,Position,Velocity,Effort\n0,0,1,1\n0.1,0,1,13\n")
    assert main(["check", str(ak), str(log), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["joints"][0]["samples_outside"] == 1 and report["joints"][0]["duration"] == 0.1


def test_two_columns_up_to_case_stay_ambiguous_and_joint_column_too() -> None:
    """Refuse 'Velocity,velocity' as today; find a 'Joint' column by its whole header."""
    with pytest.raises(InputError, match="column 'velocity' is ambiguous"):
        ColumnPlan(["time", "Velocity", "velocity", "effort"], LogColumns(), "log.csv")
    with pytest.raises(InputError, match="column 'velocity' is ambiguous"):
        ColumnPlan(["velocity", "VELOCITY [rpm]", "effort"], LogColumns(), "log.csv")
    plan = ColumnPlan(["Joint", "Velocity", "Effort"], LogColumns(), "log.csv")
    assert plan.joint and plan.position == {"joint": 0, "velocity": 1, "effort": 2}
    assert ColumnPlan(["qd", "tau"], LogColumns(velocity="QD", effort="Tau"), "x").position == {
        "velocity": 0,
        "effort": 1,
    }


def test_identify_bench_header_uses_the_same_rule() -> None:
    """Find bench columns up to case with the check's rule; two up to case stay ambiguous."""
    plan, scales = _plan(["Time", "Position [deg]", "Target_Position [deg]", "Velocity [RPM]"], "bench.csv")
    assert plan == {"time": 0, "position": 1, "target_position": 2, "velocity": 3}
    assert scales["velocity"] == pytest.approx(2 * 3.141592653589793 / 60)
    with pytest.raises(InputError, match="column 'velocity' is ambiguous"):
        _plan(["time", "position", "target_position", "Velocity", "velocity"], "bench.csv")


# -- 3. map files: inline envelopes, hints ----------------------------------------------------------


def test_map_file_takes_an_inline_envelope(tmp_path: Path) -> None:
    """Read the inline form of docs/analysis.md in a usd/mujoco map (was: unknown key 'max_effort')."""
    body = (
        '[joints]\n"fr3_joint1" = { max_effort = "12 N*m", max_actuator_velocity = "2.6 rad/s" }\n'
        '"fr3_joint[2-7]" = { max_effort = 87, max_actuator_velocity = "150 deg/s", instance = "angular" }\n'
    )
    match = match_joints(read_map(_write(tmp_path, "map.toml", body)), FR3)
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
    ],
)
def test_bad_inline_entries_name_the_key(tmp_path: Path, value: str, message: str) -> None:
    """Refuse a source mixed with envelope keys, an unknown key and bad values, in one line."""
    path = _write(tmp_path, "map.toml", f'[joints]\n"fr3_joint1" = {value}\n')
    with pytest.raises(InputError) as info:
        read_map(path)
    text = str(info.value)
    assert text.startswith(f"{path}: key 'joints.fr3_joint1': ") and message in text and "\n" not in text


def test_unmatched_map_pattern_hints_globs_and_case(tmp_path: Path) -> None:
    """Add the glob hint to a regex pattern's error and 'did you mean' to a name off only by case."""
    regex = _write(tmp_path, "re.toml", '[joints]\n"fr3_joint\\\\d" = { max_effort = 1.0 }\n')
    with pytest.raises(InputError, match="patterns are globs") as info:
        match_joints(read_map(regex), FR3)
    assert "matches no joint name" in str(info.value)
    upper = _write(tmp_path, "up.toml", '[joints]\n"FR3_JOINT1" = { max_effort = 1.0 }\n')
    with pytest.raises(InputError, match=r"did you mean 'fr3_joint1'\?") as info:
        match_joints(read_map(upper), FR3)
    assert "not regular expressions" not in str(info.value)
    glob = _write(tmp_path, "glob.toml", '[joints]\n"FR3_*" = { max_effort = 1.0 }\n')
    with pytest.raises(
        InputError, match=r"did you mean 'fr3_joint1', 'fr3_joint2', 'fr3_joint3' and 4 more\?"
    ):
        match_joints(read_map(glob), FR3)


def test_usd_apply_inline_map_on_the_fr3(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Apply an inline map to Newton's FR3 and read it back (needs usd-core and the shared assets)."""
    pytest.importorskip("pxr")
    asset = Path(__file__).resolve().parents[2] / "shared/data/newton-assets/fr3/fr3_usd/fr3.usda"
    if not asset.is_file():
        pytest.skip("no shared newton-assets")
    body = '[joints]\n"fr3_joint1" = { max_effort = "12 N*m", max_actuator_velocity = "2.6 rad/s" }\n'
    out = tmp_path / "fr3_envelope.usda"
    assert (
        main(["usd", "apply", str(asset), "--map", str(_write(tmp_path, "map.toml", body)), "-o", str(out)])
        == 0
    )
    capsys.readouterr()
    assert main(["usd", "show", str(out), "--json"]) == 0
    drives = {d["joint"]: d for d in json.loads(capsys.readouterr().out)["drives"]}
    envelope = drives["/fr3/Physics/fr3_joint1"]["envelope"]
    assert envelope["max_effort"] == 12.0 and envelope["max_actuator_velocity"] == pytest.approx(
        2.6, rel=1e-6
    )

"""Checking logs against envelopes: golden counts by hand, streaming invariance, mappings, test stand."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drive_envelope import PerformanceEnvelope
from drive_envelope._src.cli.main import main
from drive_envelope.analysis import CheckOptions, JointMapping, check_log, check_samples, load_joint_mapping
from drive_envelope.datasheet import resolve_envelope
from drive_envelope.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

# T = 10 N*m, R = 0.5 N*m*s/rad, V = 5 rad/s, G = 0.2 (rad/s)/(N*m)
ENV = PerformanceEnvelope(
    max_effort=10.0, max_actuator_velocity=5.0, velocity_dependent_resistance=0.5, speed_effort_gradient=0.2
)
#   row  t     v     tau    effort margin 10-0.5|v|-|tau|   velocity margin 5-0.2|tau|-|v|
#   1    0.0   0     0      10                               5
#   2    0.1   2     9      0      (on eq. 1)                1.2
#   3    0.2   4    -5      3                                0      (on eq. 2)
#   4    0.3  -3     9.5   -1      (outside eq. 1: 10 %)     0.1
#   5    0.5   4.5   4      3.75                            -0.3    (outside eq. 2: 6 %)
#   6    0.6   1     1      8.5                              3.8
TIME = [0.0, 0.1, 0.2, 0.3, 0.5, 0.6]
VELOCITY = [0.0, 2.0, 4.0, -3.0, 4.5, 1.0]
EFFORT = [0.0, 9.0, -5.0, 9.5, 4.0, 1.0]


def test_golden_counts_margins_and_worst_violation() -> None:
    """Match the hand-computed table: outside counts per curve, worst sample, times on limits."""
    check = check_samples(ENV, VELOCITY, EFFORT, time=TIME)
    assert check.samples == 6 and check.samples_outside == 2
    assert check.fraction_outside == pytest.approx(2 / 6)
    assert (
        check.effort.samples_outside == 1
        and check.velocity is not None
        and check.velocity.samples_outside == 1
    )
    assert check.effort.minimum == pytest.approx(-1.0) and check.velocity.minimum == pytest.approx(-0.3)
    worst = check.worst
    assert worst is not None and worst.curve == "effort"
    assert (worst.row, worst.time, worst.velocity, worst.effort) == (4, 0.3, -3.0, 9.5)
    assert worst.excess == pytest.approx(1.0) and worst.relative == pytest.approx(0.1)
    speed = check.velocity.worst
    assert speed is not None and (speed.row, speed.time) == (5, 0.5)
    assert speed.relative == pytest.approx(0.06)
    # time steps ending at each sample: 0, .1, .1, .1, .2, .1
    assert check.duration == pytest.approx(0.6)
    assert check.time_outside == pytest.approx(0.3)
    assert check.effort.samples_on_limit == 1 and check.effort.time_on_limit == pytest.approx(0.1)
    assert check.velocity.samples_on_limit == 1 and check.velocity.time_on_limit == pytest.approx(0.1)


def test_tolerance_decides_the_verdict() -> None:
    """Pass when the fraction outside is within the tolerance, fail above it."""
    table = {"time": TIME, "velocity": VELOCITY, "effort": EFFORT}
    assert not check_log(ENV, table).passed
    assert check_log(ENV, table, options=CheckOptions(tolerance=0.34)).passed
    assert not check_log(ENV, table, options=CheckOptions(tolerance=0.33)).passed


def test_slack_absorbs_rounding_only() -> None:
    """Count a sample 1e-9 of the cap outside as inside with the default slack, not with zero slack."""
    effort = [10.0 * (1.0 + 1e-9)]
    assert check_samples(ENV, [0.0], effort).samples_outside == 0
    assert check_samples(ENV, [0.0], effort, options=CheckOptions(slack=0.0)).samples_outside == 1


def test_infinite_speed_limit_skips_eq2() -> None:
    """Report no eq. 2 margins when max_actuator_velocity is infinite."""
    check = check_samples(PerformanceEnvelope(max_effort=1.0), [100.0], [0.5])
    assert check.velocity is None and check.samples_outside == 0


def test_infinite_max_effort_gives_infinite_eq1_margins(tmp_path: Path) -> None:
    """Check eq. 2 alone when max_effort is inf (an envelope file may say so, as PhysX's maxForce).

    The inf margins were cast to a histogram bin as a huge negative integer: a RuntimeWarning, then
    bincount's ValueError, an internal error (exit 1) from the CLI.
    """
    envelope = PerformanceEnvelope(max_effort=float("inf"), max_actuator_velocity=3.0)
    check = check_samples(envelope, [0.0, 2.0, 4.0], [1e6, -5.0, 0.5])
    assert check.effort.minimum == float("inf") and check.effort.samples_outside == 0
    assert all(value == float("inf") for _, value in check.effort.quantiles)
    assert check.velocity is not None and check.samples_outside == 1
    assert check.velocity.minimum == pytest.approx(-1.0)
    env_file = tmp_path / "inf.toml"
    env_file.write_text('max_effort = "inf"\nmax_actuator_velocity = 3.0\n', encoding="utf-8")
    log = tmp_path / "log.csv"
    log.write_text("velocity,effort\n0,1e6\n2,-5\n4,0.5\n", encoding="utf-8")
    assert main(["check", str(env_file), str(log)]) == 1  # one sample beyond eq. 2: a failed gate


def test_margin_quantiles_match_numpy_within_the_bin_width() -> None:
    """Agree with exact (inverted-CDF) quantiles of the margins to half a bin, 0.05 % of the cap."""
    rng = np.random.default_rng(3)
    velocity, effort = rng.uniform(-5.0, 5.0, 20000), rng.uniform(-10.0, 10.0, 20000)
    check = check_samples(ENV, velocity, effort)
    effort_margin, velocity_margin = ENV.margins(velocity, effort)
    for summary, margins, cap in (
        (check.effort, effort_margin, 10.0),
        (check.velocity, velocity_margin, 5.0),
    ):
        assert summary is not None
        for p, value in summary.quantiles:
            exact = np.quantile(margins, p, method="inverted_cdf")
            if exact > -cap:  # below -100 % of the cap only the minimum is kept
                assert value == pytest.approx(exact, abs=0.5e-3 * cap + 1e-9)


@settings(max_examples=25, deadline=None)
@given(chunk_rows=st.integers(1, 40), seed=st.integers(0, 2**16))
def test_results_do_not_depend_on_chunking(chunk_rows: int, seed: int) -> None:
    """Give the same report whatever the chunk size (the streaming state carries across chunks)."""
    rng = np.random.default_rng(seed)
    n = 97
    table = {
        "time": np.cumsum(rng.uniform(0.0, 0.02, n)),
        "velocity": rng.uniform(-6.0, 6.0, n),
        "effort": rng.uniform(-11.0, 11.0, n),
        "joint": rng.choice(["a", "b", "c"], n),
    }
    whole = check_log(ENV, table).to_dict()
    parts = check_log(ENV, table, chunk_rows=chunk_rows).to_dict()
    key = lambda joint: joint["joint"]  # noqa: E731
    for one, other in zip(sorted(whole["joints"], key=key), sorted(parts["joints"], key=key), strict=True):
        assert one["samples_outside"] == other["samples_outside"]
        assert one["duration"] == pytest.approx(other["duration"])
        for curve in ("effort", "velocity"):
            assert one[curve]["quantiles"] == other[curve]["quantiles"]
            assert one[curve]["worst"] == other[curve]["worst"]
            assert one[curve]["time_on_limit"] == pytest.approx(other[curve]["time_on_limit"])


def test_joint_mapping_with_exact_names_globs_and_inline_tables(tmp_path: Path) -> None:
    """Give each joint the envelope its mapping names: exact key first, then globs in file order."""
    (tmp_path / "env").mkdir()
    (tmp_path / "env" / "big.toml").write_text("max_effort = 100.0\n", encoding="utf-8")
    mapping = tmp_path / "joints.toml"
    mapping.write_text(
        '[joints]\n"arm_*" = "env/big.toml"\narm_2 = { max_effort = "5 N*m" }\n"*" = { max_effort = 1.0 }\n',
        encoding="utf-8",
    )
    table = {"joint": ["arm_1", "arm_2", "wrist"], "velocity": [0.0, 0.0, 0.0], "effort": [50.0, 50.0, 0.5]}
    report = check_log(mapping, table)
    efforts = {j.joint: (j.envelope.max_effort, j.samples_outside) for j in report.joints}
    assert efforts == {"arm_1": (100.0, 0), "arm_2": (5.0, 1), "wrist": (1.0, 0)}


def test_mapping_errors_name_the_file_and_joint(tmp_path: Path) -> None:
    """Refuse an unmatched joint, a log without joint column, and a bad mapping entry."""
    mapping = tmp_path / "joints.toml"
    mapping.write_text("[joints]\nknee = { max_effort = 1.0 }\n", encoding="utf-8")
    with pytest.raises(InputError, match="no envelope for joint 'hip'"):
        check_log(mapping, {"joint": ["hip"], "velocity": [0.0], "effort": [0.0]})
    with pytest.raises(InputError, match="needs a joint column"):
        check_log(mapping, {"velocity": [0.0], "effort": [0.0]})
    # a regular expression for a key, or a key in another case: the error says which (it only listed keys)
    mapping.write_text('[joints]\n"wrist_.*" = { max_effort = 1.0 }\n', encoding="utf-8")
    with pytest.raises(InputError, match=r"\(keys: wrist_\.\*\); patterns are globs .* not regular exp"):
        check_log(mapping, {"joint": ["wrist_1"], "velocity": [0.0], "effort": [0.0]})
    mapping.write_text("[joints]\nHip = { max_effort = 1.0 }\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"did you mean 'Hip'\? \(names are case-sensitive\)"):
        check_log(mapping, {"joint": ["hip"], "velocity": [0.0], "effort": [0.0]})
    mapping.write_text("[joints]\nknee = 3\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"joints\.knee"):
        load_joint_mapping(mapping)


def _stand(name: str) -> tuple[PerformanceEnvelope, object]:
    teststand = pytest.importorskip("drive_envelope.teststand")
    scenario = teststand.load_scenario(EXAMPLES / "scenarios" / f"{name}.toml")
    envelope = scenario.effective_envelope()
    assert envelope is not None
    return envelope, teststand.simulate(scenario, engine="reference")


@pytest.mark.parametrize(
    "name", ["actuator_swing", "velocity_saturation_pgs", "velocity_saturation_tgs", "braking_pgs"]
)
def test_reference_test_stand_checks_clean_and_fails_a_tighter_envelope(name: str) -> None:
    """Find no test-stand sample outside its own envelope, and some outside a 10 % tighter one."""
    envelope, trajectory = _stand(name)
    own = check_samples(envelope, trajectory.velocity, trajectory.effort, time=trajectory.time)  # type: ignore[attr-defined]
    assert own.samples_outside == 0
    assert own.effort.samples_on_limit + (own.velocity.samples_on_limit if own.velocity else 0) > 0
    tighter = PerformanceEnvelope(
        max_effort=0.9 * envelope.max_effort,
        max_actuator_velocity=0.9 * envelope.max_actuator_velocity,
        velocity_dependent_resistance=envelope.velocity_dependent_resistance,
        speed_effort_gradient=envelope.speed_effort_gradient,
    )
    other = check_samples(tighter, trajectory.velocity, trajectory.effort, time=trajectory.time)  # type: ignore[attr-defined]
    assert other.samples_outside > 0 and other.worst is not None


def test_runaway_past_the_speed_limit_is_reported_as_released() -> None:
    """Count the overspeed scenario's samples as released: the load drives the joint, the drive lets go."""
    envelope, trajectory = _stand("overspeed_release_tgs")
    check = check_samples(envelope, trajectory.velocity, trajectory.effort, time=trajectory.time)  # type: ignore[attr-defined]
    assert check.samples_released == check.samples == len(trajectory)  # type: ignore[arg-type]
    assert check.samples_outside == 0 and check.worst is None
    assert check.velocity is not None and check.velocity.minimum < -0.3 * envelope.max_actuator_velocity
    assert check.time_released == pytest.approx(float(trajectory.time[-1]))  # type: ignore[attr-defined]


#   released golden: T = 10, R = 0.5, V = 5, G = 0.2 -> no-load speed min(5, 10/0.5) = 5 rad/s
#   row  v      tau     effort margin   velocity margin   verdict
#   1    6      0       7               -1                released (zero effort, past no-load)
#   2   -7      1e-7    6.5             -2                released (|tau| <= slack * 10)
#   3    6      0.5     6.5             -1.1              outside (eq. 2): the drive pushed
#   4    4.9    0       7.55            0.1               inside
#   5    5      0       7.5             0                 inside (on the line)
def test_released_samples_are_counted_apart_from_outside() -> None:
    """Count zero-effort samples past the no-load speed as released, never as outside."""
    velocity, effort = [6.0, -7.0, 6.0, 4.9, 5.0], [0.0, 1e-7, 0.5, 0.0, 0.0]
    check = check_samples(ENV, velocity, effort, time=[0.0, 0.1, 0.3, 0.4, 0.5])
    assert (check.samples_released, check.samples_outside) == (2, 1)
    assert check.time_released == pytest.approx(0.1) and check.time_outside == pytest.approx(0.2)
    assert check.velocity is not None and check.velocity.samples_outside == 1
    worst = check.worst
    assert worst is not None and worst.row == 3 and worst.excess == pytest.approx(1.1)
    assert check.velocity.minimum == pytest.approx(-2.0)  # margins still cover every sample
    # a resistance-bound no-load speed (10 / 2 = 5 rad/s < V = 8) releases through eq. 1
    steep = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=8.0, velocity_dependent_resistance=2.0)
    other = check_samples(steep, [6.0, 6.0], [0.0, 0.1])
    assert (other.samples_released, other.samples_outside) == (1, 1)


def test_kept_points_are_bounded_and_include_violations() -> None:
    """Keep at most about twice keep_points samples per joint, violations flagged."""
    rng = np.random.default_rng(0)
    velocity, effort = rng.uniform(-6, 6, 50000), rng.uniform(-11, 11, 50000)
    check = check_samples(ENV, velocity, effort, options=CheckOptions(keep_points=500))
    points = check.points
    assert points is not None and points.velocity.size <= 1000 and points.outside.sum() == 500
    outside = ~ENV.contains(points.velocity[points.outside], points.effort[points.outside], atol=1e-9)
    assert outside.all()


def test_joint_count_is_bounded() -> None:
    """Refuse a log with more distinct joints than max_joints, naming the row of the first extra one."""
    table = {"joint": ["a", "b", "a", "c"], "velocity": [0.0] * 4, "effort": [0.0] * 4}
    assert len(check_log(ENV, table, options=CheckOptions(max_joints=3)).joints) == 3
    with pytest.raises(InputError, match=r"row 4: joint 'c' is joint number 3; expected at most 2"):
        check_log(ENV, table, options=CheckOptions(max_joints=2))
    with pytest.raises(InputError, match="max_joints: expected an integer >= 1"):
        CheckOptions(max_joints=0)


def test_kept_points_share_one_budget_across_many_joints() -> None:
    """Keep at most about 16 x keep_points samples in all, and at least 500 per joint."""
    rng = np.random.default_rng(1)
    joints = 40
    n = 2000 * joints
    table = {
        "joint": np.repeat([f"j{i}" for i in range(joints)], 2000),
        "velocity": rng.uniform(-6, 6, n),
        "effort": rng.uniform(-11, 11, n),
    }
    report = check_log(ENV, table, options=CheckOptions(keep_points=1000))
    kept = [j.points.velocity.size for j in report.joints if j.points is not None]
    assert len(kept) == joints and min(kept) > 0
    # 16 * 1000 // 40 = 400 < 500: each joint keeps at most 500 regular samples and 500 violations
    assert max(kept) <= 2 * 500 and sum(kept) <= 2 * max(16 * 1000, 500 * joints)
    alone = check_log(ENV, {k: v[:2000] for k, v in table.items()}, options=CheckOptions(keep_points=1000))
    assert alone.joints[0].points is not None and alone.joints[0].points.velocity.size > 1000


def test_overflowing_margins_are_outside_and_json_stays_strict() -> None:
    """Count a margin beyond float range as outside, and write it as "-inf" (strict JSON)."""
    import json

    huge = PerformanceEnvelope(
        max_effort=1.0, max_actuator_velocity=1e308, velocity_dependent_resistance=10.0
    )
    with np.errstate(all="raise"):  # no floating-point warning escapes the check
        report = check_log(huge, {"time": [-1e308, 1e308], "velocity": [1e308, 0.0], "effort": [1.0, 0.0]})
    joint = report.joints[0]
    assert joint.samples_outside == 1 and joint.effort.minimum == -np.inf
    text = json.dumps(report.to_dict(), allow_nan=False)
    assert '"minimum": "-inf"' in text and '"duration": "inf"' in text


# keys of a joint mapping that no joint of the log took (a new user's findings): warned on stderr and in
# --json, with a hint for a regex written as a glob and for a name off only by case

MAPPING_LOG = "time,joint,velocity,effort\n0,elbow_l,0,1\n0,elbow_r,0,1\n0,knee,0,1\n"


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def test_regex_key_warns_once_with_the_glob_hint(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Warn after the log is read that a regex key matches nothing, and say patterns are globs."""
    jm = _write(
        tmp_path, "jm.toml", '[joints]\n"elbow_.*" = "cubemars-ak80-9-v3"\n"*" = "damiao-dm-j4310-2ec"\n'
    )
    log = _write(tmp_path, "lj.csv", MAPPING_LOG)
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
    log = _write(tmp_path, "lj.csv", MAPPING_LOG)
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
    log = _write(tmp_path, "lj.csv", MAPPING_LOG)
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


def test_check_samples_refuses_swapped_or_missing_arguments_in_one_line() -> None:
    """The samples given first, or None for a column, are named (they were a TypeError and a shape error)."""
    from drive_envelope import InputError

    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=5.0)
    samples = np.zeros(3)
    with pytest.raises(
        InputError, match=r"^check_samples: argument 'envelope': expected a PerformanceEnvelope"
    ):
        check_samples(samples, env, samples)  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"^check_samples: velocity: expected numbers .*, got None$"):
        check_samples(env, None, samples)  # type: ignore[arg-type]
    assert check_samples(env, samples, samples).samples == 3

"""The one role-to-column plan (issue 29): check, fit, fit --from-curve, identify and replay alike."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

from drive_envelope._src.analysis.columns import Role, plan_columns
from drive_envelope._src.analysis.log_model import log_plan
from drive_envelope._src.cli.main import main
from drive_envelope._src.identify.logs import bench_plan, read_bench_log
from drive_envelope.analysis import LogColumns, read_curve
from drive_envelope.errors import InputError

HAS_PYARROW = importlib.util.find_spec("pyarrow") is not None
STAND = Path(__file__).resolve().parent / "corpus" / "good" / "stand.toml"


def _error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    return err


def test_a_chain_run_of_simulate_says_how_to_check_one_joint() -> None:
    """simulate's chain CSV has JOINT.velocity columns: the error gives the flags for its first joint."""
    header = ["time", "hip.position", "hip.velocity", "hip.effort", "knee.velocity", "knee.effort"]
    with pytest.raises(InputError) as caught:
        log_plan(header, LogColumns(), "run.csv")
    assert str(caught.value) == (
        f"run.csv: no column 'velocity' or 'effort' (columns: {', '.join(header)}); the columns are per "
        "joint (hip, knee): name one with --velocity-column hip.velocity --effort-column hip.effort"
    )


def test_every_missing_required_column_is_named_in_one_line() -> None:
    """Both missing roles, the columns there and both flags; identify's list of what a bench log needs."""
    with pytest.raises(InputError) as caught:
        log_plan(["time", "position"], LogColumns(), "b.csv")
    assert str(caught.value) == (
        "b.csv: no column 'velocity' or 'effort' (columns: time, position); "
        "name them with --velocity-column and --effort-column"
    )
    with pytest.raises(InputError) as caught:
        bench_plan(["stamp", "q"], "bench.csv")
    assert str(caught.value) == (
        "bench.csv: no column 'time', 'position' or 'target_position' (columns: stamp, q); a bench log "
        "needs time, position, target_position (optional: velocity, effort, target_velocity, torque_enable)"
    )


def test_a_missing_column_suggests_the_nearest_name_in_the_header() -> None:
    """'velocty [rpm]' is suggested for velocity (by its name, which --velocity-column accepts)."""
    with pytest.raises(
        InputError, match=r"\(columns: time, velocty \[rpm\], effort\) \(did you mean 'velocty'\?\)"
    ):
        log_plan(["time", "velocty [rpm]", "effort"], LogColumns(), "a.csv")
    with pytest.raises(
        InputError, match=r"no column 'position' .*\(did you mean 'Posiiton'\?\); a bench log"
    ):
        bench_plan(["Time", "Posiiton", "target_position"], "f.csv")


def test_check_and_identify_refuse_an_ambiguous_column_with_one_message(tmp_path: Path) -> None:
    """The same header, read as a check log and as a bench log: the same line after the file name."""
    header = ["time", "position", "target_position", "velocity", "Velocity [rpm]", "effort"]
    messages = []
    for plan in (lambda: log_plan(header, LogColumns(), "x.csv"), lambda: bench_plan(header, "x.csv")):
        with pytest.raises(InputError) as caught:
            plan()
        messages.append(str(caught.value))
    assert (
        messages[0]
        == messages[1]
        == (
            "x.csv: column 'velocity' is ambiguous: the header has 'velocity' (column 4), "
            "'Velocity [rpm]' (column 5); expected each column name once"
        )
    )


def test_units_of_two_joint_types_read_the_same_in_check_and_identify() -> None:
    """rpm with N in a check log, deg with mm in a bench log: one message, naming both columns."""
    with pytest.raises(InputError) as caught:
        log_plan(["velocity [rpm]", "effort [N]"], LogColumns(), "mixed.csv")
    assert str(caught.value) == (
        "mixed.csv: the header units are of two joint types: column 'velocity [rpm]' has the unit of a "
        "revolute joint but column 'effort [N]' that of a prismatic joint; expected one joint type "
        "(rad/s and N*m for a revolute joint, or m/s and N for a prismatic one)"
    )
    with pytest.raises(InputError, match=r"column 'position \[deg\]' has the unit of a revolute joint but"):
        bench_plan(["time", "position [deg]", "target_position [mm]"], "bench.csv")


def test_aliases_find_the_role_and_two_candidates_are_refused() -> None:
    """A curve's 'speed' is the velocity; 'velocity' and 'speed' together could each be it: refused."""
    roles = [
        Role(
            role="velocity",
            column="velocity",
            required=True,
            aliases=("speed",),
            flag="--v",
            quantity="velocity",
        )
    ]
    plan = plan_columns(["Speed [rpm]"], roles, "c.csv")
    assert plan.position == {"velocity": 0} and plan.scale["velocity"] == pytest.approx(2 * math.pi / 60)
    with pytest.raises(
        InputError,
        match=r"columns 'velocity', 'speed' could each be the velocity; name the one to use with --v",
    ):
        plan_columns(["velocity", "speed"], roles, "c.csv")


def test_a_unitless_role_refuses_a_unit_and_a_text_role_takes_none() -> None:
    """torque_enable [V] is refused as identify refused it; a joint column is never converted."""
    roles = [
        Role(role="flag", column="torque_enable", meaning="0 or 1 per sample"),
        Role(role="joint", column="joint", text=True),
    ]
    with pytest.raises(
        InputError, match=r"column 'torque_enable \[V\]': expected no unit \(0 or 1 per sample\), got 'V'"
    ):
        plan_columns(["torque_enable [V]", "joint"], roles, "x.csv")
    plan = plan_columns(["joint", "torque_enable"], roles, "x.csv")
    assert plan.numeric == ("flag",) and "joint" in plan and plan.scale == {"flag": 1.0}


def test_fit_from_curve_with_velocity_and_speed_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The curve's aliases go through the plan: two columns for the velocity, one line, the flag."""
    curve = tmp_path / "c.csv"
    curve.write_text("velocity,speed,torque\n0,0,1\n1,1,1\n2,2,0.5\n")
    err = _error(capsys, ["fit", "--from-curve", str(curve)])
    assert (
        "columns 'velocity', 'speed' could each be the velocity; name the one to use with --velocity-column"
        in err
    )
    assert main(["fit", "--from-curve", str(curve), "--velocity-column", "speed", "--json"]) == 0


@pytest.mark.skipif(not HAS_PYARROW, reason="needs pyarrow")
def test_a_parquet_curve_finds_speed_and_torque_too(tmp_path: Path) -> None:
    """The aliases were applied to CSV headers only; the plan applies them to every format."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    csv = tmp_path / "curve.csv"
    csv.write_text("speed [rpm],torque [mNm]\n0,820\n2500,760\n5000,700\n")
    parquet = tmp_path / "curve.parquet"
    pq.write_table(
        pa.table({"speed [rpm]": [0.0, 2500.0, 5000.0], "torque [mNm]": [820.0, 760.0, 700.0]}), parquet
    )
    a, b = read_curve(csv), read_curve(parquet)
    assert a[0].tolist() == b[0].tolist() and a[1].tolist() == b[1].tolist()
    assert b[1].tolist() == pytest.approx([0.82, 0.76, 0.70], rel=1e-15)


def test_replay_and_identify_read_a_bench_log_through_the_plan(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """replay's message for a log without targets is identify's and check's form, with the nearest name."""
    log = tmp_path / "bench.csv"
    log.write_text("time,position,target_pos\n0,0,0\n0.01,0,0\n0.02,0,0\n")
    for argv in (["replay", str(log), "--stand", str(STAND)], ["identify", str(log), "--stand", str(STAND)]):
        err = _error(capsys, argv)
        assert (
            f"{log}: no column 'target_position' (columns: time, position, target_pos) "
            "(did you mean 'target_pos'?)" in err
        )
    units = tmp_path / "units.csv"
    units.write_text("time [ms],position [deg],target_position [deg]\n0,0,90\n10,45,90\n20,90,90\n")
    read = read_bench_log(units)
    assert read.time.tolist() == pytest.approx([0.0, 0.01, 0.02]) and read.position[2] == pytest.approx(
        math.pi / 2
    )

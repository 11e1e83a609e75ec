"""Bench logs and stand files for identify: reading, sidecars, and one-line errors."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import InputError
from drive_envelope._src.identify.logs import bench_plan, read_bench_log
from drive_envelope._src.identify.stand import StandWarning, read_stand

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "bam" / "logs"
REPO = Path(__file__).resolve().parents[1]


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_minimal_log_defaults(tmp_path: Path) -> None:
    """Read time, position and target; velocity absent, target velocity 0 and drive powered by default."""
    log = read_bench_log(
        _write(
            tmp_path / "a.csv", "# bench 3\ntime,position,target_position\n0,0,1\n0.01,0.1,1\n0.02,0.2,1\n"
        )
    )
    assert log.rows == 3 and log.dt == pytest.approx(0.01)
    assert log.velocity is None and log.effort is None and log.duty_per_rad is None
    assert np.all(log.target_velocity == 0.0) and np.all(log.enabled)


def test_a_log_sampled_coarser_than_a_drive_can_step_is_a_warning(tmp_path: Path) -> None:
    """Warn for a time in ms under a bare header (5 s steps); say nothing for the same log with its unit."""
    rows = "".join(f"{5 * i},0,1\n" for i in range(4))
    with pytest.warns(StandWarning, match=r"ms\.csv: samples 5 s apart, .*needs its unit in the header"):
        assert read_bench_log(_write(tmp_path / "ms.csv", "time,position,target_position\n" + rows)).dt == 5.0
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        labelled = read_bench_log(_write(tmp_path / "u.csv", "time [ms],position,target_position\n" + rows))
        assert labelled.dt == pytest.approx(0.005)


def test_columns_any_order_and_case_with_extra_columns(tmp_path: Path) -> None:
    """Find the columns by name, whatever their order and case; ignore the others."""
    text = (
        "Torque_Enable;volts;Position;TIME;target_position;velocity\n"
        "1;7;0;0;1;0\n0;7;0.1;0.005;1;2\n1;7;0.2;0.01;1;2\n"
    )
    log = read_bench_log(_write(tmp_path / "b.csv", text))
    assert log.enabled.tolist() == [True, False, True]
    assert log.velocity is not None and log.velocity.tolist() == [0.0, 2.0, 2.0]


def test_sidecar_gives_the_duty_gain(tmp_path: Path) -> None:
    """Read kp_duty_per_rad from NAME.json beside NAME.csv."""
    path = _write(tmp_path / "c.csv", "time,position,target_position\n0,0,0\n1,0,0\n2,0,0\n")
    _write(tmp_path / "c.json", json.dumps({"kp_duty_per_rad": 0.5, "other": "ignored"}))
    assert read_bench_log(path).duty_per_rad == 0.5


def test_a_sidecar_given_as_the_log_points_to_the_log(tmp_path: Path) -> None:
    """NAME.json passed as the log: named as a sidecar, with the log beside it (it was "columns: {")."""
    _write(tmp_path / "c.csv.gz", "")  # the log beside it, whatever its format
    sidecar = _write(tmp_path / "c.json", json.dumps({"kp_duty_per_rad": 0.5}))
    with pytest.raises(InputError) as caught:
        read_bench_log(sidecar)
    assert str(caught.value) == (
        f"{sidecar}: a JSON file, not a bench log (CSV, Parquet or a ROS 2 bag); a JSON file beside a log "
        "is its sidecar: pass the log (c.csv.gz), its sidecar is read with it"
    )


def test_parquet_log(tmp_path: Path) -> None:
    """Read the same log from Parquet."""
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    table = pa.table({"time": [0.0, 0.1, 0.2], "position": [0.0, 0.1, 0.3], "target_position": [1.0] * 3,
                      "torque_enable": pa.array([True, True, False])})  # fmt: skip
    pq.write_table(table, tmp_path / "d.parquet")
    log = read_bench_log(tmp_path / "d.parquet")
    assert log.position.tolist() == [0.0, 0.1, 0.3] and log.enabled.tolist() == [True, True, False]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("time,position\n0,0\n1,0\n2,0\n", "no column 'target_position' (columns: time, position)"),
        (
            "time,position,target_position\n0,0,0\n1,,0\n2,0,0\n",
            "row 2, column 'position': got an empty cell",
        ),
        ("time,position,target_position\n0,0,0\n1,inf,0\n2,0,0\n", "row 2, column 'position': got inf"),
        ("time,position,target_position\n0,0,0\n1,0,0\n2.5,0,0\n3.5,0,0\n", "expected a uniform grid"),
        ("time,position,target_position,torque_enable\n0,0,0,1\n1,0,0,2\n2,0,0,1\n", "expected 0 or 1"),
        ("time,position,target_position\n0,0,0\n1,0,0\n", "expected at least 3 samples"),
        ("time,position,position,target_position\n0,0,0,0\n", "column 'position' is ambiguous"),
        ("time,position,target_position\n0,0,0\n1,0\n", "row 2: 2 fields"),
        (  # the search squared it into an OverflowError inside SciPy, exit 1
            "time,position,target_position\n0,0,0\n1,1e300,0\n2,0,0\n",
            "row 2, column 'position': got 1e+300 [SI]; expected |position| at most 1e+100",
        ),
        (
            "time,position,target_position,velocity\n0,0,0,0\n1,0,0,0\n2,0,-2e100,0\n",
            "row 3, column 'target_position': got -2e+100 [SI]",
        ),
        (
            "time,position,target_position,velocity\n0,0,0,0\n1,0,0,1e101\n2,0,0,0\n",
            "row 2, column 'velocity': got 1e+101 [SI]",
        ),
    ],
)
def test_bad_logs_are_one_line(tmp_path: Path, text: str, message: str) -> None:
    """Refuse a damaged log with one line naming the file, the row and the column."""
    path = _write(tmp_path / "bad.csv", text)
    with pytest.raises(InputError) as caught:
        read_bench_log(path)
    assert message in str(caught.value) and str(path) in str(caught.value) and "\n" not in str(caught.value)


def test_bad_sidecar_is_one_line(tmp_path: Path) -> None:
    """Refuse a sidecar whose duty gain is not a positive number, naming the sidecar and the key."""
    path = _write(tmp_path / "e.csv", "time,position,target_position\n0,0,0\n1,0,0\n2,0,0\n")
    _write(tmp_path / "e.json", json.dumps({"kp_duty_per_rad": -1}))
    with pytest.raises(InputError, match=r"e\.json: key 'kp_duty_per_rad': expected a number > 0"):
        read_bench_log(path)


def test_stand_tables(tmp_path: Path) -> None:
    """Read [servo] and [bounds] (with units) beside the scenario tables."""
    path = _write(
        tmp_path / "stand.toml",
        "[joint]\ninertia = 1e-6\n[drive]\nmax_effort = 0.5\n[servo]\nduty_per_rad = 1.2\n"
        "[bounds]\nmax_effort = ['100 mN*m', '2 N*m']\narmature = [0, 0.01]\n",
    )
    stand = read_stand(path)
    assert stand.duty_per_rad == 1.2
    assert stand.bounds["max_effort"] == pytest.approx((0.1, 2.0)) and stand.bounds["armature"] == (0.0, 0.01)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[joint]\ninertia=1\n[servo]\nkp=4\n", "unknown key 'servo.kp'"),
        ("[joint]\ninertia=1\n[servo]\nduty_per_rad=0\n", "'servo.duty_per_rad': expected a number > 0"),
        ("[joint]\ninertia=1\n[bounds]\nmax_effort=[2, 1]\n", "expected finite low < high"),
        ("[joint]\ninertia=1\n[bounds]\nmax_torque=[0, 1]\n", "unknown key 'bounds.max_torque'"),
        ("[joint]\ninertia=1\n[bounds]\ndamping=3\n", "expected [low, high]"),
    ],
)
def test_bad_stand_tables_are_one_line(tmp_path: Path, text: str, message: str) -> None:
    """Refuse bad [servo] and [bounds] tables with one line naming the key."""
    with pytest.raises(InputError) as caught:
        read_stand(_write(tmp_path / "stand.toml", text))
    assert message in str(caught.value) and "stand.toml" in str(caught.value)


def test_stand_time_step_is_the_logs(tmp_path: Path) -> None:
    """Warn that a stand's dt and duration are ignored: each log sets them."""
    path = _write(tmp_path / "stand.toml", "[joint]\ninertia=1\n[simulation]\ndt=0.01\nsolver='pgs'\n")
    with pytest.warns(StandWarning, match=r"simulation\.dt ignored"):
        stand = read_stand(path)
    assert stand.scenario.simulation.solver == "pgs"


@pytest.mark.skipif(not SHARED.is_dir(), reason="needs ../shared/data/bam (the real BAM bench logs)")
def test_every_shared_bam_log_reads() -> None:
    """Read all 16 real BAM logs with their sidecars' duty gains (kp 100..800 -> 0.29..2.3 per rad)."""
    logs = [read_bench_log(path) for path in sorted(SHARED.glob("*.csv"))]
    assert len(logs) == 16
    assert {round(log.duty_per_rad or 0.0, 4) for log in logs} == {0.2877, 0.5755, 1.151, 2.3019}
    assert all(log.dt == pytest.approx(0.005, rel=1e-6) and log.velocity is not None for log in logs)
    assert sum(not log.enabled.all() for log in logs) == 4  # the lift_and_drop logs fall free after 2 s


def test_shipped_bam_stand_reads() -> None:
    """Read the shipped XL330 stand: a pendulum, a duty gain, PGS with one iteration."""
    stand = read_stand(REPO / "examples" / "bam" / "xl330_pendulum.toml")
    assert stand.scenario.pendulum is not None and stand.scenario.pendulum.mass == 0.49
    assert stand.duty_per_rad == pytest.approx(1.1509510008905426)
    assert stand.scenario.simulation.position_iterations == 1


def test_identify_bench_header_uses_the_same_rule() -> None:
    """Find bench columns up to case with the check's rule; two up to case stay ambiguous."""
    plan = bench_plan(["Time", "Position [deg]", "Target_Position [deg]", "Velocity [RPM]"], "bench.csv")
    assert plan.position == {"time": 0, "position": 1, "target_position": 2, "velocity": 3}
    assert plan.scale["velocity"] == pytest.approx(2 * 3.141592653589793 / 60)
    with pytest.raises(InputError, match="column 'velocity' is ambiguous"):
        bench_plan(["time", "position", "target_position", "Velocity", "velocity"], "bench.csv")


def test_bench_logs_read_header_units(tmp_path: Path) -> None:
    """``time [ms]``, ``position [deg]``, ``target_position (deg)``: SI in the BenchLog, like check."""
    si = _write(tmp_path / "si.csv", "time,position,target_position\n0,0,0.5\n0.01,0.1,0.5\n0.02,0.2,0.5\n")
    degrees = [0.0, 0.1 * 180 / math.pi, 0.2 * 180 / math.pi]
    rows = "".join(f"{10 * i},{d!r},{0.5 * 180 / math.pi!r}\n" for i, d in enumerate(degrees))
    units = _write(tmp_path / "units.csv", "time [ms],position [deg],target_position (deg)\n" + rows)
    a, b = read_bench_log(si), read_bench_log(units)
    for column in ("time", "position", "target_position"):
        np.testing.assert_allclose(getattr(b, column), getattr(a, column), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    ("header", "message"),
    [
        ("time,position [N*m],target_position", "column 'position [N*m]': unit 'N*m'"),
        ("time,position [deg],target_position [mm]", "the header units are of two joint types"),
        ("time,position,target_position,torque_enable [V]", "expected no unit (0 or 1 per sample)"),
    ],
)
def test_bench_log_unit_errors_are_one_line(tmp_path: Path, header: str, message: str) -> None:
    fields = header.count(",") + 1
    log = _write(
        tmp_path / "bad.csv", header + "\n" + "".join(",".join(["1"] * fields) + "\n" for _ in range(3))
    )
    with pytest.raises(InputError, match=re.escape(message)) as caught:
        read_bench_log(log)
    assert "\n" not in str(caught.value)

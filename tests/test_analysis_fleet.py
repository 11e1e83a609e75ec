"""Fleets: check over a folder, a glob or a partitioned Parquet dataset, merged exactly, on Dask too.

The merged report of a fleet's parts must equal the report of one log holding all their rows (the
counts, durations and margin quantiles; the histogram is the same), in this process and on a local
Dask distributed cluster with one worker process.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.analysis.api import check_log
from drive_envelope._src.analysis.check import CheckOptions
from drive_envelope._src.analysis.fleet import check_fleet, fleet_parts, is_fleet, merge_reports
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError

ENVELOPE = PerformanceEnvelope(
    max_effort=10.0, max_actuator_velocity=3.0, velocity_dependent_resistance=0.5, speed_effort_gradient=0.1
)


def _columns(seed: int, rows: int = 500) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    time = np.arange(rows) * 0.01
    velocity = rng.uniform(-3.2, 3.2, rows)  # a few samples beyond both lines
    effort = rng.uniform(-10.5, 10.5, rows)
    return {"time": time, "velocity": velocity, "effort": effort}


def _write_csv(path: Path, columns: dict[str, np.ndarray], joint: str | None = None) -> None:
    names = list(columns)
    lines = [",".join(names + (["joint"] if joint else []))]
    for i in range(len(columns["time"])):
        cells = [repr(float(columns[name][i])) for name in names] + ([joint] if joint else [])
        lines.append(",".join(cells))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _strip(data: dict[str, object]) -> dict[str, object]:
    """A report's JSON without what names the parts (source, rows of a part)."""
    text = json.dumps(data)
    data = json.loads(text)
    data.pop("source"), data.pop("parts", None)
    for joint in data["joints"]:  # type: ignore[attr-defined]
        # one log counts the step from a part's last sample to the next part's first: parts do not
        joint.pop("duration"), joint.pop("time_outside"), joint.pop("time_released")
        for curve in ("effort", "velocity"):
            worst = joint[curve]["worst"]
            if worst is not None:
                worst.pop("row"), worst.pop("source", None)
    return data


def test_a_folder_of_logs_merges_to_the_report_of_their_concatenation(tmp_path: Path) -> None:
    """Three robots' logs, two joints each: the merged report equals the one of all rows at once."""
    robots = [tmp_path / "fleet" / f"robot{i}" for i in range(3)]
    whole: dict[str, list[np.ndarray]] = {"time": [], "velocity": [], "effort": [], "joint": []}
    for i, folder in enumerate(robots):
        for j, joint in enumerate(("hip", "knee")):
            columns = _columns(10 * i + j)
            columns["time"] = columns["time"] + 10.0 * i  # each part after the last: one time line
            _write_csv(folder / f"{joint}.csv", columns, joint)
            for key, values in columns.items():
                whole[key].append(values)
            whole["joint"].append(np.full(500, joint, dtype=object))
    (tmp_path / "fleet" / "robot0" / "hip.json").write_text("{}", encoding="utf-8")  # a sidecar: not a log
    parts = fleet_parts(tmp_path / "fleet")
    assert [Path(p).relative_to(tmp_path / "fleet").as_posix() for p in parts] == [
        "robot0/hip.csv", "robot0/knee.csv", "robot1/hip.csv", "robot1/knee.csv", "robot2/hip.csv",
        "robot2/knee.csv",
    ]  # fmt: skip
    # the one log: hip rows of every robot, then knee rows, as the merge orders them per joint
    order = [k for j in (0, 1) for k in (j, 2 + j, 4 + j)]
    table = {key: np.concatenate([whole[key][k] for k in order]) for key in whole}
    single = check_log(ENVELOPE, table)
    fleet = check_fleet(ENVELOPE, tmp_path / "fleet")
    assert fleet.report.parts == 6 and fleet.rows == 3000 and fleet.workers == 0
    assert _strip(fleet.report.to_dict()) == _strip(single.to_dict())
    assert [j.duration for j in fleet.report.joints] == pytest.approx([3 * 4.99, 3 * 4.99])  # per part
    for merged, alone in zip(fleet.report.joints, single.joints, strict=True):
        np.testing.assert_array_equal(merged.effort.histogram, alone.effort.histogram)
        assert merged.samples_outside == alone.samples_outside > 0
    worst = fleet.report.joints[0].worst
    assert worst is not None and worst.source is not None and worst.source.endswith("hip.csv")
    glob = check_fleet(ENVELOPE, str(tmp_path / "fleet" / "*" / "knee.csv")).report
    assert glob.parts == 3 and [j.joint for j in glob.joints] == ["knee"]


def test_a_partitioned_parquet_dataset_takes_the_joint_from_its_folders(tmp_path: Path) -> None:
    """dataset/joint=NAME/part-K.parquet without a joint column: the folder names the joint."""
    pq = pytest.importorskip("pyarrow.parquet")
    pa = pytest.importorskip("pyarrow")
    root = tmp_path / "dataset"
    expected = {}
    for j, joint in enumerate(("hip", "knee")):
        parts = [_columns(7 * j + k, 300) for k in range(2)]
        for k, columns in enumerate(parts):
            (root / f"joint={joint}").mkdir(parents=True, exist_ok=True)
            pq.write_table(pa.table(columns), root / f"joint={joint}" / f"part-{k}.parquet")
        expected[joint] = check_log(
            ENVELOPE, {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
        )
    assert is_fleet(root)
    report = check_fleet(ENVELOPE, root).report
    assert [j.joint for j in report.joints] == ["hip", "knee"]
    for check in report.joints:
        alone = expected[check.joint].joints[0]
        assert check.samples == 600 and check.samples_outside == alone.samples_outside
        assert check.effort.quantiles == alone.effort.quantiles
        assert check.duration is not None and alone.duration is not None


def test_check_on_a_local_dask_cluster_equals_the_in_process_check(tmp_path: Path) -> None:
    """--scheduler: the same merged report from a local Dask cluster with one worker process."""
    distributed = pytest.importorskip("distributed")
    for i in range(4):
        _write_csv(tmp_path / "fleet" / f"log{i}.csv", _columns(i), "joint")
    local = check_fleet(ENVELOPE, tmp_path / "fleet")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        remote = check_fleet(ENVELOPE, tmp_path / "fleet", scheduler=cluster.scheduler_address)
    assert remote.workers == 1
    assert remote.report.to_dict() == local.report.to_dict()


def test_cli_checks_a_folder_and_names_a_bad_part(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """check ENVELOPE FOLDER prints the merged report; a bad part is one line naming it."""
    from drive_envelope._src.cli.main import main

    for i in range(2):
        _write_csv(tmp_path / "fleet" / f"log{i}.csv", _columns(i), "joint")
    envelope = tmp_path / "env.toml"
    envelope.write_text(
        "joint = 'revolute'\nmax_effort = 10.0\nmax_actuator_velocity = 3.0\n"
        "velocity_dependent_resistance = 0.5\nspeed_effort_gradient = 0.1\n",
        encoding="utf-8",
    )
    assert main(["check", str(envelope), str(tmp_path / "fleet"), "--json"]) == 1  # violations
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert data["parts"] == 2 and data["joints"][0]["samples"] == 1000
    assert "checked 2 log(s), 1000 samples" in captured.err
    (tmp_path / "fleet" / "log9.csv").write_text("time,velocity\n0,1\n", encoding="utf-8")
    assert main(["check", str(envelope), str(tmp_path / "fleet")]) == 2
    assert "log9.csv: no column 'effort'" in capsys.readouterr().err
    assert main(["check", str(envelope), str(tmp_path / "none" / "*.csv")]) == 2
    assert "the pattern matches no log" in capsys.readouterr().err


def test_merge_refuses_parts_checked_differently(tmp_path: Path) -> None:
    table = _columns(0)
    a = check_log(ENVELOPE, table)
    b = check_log(ENVELOPE, table, options=CheckOptions(tolerance=0.5))
    with pytest.raises(InputError, match="checked with different thresholds"):
        merge_reports([a, b], "fleet")
    c = check_log(PerformanceEnvelope(max_effort=5.0), table)
    with pytest.raises(InputError, match="joint 'joint' has two envelopes"):
        merge_reports([a, c], "fleet")


@pytest.mark.parametrize(
    ("scheduler", "message"),
    [
        ("nonsense", "missing port number in address 'nonsense'"),
        ("tcp://host:abc", "invalid literal for int()"),
        ("foo://x:1", "unknown address scheme 'foo'"),
    ],
)
def test_a_malformed_scheduler_address_is_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], scheduler: str, message: str
) -> None:
    """Exit 2 with one line: distributed's ValueError for the address was an internal error (exit 1)."""
    pytest.importorskip("distributed")
    from drive_envelope._src.cli.main import main

    _write_csv(tmp_path / "fleet" / "log0.csv", _columns(0))
    envelope = tmp_path / "env.toml"
    envelope.write_text("max_effort = 10.0\nmax_actuator_velocity = 3.0\n", encoding="utf-8")
    assert main(["check", str(envelope), str(tmp_path / "fleet"), "--scheduler", scheduler]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--scheduler {scheduler!r}: {message}" in err[0]
    assert "expected an address such as tcp://HOST:8786" in err[0]

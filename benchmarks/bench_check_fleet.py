"""check over a fleet: rows per second in this process and on a local Dask cluster of 1 and 2 workers.

The dataset is generated here into a temporary folder (removed afterwards): a hive-partitioned
Parquet dataset ``joint=NAME/part-K.parquet`` of ``--rows`` samples (time, velocity, effort; the
joint comes from the folder) in ``--parts`` part files, a few per cent of the samples outside the
envelope. Each configuration is run ``--rounds`` times, interleaved (in-process, 1 worker, 2
workers, in-process, ...); the table gives medians: wall time, rows per second, and the merge of the
part reports alone (``merge_reports``, timed by ``check_fleet``). The Dask clusters are
``distributed.LocalCluster`` with one thread per worker process, started before the timed runs.

    python benchmarks/bench_check_fleet.py                          # 1e7 rows, 40 parts
    python benchmarks/bench_check_fleet.py --rows 1e8 --parts 200   # the 1e8-row run of docs/analysis.md
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from drive_envelope._src.analysis.fleet import check_fleet
from drive_envelope._src.envelope.model import PerformanceEnvelope

ENVELOPE = PerformanceEnvelope(
    max_effort=10.0, max_actuator_velocity=3.0, velocity_dependent_resistance=0.5, speed_effort_gradient=0.1
)
JOINTS = ("hip", "knee", "ankle", "wrist")


def write_dataset(root: Path, rows: int, parts: int, seed: int = 0) -> int:
    """A partitioned dataset of ``rows`` samples in ``parts`` files; returns the bytes written."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    rng = np.random.default_rng(seed)
    per_part = rows // parts
    written = 0
    for k in range(parts):
        joint = JOINTS[k % len(JOINTS)]
        folder = root / f"joint={joint}"
        folder.mkdir(parents=True, exist_ok=True)
        n = per_part + (rows - per_part * parts if k == parts - 1 else 0)
        start = (k // len(JOINTS)) * per_part
        table = pa.table(
            {
                "time": (start + np.arange(n)) * 0.002,
                "velocity": rng.uniform(-3.05, 3.05, n),
                "effort": rng.uniform(-10.2, 10.2, n),
            }
        )
        path = folder / f"part-{k:05d}.parquet"
        pq.write_table(table, path, compression="snappy")
        written += path.stat().st_size
    return written


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=float, default=1e7, help="samples in the dataset (default 1e7)")
    parser.add_argument("--parts", type=int, default=40, help="part files (default 40)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (default 3)")
    parser.add_argument("--workers", default="0,1,2", help="configurations: 0 = in process (default 0,1,2)")
    args = parser.parse_args()
    rows = int(args.rows)
    configurations = [int(w) for w in args.workers.split(",")]
    folder = Path(tempfile.mkdtemp(prefix="fleet-bench-"))
    clusters = {}
    try:
        started = time.perf_counter()
        size = write_dataset(folder, rows, args.parts)
        print(f"dataset: {rows:.3g} rows in {args.parts} parts, {size / 2**20:.0f} MiB Parquet, "
              f"written in {time.perf_counter() - started:.0f} s")  # fmt: skip
        if any(configurations):
            from distributed import LocalCluster

            for workers in configurations:
                if workers:
                    clusters[workers] = LocalCluster(
                        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
                    )
        results: dict[int, list[tuple[float, float]]] = {w: [] for w in configurations}
        reference = None
        for _ in range(args.rounds):
            for workers in configurations:
                scheduler = clusters[workers].scheduler_address if workers else None
                run = check_fleet(ENVELOPE, folder, scheduler=scheduler)
                assert run.rows == rows, (run.rows, rows)
                if reference is None:
                    reference = run.report.to_dict()
                else:  # every configuration gives the same merged report
                    assert run.report.to_dict() == reference
                results[workers].append((run.wall_time_s, run.merge_time_s))
        print(f"{'configuration':<22}{'wall [s]':>10}{'rows/s':>14}{'merge [ms]':>12}")
        for workers, runs in results.items():
            wall = statistics.median(r[0] for r in runs)
            merge = statistics.median(r[1] for r in runs)
            label = "in process" if workers == 0 else f"Dask, {workers} worker(s)"
            print(f"{label:<22}{wall:>10.2f}{rows / wall:>14.3g}{1e3 * merge:>12.2f}")
    finally:
        for cluster in clusters.values():
            cluster.close()
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()

"""Benchmark: `check` on a large log vs. pyarrow just reading the same file, side by side.

Generates a log (default 10 million rows, the CSV of `drive-envelope simulate`: time, position,
velocity, effort) in a temporary directory, then times, interleaved and each in a fresh subprocess
(so peak memory is per task):

* ``read``: ``pyarrow.csv.read_csv`` of the whole file (multi-threaded), the baseline;
* ``check``: ``drive_envelope.analysis.check_log`` streaming the file in chunks;
* ``check-csv-python``: the same check through the standard library's CSV engine
  (``engine="python"``), the measurement that keeps pyarrow's CSV engine in the one log reader;
* the same two for a Parquet copy (``pyarrow.parquet.read_table`` vs ``check_log``);
* ``check-joints``: ``check_log`` on a long-format copy whose rows cycle through ``--joints``
  distinct joint names (default 1000, the most a check accepts): memory must stay bounded, about
  one chunk plus 32 KiB per joint, whatever the number of rows.

Prints the median wall time and peak RSS of each, and the ratio check / read (goal: <= 5). Usage::

    python benchmarks/bench_check.py [--rows 10000000] [--repeats 3] [--joints 1000]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_CHECK = (
    "from drive_envelope import PerformanceEnvelope\n"
    "from drive_envelope.analysis import check_log\n"
    "env = PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=30.0,"
    " velocity_dependent_resistance=0.05, speed_effort_gradient=0.5)",
    "assert check_log(env, {path!r}).joints[0].samples == {rows}",
)
# task -> (setup, timed statement); imports are not timed
_TASKS = {
    "read-csv": ("import pyarrow.csv as c", "c.read_csv({path!r})"),
    "check-csv": _CHECK,
    "check-csv-python": (_CHECK[0], _CHECK[1].replace("{path!r})", "{path!r}, engine='python')")),
    "read-parquet": ("import pyarrow.parquet as q", "q.read_table({path!r})"),
    "check-parquet": _CHECK,
    "check-joints": (_CHECK[0], "assert sum(j.samples for j in check_log(env, {path!r}).joints) == {rows}"),
}


def _generate(directory: Path, rows: int) -> tuple[Path, Path]:
    import numpy as np
    import pyarrow as pa
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    csv_path, parquet_path = directory / "log.csv", directory / "log.parquet"
    rng = np.random.default_rng(0)
    block = 1_000_000
    writer = None
    with pacsv.CSVWriter(
        csv_path, pa.schema([(n, pa.float64()) for n in ("time", "position", "velocity", "effort")])
    ) as out:
        for start in range(0, rows, block):
            n = min(block, rows - start)
            t = (start + np.arange(n)) * 1e-3
            velocity = 25.0 * np.sin(0.7 * t) + rng.normal(0.0, 0.5, n)
            effort = 11.0 * np.cos(1.3 * t) + rng.normal(0.0, 0.3, n)
            table = pa.table(
                {"time": t, "position": np.cumsum(velocity) * 1e-3, "velocity": velocity, "effort": effort}
            )
            out.write_table(table)
            if writer is None:
                writer = pq.ParquetWriter(parquet_path, table.schema)
            writer.write_table(table)
    assert writer is not None
    writer.close()
    return csv_path, parquet_path


def _generate_joints(directory: Path, rows: int, joints: int) -> Path:
    import numpy as np
    import pyarrow as pa
    import pyarrow.csv as pacsv

    path = directory / "joints.csv"
    names = np.array([f"joint_{i}" for i in range(joints)])
    rng = np.random.default_rng(1)
    schema = pa.schema([("time", pa.float64()), ("joint", pa.string()), ("velocity", pa.float64()),
                        ("effort", pa.float64())])  # fmt: skip
    with pacsv.CSVWriter(path, schema) as out:
        for start in range(0, rows, 1_000_000):
            n = min(1_000_000, rows - start)
            index = start + np.arange(n)
            table = pa.table(
                {
                    "time": (index // joints) * 1e-3,
                    "joint": pa.array(names[index % joints]),
                    "velocity": rng.uniform(-25.0, 25.0, n),
                    "effort": rng.uniform(-11.0, 11.0, n),
                },
                schema=schema,
            )
            out.write_table(table)
    return path


def _run(task: str, path: Path, rows: int) -> tuple[float, float]:
    setup, statement = (part.format(path=str(path), rows=rows) for part in _TASKS[task])
    script = (
        f"import resource, time, json\n{setup}\n"
        f"t0 = time.perf_counter()\n{statement}\n"
        "rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024\n"
        "print(json.dumps([time.perf_counter() - t0, rss]))"
    )
    output = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True, text=True).stdout
    seconds, rss_mib = json.loads(output.strip().splitlines()[-1])
    return float(seconds), float(rss_mib)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", type=int, default=10_000_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--joints", type=int, default=1000)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        started = time.perf_counter()
        csv_path, parquet_path = _generate(Path(tmp), args.rows)
        joints_path = _generate_joints(Path(tmp), args.rows, args.joints)
        size_mib = csv_path.stat().st_size / 2**20
        print(f"generated {args.rows} rows: CSV {size_mib:.0f} MiB in {time.perf_counter() - started:.1f} s")
        results: dict[str, list[tuple[float, float]]] = {task: [] for task in _TASKS}
        for _ in range(args.repeats):  # interleaved, so machine load hits every task alike
            for task in _TASKS:
                path = parquet_path if task.endswith("parquet") else csv_path
                path = joints_path if task == "check-joints" else path
                results[task].append(_run(task, path, args.rows))
    medians = {
        task: (statistics.median(t for t, _ in runs), max(m for _, m in runs))
        for task, runs in results.items()
    }
    for task, (seconds, rss) in medians.items():
        print(f"{task:16s} median {seconds:7.3f} s   peak RSS {rss:7.0f} MiB   ({args.repeats} runs)")
    for kind in ("csv", "parquet"):
        ratio = medians[f"check-{kind}"][0] / medians[f"read-{kind}"][0]
        print(f"ratio check/read ({kind}): {ratio:.2f}  (goal <= 5)")
    engines = medians["check-csv-python"][0] / medians["check-csv"][0]
    print(f"ratio check python/pyarrow CSV engine: {engines:.2f}  (pyarrow stays while > 1.5)")


if __name__ == "__main__":
    main()

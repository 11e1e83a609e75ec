"""What a user waits for the first time an envelope model steps in MJWarp, and on later runs.

Warp compiles every kernel a model's step uses the first time it runs and keeps the binaries in
its kernel cache (``WARP_CACHE_PATH``, default ``~/.cache/warp/<version>``); later processes load
them. This benchmark points ``WARP_CACHE_PATH`` at a new empty folder and runs ``--runs`` fresh
Python processes one after another on it (the first cold, the rest cached). Each process builds a
Menagerie robot with its map's drives (``bench_mujoco.robot_spec``: the model's own kp/kv, the
same model as ``bench_mujoco.py --robot R``), puts it on Warp's default device with
``drive_envelope.mjwarp.put_model`` and times, in wall seconds:

* ``put``: ``put_model`` and ``mujoco_warp.make_data`` (nworld 1);
* ``first step``: the first ``mujoco_warp.step`` (the compile, or the cache load, of every kernel);
* ``next step``: the second step.

The folder is removed at the end. Progress goes to stderr.

    .venv/bin/python benchmarks/bench_mjwarp_first_run.py [--robot anymal-c] [--runs 2]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_mujoco


def child(robot_name: str) -> dict[str, Any]:
    """One process's times [s]: put (model and data), first step, next step; and Warp's version."""
    import mujoco_warp
    import warp as wp

    from drive_envelope.mjwarp import put_model
    from drive_envelope.mujoco import load_plugin

    load_plugin()
    spec = bench_mujoco.robot_spec(bench_mujoco.ROBOTS[robot_name], "plugin")
    start = time.perf_counter()
    model = put_model(spec)
    data = mujoco_warp.make_data(model.callback.act_bias.mj_model, nworld=1)
    put = time.perf_counter() - start
    times = []
    for _ in range(2):
        start = time.perf_counter()
        mujoco_warp.step(model, data)
        wp.synchronize()
        times.append(time.perf_counter() - start)
    return {"put": put, "first": times[0], "next": times[1], "warp": wp.__version__}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="anymal-c", choices=sorted(bench_mujoco.ROBOTS))
    parser.add_argument("--runs", type=int, default=2, help="processes on one cache (the first cold)")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.robot)))
        return 0
    if args.runs < 1:
        parser.error(f"--runs: expected at least 1, got {args.runs}")
    cache = tempfile.mkdtemp(prefix="warp-cache-")
    env = {**os.environ, "WARP_CACHE_PATH": cache}
    rows: list[dict[str, Any]] = []
    try:
        for run in range(args.runs):
            state = "cold" if run == 0 else "cached"
            print(f"run {run + 1}/{args.runs} ({state}) ...", file=sys.stderr, flush=True)
            command = [sys.executable, __file__, "--child", "--robot", args.robot]
            done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
            if done.returncode != 0:
                lines = done.stderr.strip().splitlines() or ["(no output)"]
                print(f"run {run + 1} failed: {lines[-1]}", file=sys.stderr)
                return 1
            rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    label = bench_mujoco.ROBOTS[args.robot].label
    print(f"MJWarp first run, {label} with its map's drives, warp {rows[0]['warp']},")
    print("a new kernel cache, one process per run, wall seconds:")
    for run, row in enumerate(rows):
        state = "cold" if run == 0 else "cached"
        print(
            f"  run {run + 1} ({state:6s})  put {row['put']:6.2f} s   first step {row['first']:7.2f} s"
            f"   next step {row['next'] * 1e3:8.2f} ms"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Start-up cost of the command line: ``drive-envelope --help`` against a bare ``python -c pass``.

The architecture goal is ``--help`` (and argument errors) within 5x a bare interpreter start, which
holds only while building the parser imports neither NumPy nor pint nor an engine. Runs are
interleaved (baseline, help, error, baseline, ...) so machine noise hits every kind alike; the
ratios of the medians are reported.

    python benchmarks/bench_cli_startup.py --repeats 21
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

GOAL = 5.0


def _time(command: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21, help="interleaved runs of each kind")
    args = parser.parse_args()
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="0")
    kinds = {
        "python -c pass": [sys.executable, "-c", "pass"],
        "drive-envelope --help": [sys.executable, "-m", "drive_envelope", "--help"],
        "drive-envelope derive --bogus": [sys.executable, "-m", "drive_envelope", "derive", "--bogus"],
        "import drive_envelope": [sys.executable, "-c", "import drive_envelope"],
    }
    for command in kinds.values():  # warm the bytecode cache
        subprocess.run(command, capture_output=True, env=env, check=False)
    times: dict[str, list[float]] = {name: [] for name in kinds}
    for _ in range(args.repeats):
        for name, command in kinds.items():
            times[name].append(_time(command))
    base = statistics.median(times["python -c pass"])
    print(f"{'command':34s} {'median [ms]':>12s} {'x python':>9s}")
    worst = 0.0
    for name, values in times.items():
        median = statistics.median(values)
        ratio = median / base
        if name != "python -c pass":
            worst = max(worst, ratio)
        print(f"{name:34s} {1e3 * median:12.1f} {ratio:9.2f}")
    verdict = "meets" if worst <= GOAL else "MISSES"
    print(f"largest ratio {worst:.2f}: {verdict} the goal of <= {GOAL:g}x a bare interpreter")
    return 0 if worst <= GOAL else 1


if __name__ == "__main__":
    raise SystemExit(main())

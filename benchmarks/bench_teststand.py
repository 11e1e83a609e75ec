"""Benchmark: the reference engine on one stand (``reference.simulate``, a batch of one) over 10 s.

Times a PGS and a TGS scenario from ``examples/scenarios/`` (``step_response_pgs.toml``,
``step_response_tgs.toml``: envelope, 4 position and 1 velocity iterations, dt = 1/120 s), their
duration raised to 10 s (1200 steps). ``--baseline FILE`` times another implementation's
``simulate(scenario)`` in the same interleaved rounds and prints ours over it; e.g. the scalar loop
the reference engine ran before it became a batch of one, copied from git::

    git show REV:src/drive_envelope/_src/teststand/engines/reference.py > /tmp/old/old_reference.py

(and its imports made importable from there). Every timing is the median thread CPU time
(``time.thread_time``: what this process spends, not what other jobs on a shared machine take) of
``--repeats`` rounds after one warm-up round; the candidates run interleaved, the order reversed
every other round. Usage::

    python benchmarks/bench_teststand.py [--repeats 9] [--duration 10] [--baseline FILE]
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from drive_envelope._src.scenario.spec import Scenario, load_scenario
from drive_envelope._src.teststand.engines import reference

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_kernels import machine, median_times  # noqa: E402  (the benchmarks' shared helpers)

SCENARIOS = ("step_response_pgs.toml", "step_response_tgs.toml")


def load_baseline(path: str) -> Callable[[Scenario], Any]:
    """``simulate`` of the module at ``path`` (its folder goes on ``sys.path`` for its imports)."""
    sys.path.insert(0, str(Path(path).resolve().parent))
    spec = importlib.util.spec_from_file_location("baseline_reference", path)
    if spec is None or spec.loader is None:
        raise SystemExit(f"--baseline {path}: not a Python module")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while it runs
    spec.loader.exec_module(module)
    simulate: Callable[[Scenario], Any] = module.simulate
    return simulate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time per run [s]")
    parser.add_argument("--baseline", help="a file whose simulate(scenario) to time beside ours")
    args = parser.parse_args()
    baseline = load_baseline(args.baseline) if args.baseline else None
    print(machine())
    for name in SCENARIOS:
        scenario = load_scenario(ROOT / "examples" / "scenarios" / name)
        simulation = dataclasses.replace(scenario.simulation, duration=args.duration)
        scenario = dataclasses.replace(scenario, simulation=simulation)
        fns: dict[str, Callable[[], Any]] = {"reference": lambda s=scenario: reference.simulate(s)}
        if baseline is not None:
            fns["baseline"] = lambda s=scenario: baseline(s)
            ours, theirs = reference.simulate(scenario), baseline(scenario)
            gap = max(
                float(np.max(np.abs(getattr(ours, c) - getattr(theirs, c))))
                for c in ("position", "velocity", "effort")
            )
        medians = dict(median_times(fns, args.repeats, clock=time.thread_time))
        sim = scenario.simulation
        ours_s = medians["reference"]
        line = (
            f"{name}: {sim.solver} {sim.position_iterations}/{sim.velocity_iterations}, {sim.steps} steps: "
            f"reference {ours_s * 1e3:.1f} ms ({ours_s / sim.steps * 1e6:.1f} us/step)"
        )
        if baseline is not None:
            theirs_s = medians["baseline"]
            line += f", baseline {theirs_s * 1e3:.1f} ms, ratio {ours_s / theirs_s:.2f}x"
            line += f", max |difference| {gap:.2g}"
        print(line)


if __name__ == "__main__":
    main()

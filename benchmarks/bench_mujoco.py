"""Cost of the drive_envelope.envelope plugin: median mj_step time of the example quadruped.

The same 12-DOF quadruped (examples/mujoco/quadruped.py) is built twice: every joint driven by the
plugin, and every joint driven by MuJoCo's native ``position`` actuator with the same gains and
``forcerange = +-max_effort``. Both run the same scripted controls from the same state through
``mujoco.rollout`` (a C loop, one thread, no Python per step), in alternating blocks so that machine
load hits both alike. Two workloads:

* own motion: each model runs the scripted controls from the standing start (its own contacts);
* same states: both models take one step from each of the same states (recorded from the plugin
  run), so the constraint solver does the same work and only the actuators differ.

Prints the median time per step of each model and their ratio (goal: <= 1.10).

    .venv/bin/python benchmarks/bench_mujoco.py [--blocks 30] [--steps 1500]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples" / "mujoco"))

import quadruped


def _setup(kind: str, steps: int) -> tuple[object, object, np.ndarray, np.ndarray]:
    import mujoco

    model = quadruped.build_quadruped(kind).compile()  # type: ignore[arg-type]
    data = mujoco.MjData(model)
    names = quadruped.joint_names()
    qpos = [int(model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)]) for n in names]
    data.qpos[qpos] = quadruped.targets(0.0)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.zeros(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    times = np.arange(steps) * model.opt.timestep
    control = np.stack([quadruped.targets(t) for t in times])[None]
    return model, data, state[None], control


def _median_per_step(runs: dict[str, tuple], blocks: int, steps: int) -> dict[str, float]:
    """Median over ``blocks`` of the time per step of each model; models alternate within a block."""
    from mujoco import rollout

    per_step: dict[str, list[float]] = {kind: [] for kind in runs}
    with rollout.Rollout(nthread=0) as runner:
        for block in range(blocks + 2):
            order = list(runs) if block % 2 == 0 else list(reversed(list(runs)))
            for kind in order:
                model, data, state, control = runs[kind]
                start = time.perf_counter()
                runner.rollout(model, data, state, control)
                elapsed = time.perf_counter() - start
                if block >= 2:  # the first blocks warm the caches
                    per_step[kind].append(elapsed / steps)
    return {kind: statistics.median(values) for kind, values in per_step.items()}


def main() -> int:
    parser = argparse.ArgumentParser(description="median mj_step time: plugin vs native position actuators")
    parser.add_argument("--blocks", type=int, default=30, help="timed blocks per model (default 30)")
    parser.add_argument("--steps", type=int, default=1500, help="steps per block (default 1500 = 3 s)")
    args = parser.parse_args()

    import mujoco
    from mujoco import rollout

    from drive_envelope.mujoco import load_plugin

    load_plugin()
    own = {kind: _setup(kind, args.steps) for kind in ("plugin", "position")}
    # same states: record the plugin run, then step each model once from every recorded state
    model, data, state0, control = own["plugin"]
    states, _ = rollout.rollout(model, data, state0, control)
    starts, controls = states[0], control[0][:, None, :]
    same = {kind: (run[0], run[1], starts, controls) for kind, run in own.items()}
    nv = own["plugin"][0].nv  # type: ignore[attr-defined]
    print(f"mujoco {mujoco.__version__}, quadruped (12 actuated DOFs, nv = {nv}), Euler, dt = 2 ms, "
          f"{args.blocks} blocks x {args.steps} steps; median time per mj_step:")  # fmt: skip
    for label, runs in (("own motion", own), ("same states", same)):
        median = _median_per_step(runs, args.blocks, args.steps)
        ratio = median["plugin"] / median["position"]
        print(
            f"  {label:11s}  position {median['position'] * 1e6:7.2f} us"
            f"   plugin {median['plugin'] * 1e6:7.2f} us   ratio plugin/position = {ratio:.3f} (goal <= 1.10)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Domain randomization of the performance envelope with ``mujoco.rollout``.

Each drive keeps its numbers in the ``MjModel`` (``actuator_dynprm`` of its effort actuator), and the
plugin reads them at every step. So randomizing the envelope is randomizing models: copy the model,
give each copy its own envelope with ``drive_envelope.mujoco.set_envelope``, and roll them all out
in one ``mujoco.rollout`` call (threads share MjData objects made from any one of the copies; each
rollout uses its own model's numbers). Between episodes of a single model, ``set_envelope`` on that
model takes effect at the next ``mj_step`` of every MjData: no new MjData, no recompilation.

Here the knees of the example quadruped (examples/mujoco/quadruped.py, Harmonic Drive FHA-8C-50 from
the catalog) get a max_effort drawn in +-30 % and a max_actuator_velocity in +-15 % around the
datasheet's, for 16 models, and the same squat runs on all of them. The table shows that each
rollout's knee efforts and speeds stay within its own envelope.

    .venv/bin/python examples/mujoco/domain_randomization.py [--models 16] [--seconds 1.5] [--seed 0]
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import quadruped

KNEES = [name for name in quadruped.joint_names() if name.endswith("knee")]


def randomized_models(count: int, seed: int) -> tuple[list[Any], list[Any]]:
    """``count`` copies of the quadruped, each with its own knee envelope; returns (models, envelopes)."""
    from drive_envelope.mujoco import set_envelope

    base = quadruped.build_quadruped("plugin").compile()
    nominal = quadruped.envelopes()[KNEES[0]]
    rng = np.random.default_rng(seed)
    models, drawn = [], []
    for _ in range(count):
        model = copy.copy(base)  # an independent MjModel: its own actuator_dynprm
        envelope = dataclasses.replace(
            nominal,
            max_effort=nominal.max_effort * rng.uniform(0.7, 1.3),
            max_actuator_velocity=nominal.max_actuator_velocity * rng.uniform(0.85, 1.15),
        )
        for knee in KNEES:
            set_envelope(model, knee, envelope)
        models.append(model)
        drawn.append(envelope)
    return models, drawn


def roll_out(models: list[Any], seconds: float, threads: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Run the scripted squat on every model at once; (knee velocity, knee effort), (nmodel, nstep, 4)."""
    import mujoco
    from mujoco import rollout

    model = models[0]
    data = mujoco.MjData(model)
    joints = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in quadruped.joint_names()]
    data.qpos[model.jnt_qposadr[joints]] = quadruped.targets(0.0)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.zeros(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state0, spec)
    steps = round(seconds / model.opt.timestep)
    control = np.stack([quadruped.targets(k * model.opt.timestep) for k in range(steps)])
    datas = [mujoco.MjData(model) for _ in range(threads)]
    states, _ = rollout.rollout(models, datas, np.tile(state0, (len(models), 1)), control[None])
    knees = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in KNEES]
    velocity = states[:, :, 1 + model.nq + model.jnt_dofadr[knees]]
    # the effort of each step is not part of the state: recompute it from the recorded states
    effort = np.zeros_like(velocity)
    actuators = [quadruped.joint_names().index(n) for n in KNEES]
    for m in range(len(models)):
        replay = mujoco.MjData(models[m])
        mujoco.mj_setState(models[m], replay, state0, spec)
        for k in range(steps):
            replay.ctrl[:] = control[k]
            mujoco.mj_step(models[m], replay)
            effort[m, k] = replay.actuator_force[actuators]
        assert np.array_equal(replay.qvel[model.jnt_dofadr[knees]], velocity[m, -1])  # same as rollout
    return velocity, effort


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: randomize, roll out, print each model's envelope and its knees' peaks."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--models", type=int, default=16, help="number of randomized models (default 16)")
    parser.add_argument("--seconds", type=float, default=1.5, help="simulated time per rollout [s]")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    args = parser.parse_args(argv)

    from drive_envelope.analysis import check_samples
    from drive_envelope.mujoco import load_plugin

    load_plugin()
    models, drawn = randomized_models(args.models, args.seed)
    velocity, effort = roll_out(models, args.seconds)
    print(
        f"{'model':>5s} {'max_effort':>11s} {'peak |effort|':>14s} {'v_max':>8s} {'peak |v|':>9s} "
        f"{'outside':>8s}"
    )
    for m, envelope in enumerate(drawn):
        outside = sum(
            check_samples(envelope, velocity[m, :, j], effort[m, :, j]).samples_outside
            for j in range(len(KNEES))
        )
        print(
            f"{m:5d} {envelope.max_effort:9.3f} Nm {np.abs(effort[m]).max():11.3f} Nm "
            f"{envelope.max_actuator_velocity:8.3f} {np.abs(velocity[m]).max():9.3f} {outside:8d}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

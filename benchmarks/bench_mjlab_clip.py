"""Cost of the mjlab explicit actuator's clip rules and of the mass-matrix response, per physics step.

Three things, each on ``(num_envs, targets)`` CPU tensors as mjlab's fused group hands them over:

* ``control_law`` of ``PerformanceEnvelopeActuator`` (``clip="end_of_step"``: PhysX's clamp at the
  end-of-step velocity; from 4096 elements one ``torch.compile`` kernel, compiled in the warm-up),
  of ``StartOfStepEnvelopeActuator`` (``clip="start_of_step"``) and of mjlab's ``IdealPdActuator``
  and ``DcMotorActuator``, on the same command;
* the response refresh of ``update()`` (``(M^-1)_ii`` from MJWarp's CSR ``data.M``: dense fill,
  batched Cholesky, inverse diagonal) for a model's ``nv`` at ``num_envs`` worlds, with ``data.M``
  taken from MuJoCo at the model's first keyframe (the Menagerie Go2 and G1 from ../shared/data).

Rounds alternate the order (ABC..., ...CBA); medians of the calling thread's CPU time over the
rounds with torch on one thread, so the other jobs on the machine do not enter it. Needs mjlab
(``.venv-mjlab``); elsewhere it says so and exits 0.

    .venv-mjlab/bin/python benchmarks/bench_mjlab_clip.py [--envs 4096] [--targets 12] [--rounds 21]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
MENAGERIE = ROOT.parent / "shared" / "data" / "menagerie"


def _median_times(calls: dict[str, Callable[[], Any]], rounds: int, repeat: int) -> dict[str, float]:
    names = list(calls)
    times: dict[str, list[float]] = {name: [] for name in names}
    for name in names:  # warm up (the compile of the fused kernel happens here)
        calls[name]()
        calls[name]()
    for index in range(rounds):
        for name in names if index % 2 == 0 else names[::-1]:
            start = time.thread_time()
            for _ in range(repeat):
                calls[name]()
            times[name].append((time.thread_time() - start) / repeat)
    return {name: statistics.median(values) for name, values in times.items()}


def _laws(envs: int, targets: int) -> dict[str, Callable[[], Any]]:
    import torch
    from mjlab.actuator import DcMotorActuator, IdealPdActuator
    from mjlab.actuator.actuator import ActuatorCmd

    from drive_envelope._src.adapters.mjlab.actuator import (
        PerformanceEnvelopeActuator,
        StartOfStepEnvelopeActuator,
    )

    shape = (envs, targets)
    gen = torch.Generator().manual_seed(0)
    q, v, target = (torch.randn(shape, generator=gen) * s for s in (0.5, 6.0, 0.5))
    cmd = ActuatorCmd(
        position_target=target,
        velocity_target=torch.zeros(shape),
        effort_target=torch.zeros(shape),
        pos=q,
        vel=v,
    )
    full = {
        "stiffness": 40.0,
        "damping": 2.0,
        "force_limit": 25.0,
        "max_effort": 25.0,
        "max_actuator_velocity": 10.0,
        "velocity_dependent_resistance": 0.1,
        "speed_effort_gradient": 0.25,
        "response": 20.0,
        "physics_dt": 0.005,
        "effort_prev": 0.0,
        "history": 1.0,
        "saturation_effort": 40.0,
        "velocity_limit_motor": 10.0,
    }
    params = {name: torch.full(shape, value) for name, value in full.items()}
    params["velocity_prev"] = v * 0.9
    kinds = {
        "end_of_step": PerformanceEnvelopeActuator,
        "start_of_step": StartOfStepEnvelopeActuator,
        "ideal_pd": IdealPdActuator,
        "dc_motor": DcMotorActuator,
    }
    laws: dict[str, Callable[[], Any]] = {}
    for name, kind in kinds.items():
        own = {key: params[key] for key in kind.param_names}
        laws[name] = lambda kind=kind, own=own: kind.control_law(own, cmd)
    return laws


def _responses(envs: int) -> dict[str, Callable[[], Any]]:
    import mujoco
    import torch

    from drive_envelope._src.adapters.mjlab.response import MassMatrixResponse

    calls: dict[str, Callable[[], Any]] = {}
    for label, path in (("go2", MENAGERIE / "go2.xml"), ("g1", MENAGERIE / "unitree_g1" / "g1.xml")):
        if not path.is_file():
            print(f"  ({label}: {path} absent, skipped)")
            continue
        model = mujoco.MjModel.from_xml_path(str(path))
        data = mujoco.MjData(model)
        if model.nkey:
            mujoco.mj_resetDataKeyframe(model, data, 0)
        mujoco.mj_forward(model, data)
        refresh = MassMatrixResponse(model, "cpu")
        packed = torch.as_tensor(data.M, dtype=torch.float32).expand(envs, -1).contiguous()
        step = iter(range(10**9))  # a new step each call: the shared diagonal is recomputed
        calls[f"response_{label} (nv {model.nv})"] = lambda r=refresh, p=packed, s=step: r.diagonal(
            p, next(s)
        )
    return calls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=4096)
    parser.add_argument("--targets", type=int, default=12)
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--repeat", type=int, default=10, help="calls per timed block")
    args = parser.parse_args()
    try:
        import mjlab.actuator  # noqa: F401
    except ModuleNotFoundError:
        print(
            "bench_mjlab_clip: needs mjlab; run it with .venv-mjlab/bin/python (make test-mjlab creates it)"
        )
        return
    import torch

    torch.set_num_threads(1)
    laws = _median_times(_laws(args.envs, args.targets), args.rounds, args.repeat)
    print(
        f"control_law on ({args.envs}, {args.targets}) CPU tensors, thread CPU time, median of {args.rounds}:"
    )
    for name, value in laws.items():
        print(f"  {name:<14} {value * 1e6:9.1f} us")
    for name in ("end_of_step", "start_of_step"):
        pd, dc = laws[name] / laws["ideal_pd"], laws[name] / laws["dc_motor"]
        print(f"  {name} / ideal_pd = {pd:.2f}x, / dc_motor = {dc:.2f}x")
    responses = _median_times(_responses(args.envs), args.rounds, args.repeat)
    print(f"update()'s mass-matrix response at {args.envs} worlds (per robot and step, all its groups):")
    for name, value in responses.items():
        print(f"  {name:<22} {value * 1e6:9.1f} us ({value * 1e9 / args.envs:.0f} ns a world)")


if __name__ == "__main__":
    main()

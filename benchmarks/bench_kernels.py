"""Benchmark: the envelope clamps against their peers, side by side in one run, N = 1,000,000 DOFs.

Sections (each skipped when its package is missing; the GPU rows only when CUDA is present):

* NumPy reference: explicit ``clamp_effort`` and implicit ``clamp_drive_impulse`` (default mode
  and ``physx_exact=True``, float64 and float32) / ``clamp_effort_implicit`` against ``np.clip`` of
  the same arrays (goals: explicit <= 15x, implicit <= 10x: five arrays read, one written, floor
  ~3x). ``--baseline MODULE`` times another
  implementation's ``clamp_effort``, ``clamp_drive_impulse`` and ``clamp_effort_implicit`` (same
  signatures; e.g. the previous release's ``envelope/clamp.py`` copied under another name) in the
  same interleaved rounds and prints ours over it.
* Warp (float32), CPU and CUDA: the implicit envelope clamp (``drive_envelope.warp``) against
  Newton's ``ClampingDCMotor.modify_forces`` on the same arrays (goal: <= 1.5x on the CPU) and
  against a copy kernel moving the same number of bytes (goal on a GPU: <= 3x).
* PyTorch (float32), CPU and CUDA: explicit and implicit clamps against an Isaac Lab style DC-motor
  clip (torque-speed line and effort cap with torch ops; goals: explicit <= 1x, implicit <= 2x, met
  by the ``torch.compile``-fused implicit clamp; the eager one is printed beside it).

Every timing is the median of ``--repeats`` rounds after one warm-up round; within a section the
candidates run interleaved (one of each per round), so load changes on a shared machine hit all of
them alike (the order is reversed every other round), and ratios are taken between medians of the
same run. Usage::

    python benchmarks/bench_kernels.py [--n 1000000] [--repeats 21] [--baseline MODULE]
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import os
import platform
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import drive_envelope as de

DT = 0.005
"""Time step of the implicit clamps [s]."""


def machine() -> str:
    """One line describing the CPU, the core count and the package versions."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            cpu = next(line.split(":", 1)[1].strip() for line in info if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    versions = [f"numpy {np.__version__}"]
    for name in ("warp", "newton", "torch"):
        if importlib.util.find_spec(name) is not None:
            module = __import__(name)
            versions.append(f"{name} {getattr(module, '__version__', '?')}")
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, " + ", ".join(versions)


def median_times(
    fns: dict[str, Callable[[], Any]],
    repeats: int,
    sync: Callable[[], None] = lambda: None,
    clock: Callable[[], float] = time.perf_counter,
) -> list[tuple[str, float]]:
    """Median time [s] of each function over ``repeats`` rounds, after one warm-up round.

    ``clock`` is wall time by default; ``time.thread_time`` where other jobs share the machine.

    The functions run interleaved (one of each per round, the order reversed every other round),
    so a load change on a shared machine hits all of them alike and their ratios stay meaningful.
    """
    times: dict[str, list[float]] = {name: [] for name in fns}
    for round_index in range(repeats + 1):
        # every other round backwards, so that no candidate always follows the same one (what
        # runs before a function changes its cache state: up to 15% at N = 1e6)
        order = list(fns.items())
        for name, fn in order if round_index % 2 else order[::-1]:
            start = clock()
            fn()
            sync()
            if round_index:
                times[name].append(clock() - start)
    return [(name, statistics.median(values)) for name, values in times.items()]


def report(rows: list[tuple[str, float]], ratios: list[tuple[str, str, str, float | None]]) -> None:
    """Print the medians and the ratios with their goals."""
    timings = dict(rows)
    for name, seconds in rows:
        print(f"  {name:<46} {seconds * 1e3:9.3f} ms")
    for label, num, den, goal in ratios:
        ratio = timings[num] / timings[den]
        verdict = "" if goal is None else ("  ok" if ratio <= goal else "  MISSED")
        print(f"  ratio {label:<40} {ratio:7.2f}x" + (f"  (goal <= {goal:g}x){verdict}" if goal else ""))


def inputs(n: int, dtype: type) -> dict[str, np.ndarray]:
    """Random per-DOF state and envelope arrays (every quadrant, both curves binding somewhere)."""
    rng = np.random.default_rng(0)
    return {
        "velocity": rng.normal(0.0, 6.0, n).astype(dtype),
        "effort": rng.normal(0.0, 15.0, n).astype(dtype),
        "applied": np.zeros(n, dtype=dtype),
        "response": rng.uniform(5.0, 50.0, n).astype(dtype),
        "max_effort": rng.uniform(5.0, 20.0, n).astype(dtype),
        "max_actuator_velocity": rng.uniform(5.0, 15.0, n).astype(dtype),
        "velocity_dependent_resistance": rng.uniform(0.0, 0.2, n).astype(dtype),
        "speed_effort_gradient": rng.uniform(0.2, 1.0, n).astype(dtype),
    }


def bench_numpy(n: int, repeats: int, baseline: str | None = None) -> None:
    """Core NumPy reference against np.clip of the same arrays (and a baseline implementation)."""
    print(f"\nNumPy reference, float64 (and float32), N = {n:,}")
    a = inputs(n, np.float64)
    env = de.PerformanceEnvelope(
        max_effort=12.0,
        max_actuator_velocity=10.0,
        velocity_dependent_resistance=0.1,
        speed_effort_gradient=0.5,
    )
    cap, effort, velocity, response = a["max_effort"], a["effort"], a["velocity"], a["response"]
    out = np.empty(n)
    impulse = [velocity, a["applied"] * DT, effort * DT, response, a["max_actuator_velocity"]]
    impulse += [cap * DT, a["speed_effort_gradient"] / DT, a["velocity_dependent_resistance"] * DT]
    impulse32 = [x.astype(np.float32) for x in impulse]
    clip, explicit, implicit, implicit_env = (
        "np.clip(effort, -cap, cap)",
        "clamp_effort (explicit)",
        "clamp_drive_impulse (implicit, per-DOF)",
        "clamp_effort_implicit (one envelope)",
    )
    exact, implicit32, exact32 = (
        "clamp_drive_impulse, physx_exact=True",
        "clamp_drive_impulse, float32",
        "clamp_drive_impulse, float32, physx_exact",
    )
    fns = {
        clip: lambda: np.clip(effort, -cap, cap, out=out),
        explicit: lambda: de.clamp_effort(env, effort, velocity),
        implicit: lambda: de.clamp_drive_impulse(*impulse),
        implicit_env: lambda: de.clamp_effort_implicit(env, effort, velocity, response, DT),
        exact: lambda: de.clamp_drive_impulse(*impulse, physx_exact=True),
        implicit32: lambda: de.clamp_drive_impulse(*impulse32, dtype=np.float32),
        exact32: lambda: de.clamp_drive_impulse(*impulse32, dtype=np.float32, physx_exact=True),
    }
    ratios: list[tuple[str, str, str, float | None]] = [
        ("explicit / np.clip", explicit, clip, 15),
        ("implicit / np.clip", implicit, clip, 10),
        ("implicit (effort API) / np.clip", implicit_env, clip, 10),
        ("implicit, physx_exact / np.clip", exact, clip, None),
        ("implicit, float32 / np.clip", implicit32, clip, None),
        ("implicit, float32, physx_exact / np.clip", exact32, clip, None),
    ]
    if baseline is not None:
        base = importlib.import_module(baseline)
        fns["baseline clamp_effort"] = lambda: base.clamp_effort(env, effort, velocity)
        fns["baseline clamp_drive_impulse"] = lambda: base.clamp_drive_impulse(*impulse)
        fns["baseline clamp_effort_implicit"] = lambda: base.clamp_effort_implicit(
            env, effort, velocity, response, DT
        )
        fns["baseline clamp_drive_impulse, float32"] = lambda: base.clamp_drive_impulse(
            *impulse32, dtype=np.float32
        )
        ratios += [
            ("explicit / baseline", explicit, "baseline clamp_effort", None),
            ("implicit / baseline", implicit, "baseline clamp_drive_impulse", None),
            ("implicit, physx_exact / baseline", exact, "baseline clamp_drive_impulse", None),
            ("implicit (effort API) / baseline", implicit_env, "baseline clamp_effort_implicit", None),
            ("implicit, float32 / baseline", implicit32, "baseline clamp_drive_impulse, float32", None),
            ("float32, physx_exact / baseline", exact32, "baseline clamp_drive_impulse, float32", None),
        ]
    report(median_times(fns, repeats), ratios)


def bench_warp(n: int, repeats: int, device: str) -> None:
    """Warp kernels against Newton's ClampingDCMotor kernel and a copy kernel, same arrays."""
    import warp as wp

    import drive_envelope.warp as dw
    from drive_envelope._src.kernels import warp_ops

    print(f"\nWarp, float32, device {device}, N = {n:,}")
    a = {k: wp.array(v, dtype=wp.float32, device=device) for k, v in inputs(n, np.float32).items()}
    params = dw.EnvelopeArrays(**{k: a[k] for k in de.PerformanceEnvelope.__slots__[:4]})
    out = wp.empty(n, dtype=wp.float32, device=device)
    # the implicit kernel reads 9 arrays and writes 1: a copy of 5N floats moves the same bytes
    big_src = wp.zeros(5 * n, dtype=wp.float32, device=device)
    big_dst = wp.empty(5 * n, dtype=wp.float32, device=device)
    small_dst = wp.empty(n, dtype=wp.float32, device=device)
    sync = wp.synchronize_device if device != "cpu" else (lambda: None)
    copy_n, copy_5n, explicit, implicit, newton_dc = (
        "copy kernel, N floats",
        "copy kernel, 5N floats (same bytes as implicit)",
        "clamp_effort (explicit)",
        "clamp_effort_implicit",
        "Newton ClampingDCMotor.modify_forces",
    )
    fns: dict[str, Callable[[], Any]] = {
        copy_n: lambda: warp_ops.copy(a["effort"], small_dst),
        copy_5n: lambda: warp_ops.copy(big_src, big_dst),
        explicit: lambda: dw.clamp_effort(params, a["effort"], a["velocity"], out=out),
        implicit: lambda: dw.clamp_effort_implicit(
            params, a["effort"], a["velocity"], a["response"], DT, a["applied"], out=out
        ),
    }
    ratios: list[tuple[str, str, str, float | None]] = [
        ("implicit / copy (same bytes)", implicit, copy_5n, 3 if device != "cpu" else None),
        ("explicit / copy N", explicit, copy_n, None),
    ]
    if importlib.util.find_spec("newton") is not None:
        from newton.actuators import ClampingDCMotor

        dc = ClampingDCMotor(
            saturation_effort=a["max_effort"],
            velocity_limit=a["max_actuator_velocity"],
            max_motor_effort=a["max_effort"],
        )
        indices = wp.array(np.arange(n, dtype=np.uint32), dtype=wp.uint32, device=device)

        def modify() -> None:
            dc.modify_forces(a["effort"], out, a["effort"], a["velocity"], indices, indices, device=device)

        fns[newton_dc] = modify
        ratios = [
            ("implicit / Newton DC motor", implicit, newton_dc, 1.5 if device == "cpu" else None),
            ("explicit / Newton DC motor", explicit, newton_dc, None),
            ("Newton DC motor / copy N", newton_dc, copy_n, None),
            *ratios,
        ]
    report(median_times(fns, repeats, sync), ratios)


def bench_torch(n: int, repeats: int, device: str) -> None:
    """torch ops against an Isaac Lab style DC-motor clip on the same tensors."""
    import torch

    import drive_envelope.torch as dt

    print(f"\nPyTorch, float32, device {device}, N = {n:,}, {torch.get_num_threads()} threads")
    a = {k: torch.from_numpy(v).to(device) for k, v in inputs(n, np.float32).items()}
    cap, v_lim, vel, effort = a["max_effort"], a["max_actuator_velocity"], a["velocity"], a["effort"]
    zeros = torch.zeros_like(cap)
    sync = torch.cuda.synchronize if device != "cpu" else (lambda: None)

    def dc_motor_clip() -> Any:
        # Isaac Lab DCMotor._clip_effort: torque-speed line from the saturation effort, then the cap
        max_effort = torch.clip(cap * (1.0 - vel / v_lim), min=zeros, max=cap)
        min_effort = torch.clip(cap * (-1.0 - vel / v_lim), min=-cap, max=zeros)
        return torch.clip(effort, min=min_effort, max=max_effort)

    params = dt.EnvelopeTensors(**{k: a[k] for k in de.PerformanceEnvelope.__slots__[:4]})
    impulse = [vel, a["applied"] * DT, effort * DT, a["response"], v_lim, cap * DT]
    impulse += [a["speed_effort_gradient"] / DT, a["velocity_dependent_resistance"] * DT]
    dc, explicit, eager, fused = (
        "Isaac Lab style DC-motor clip",
        "clamp_effort (explicit)",
        "clamp_drive_impulse (implicit, eager)",
        "fused_clamp_drive_impulse (implicit)",
    )
    fns = {
        dc: dc_motor_clip,
        explicit: lambda: dt.clamp_effort(params, effort, vel),
        eager: lambda: dt.clamp_drive_impulse(*impulse),
        fused: lambda: dt.fused_clamp_drive_impulse(*impulse),
    }
    with torch.inference_mode():
        start = time.perf_counter()
        dt.fused_clamp_drive_impulse(*impulse)
        sync()
        print(f"  (first fused call, torch.compile included: {time.perf_counter() - start:.1f} s)")
        rows = median_times(fns, repeats, sync)
    report(
        rows,
        [
            ("explicit / DC-motor clip", explicit, dc, 1),
            ("implicit fused / DC-motor clip", fused, dc, 2),
            ("implicit eager / DC-motor clip", eager, dc, None),
        ],
    )


def main() -> None:
    parser = argparse.ArgumentParser(
        description="Envelope clamp kernels against their peers (medians, ratios)."
    )
    parser.add_argument("--n", type=int, default=1_000_000, help="number of DOFs (default 1,000,000)")
    parser.add_argument("--repeats", type=int, default=21, help="timed runs per row (default 21)")
    parser.add_argument(
        "--baseline",
        default=None,
        help="module with clamp_effort/clamp_drive_impulse/clamp_effort_implicit to compare",
    )
    parser.add_argument("--numpy-only", action="store_true", help="run the NumPy section only")
    args = parser.parse_args()
    print(f"machine: {machine()}")
    bench_numpy(args.n, args.repeats, args.baseline)
    if args.numpy_only:
        return
    if importlib.util.find_spec("warp") is not None:
        import warp as wp

        wp.config.quiet = True
        wp.init()
        for device in ["cpu"] + (["cuda:0"] if wp.is_cuda_available() else []):
            bench_warp(args.n, args.repeats, device)
    else:
        print("\nWarp: not installed, skipped")
    if importlib.util.find_spec("torch") is not None:
        import torch

        for device in ["cpu"] + (["cuda"] if torch.cuda.is_available() else []):
            bench_torch(args.n, args.repeats, device)
    else:
        print("\nPyTorch: not installed, skipped (see docs/kernels.md: torch is opt-in)")


if __name__ == "__main__":
    main()

"""Benchmark: would one array-API implicit clamp serve NumPy and PyTorch both? (issue 29)

The NumPy core (``envelope/clamp.py``) and the torch port (``kernels/torch_ops.py``) run the same
sign-normalized algorithm of PhysX's ``clampDriveImpulse``, written twice: NumPy's with
data-dependent shortcuts (reductions that skip patches no element needs), bit-pattern selects and
cache-sized blocks; torch's branch-free (every patch a ``where``), so that it never syncs with a
GPU and ``torch.compile`` fuses it whole. This benchmark times a single array-API version, the
torch port's default mode written against a namespace ``xp`` (NumPy 2's main namespace or
``torch``), beside both, on the same arrays (N = 1e6, float64 and float32), and checks that it
gives the same numbers. Thread CPU time, interleaved rounds (order reversed every other round),
medians. Usage::

    python benchmarks/bench_array_api_clamp.py [--n 1000000] [--repeats 11]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import drive_envelope as de

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_kernels import median_times

DT = 0.005
"""Time step [s]."""
EPS = 2.0**-23
"""PhysX's absolute epsilon of a near-zero denominator."""


def _split(xp: Any, bound: Any, num: Any, a: Any, b: Any, denom: Any) -> Any:
    """``(a + b)/denom`` as ``a/denom + b/denom`` where ``a + b`` overflowed (every backend's rule)."""
    over = xp.isinf(num) & xp.isfinite(a) & xp.isfinite(b)
    return xp.where(over, a / denom + b / denom, bound)


def _bounds(xp: Any, dev: Any, limit: Any, denom1: Any, denom2: Any) -> tuple[Any, Any]:
    """``computeBoundsForPositiveImpulse``, default mode, branch-free (the torch port's ``_bounds``)."""
    num1, num2 = dev - limit, dev + limit
    bound1 = _split(xp, num1 / denom1, num1, dev, -limit, denom1)
    bound2 = _split(xp, num2 / denom2, num2, dev, limit, denom2)
    rising = denom1 >= 0.0
    near = xp.abs(num1) < EPS
    lower = xp.where(rising, bound1, 0.0)
    upper = xp.where(rising, bound2, xp.minimum(bound1, bound2))
    flat_lower = xp.where(near | (num1 <= 0.0), 0.0, math.nan)
    flat = xp.abs(denom1) < EPS
    lower, upper = xp.where(flat, flat_lower, lower), xp.where(flat, bound2, upper)
    ignored = xp.abs(denom2) < EPS
    return xp.where(ignored, -math.inf, lower), xp.where(ignored, math.inf, upper)


def xp_clamp(
    xp: Any, v0: Any, x0: Any, x: Any, r: Any, max_v: Any, max_x: Any, grad: Any, resist: Any
) -> Any:
    """The implicit clamp's default mode on any array-API namespace (NumPy 2, torch)."""
    sign = xp.copysign(xp.ones_like(x), x)
    request, dev = xp.abs(x), (x0 * r - v0) * sign
    lo1, hi1 = _bounds(xp, dev, max_v, r - grad, r + grad)
    inv_r, limit_r = 1.0 / resist, max_x / resist
    plain = ~(xp.isfinite(inv_r) & xp.isfinite(limit_r))
    lo2, hi2 = _bounds(xp, dev, limit_r, r - inv_r, r + inv_r)
    lo2, hi2 = xp.where(plain, -math.inf, lo2), xp.where(plain, math.inf, hi2)
    lower = xp.maximum(xp.maximum(lo1, lo2), xp.clip(-max_x, 0.0, None))
    upper = xp.minimum(xp.minimum(xp.minimum(hi1, hi2), max_x), request)
    return xp.where(lower <= upper, upper * sign, 0.0)


def _arrays(n: int, dtype: Any) -> list[np.ndarray]:
    """The impulse-level arguments of ``bench_kernels.py`` (every quadrant, both curves binding)."""
    rng = np.random.default_rng(0)
    velocity, effort = rng.normal(0.0, 6.0, n), rng.normal(0.0, 15.0, n)
    response, cap = rng.uniform(5.0, 50.0, n), rng.uniform(5.0, 20.0, n)
    vmax, resist, grad = rng.uniform(5.0, 15.0, n), rng.uniform(0.0, 0.2, n), rng.uniform(0.2, 1.0, n)
    args = [velocity, np.zeros(n), effort * DT, response, vmax, cap * DT, grad / DT, resist * DT]
    return [a.astype(dtype) for a in args]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=11)
    args = parser.parse_args()
    import torch

    from drive_envelope.torch import clamp_drive_impulse as torch_clamp

    torch.set_num_threads(1)  # thread CPU time counts one thread
    for dtype, kind in ((np.float64, torch.float64), (np.float32, torch.float32)):
        arrays = _arrays(args.n, dtype)
        tensors = [torch.from_numpy(a) for a in arrays]
        ours = de.clamp_drive_impulse(*arrays, dtype=dtype)
        ported = xp_clamp(np, *arrays)
        mismatch = int(np.count_nonzero(ours != ported))
        fns = {
            "NumPy core": lambda a=arrays, d=dtype: de.clamp_drive_impulse(*a, dtype=d),
            "array API on NumPy": lambda a=arrays: xp_clamp(np, *a),
            "torch port (eager)": lambda t=tensors, k=kind: torch_clamp(*t, dtype=k),
            "array API on torch": lambda t=tensors: xp_clamp(torch, *t),
        }
        medians = dict(median_times(fns, args.repeats, clock=time.thread_time))
        print(f"\n{np.dtype(dtype).name}, N = {args.n:,}, thread CPU time, median of {args.repeats}:")
        for name, seconds in medians.items():
            print(f"  {name:<22} {seconds * 1e3:8.2f} ms")
        for label, num, den in (
            ("NumPy core", "array API on NumPy", "NumPy core"),
            ("torch port", "array API on torch", "torch port (eager)"),
        ):
            print(f"  array API / {label:<11} {medians[num] / medians[den]:5.2f}x")
        print(f"  elements where the array-API port differs from the NumPy core: {mismatch}")


if __name__ == "__main__":
    main()

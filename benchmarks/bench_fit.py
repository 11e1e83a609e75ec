"""Benchmark: how often `fit` recovers random envelopes from the frontier, and how long it takes.

Recovery sweep (``--trials`` random envelopes per case, knee anywhere between 5 % and 95 % of the
speed limit, eq. 1 flatter than eq. 2): saturated samples on both lines plus interior samples (at
most 90 % of the boundary's radius along random rays), with Gaussian noise on the saturated ones
(a share of each cap, both axes). Per case it prints the median and worst parameter error (caps
relative to themselves, slopes by the effort or speed they change over the caps), how many trials
miss 5 %, and the worst region error (the largest relative difference of the boundaries' radii
along rays from the origin, the rays spread evenly in units of the caps: a faint knee read as one
line misses R but hardly the region);
the "one line" cases sweep eq. 1 only and count invented speed limits, the "speed line" cases a
single line to zero effort (a DC motor) and count fits that do not read it as eq. 2.

Timing: one fit (no bootstrap, then 50 resamples) of 1e3 to 1e5 samples, a quarter saturated.

Usage::

    python benchmarks/bench_fit.py [--trials 40] [--sizes 1000,10000,100000]
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np

from drive_envelope import PerformanceEnvelope
from drive_envelope.analysis import FitOptions, fit_samples

FIELDS = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")
Samples = tuple[np.ndarray, np.ndarray]


def _envelope(rng: np.random.Generator) -> PerformanceEnvelope:
    corner = rng.uniform(0.05, 0.95)
    drop = rng.uniform(0.0, min(0.4, 0.8 * corner))  # eq. 1 loses `drop` of max_effort by the corner
    effort, speed = rng.uniform(1.0, 100.0), rng.uniform(1.0, 100.0)
    return PerformanceEnvelope(
        max_effort=effort,
        max_actuator_velocity=speed,
        velocity_dependent_resistance=effort * drop / (corner * speed),
        speed_effort_gradient=(speed - corner * speed) / (effort * (1.0 - drop)),
    )


def _knee(env: PerformanceEnvelope) -> float:
    e, r = env.max_effort, env.velocity_dependent_resistance
    v, g = env.max_actuator_velocity, env.speed_effort_gradient
    return (v - g * e) / (1.0 - g * r)


def _interior(env: PerformanceEnvelope, n: int, rng: np.random.Generator) -> Samples:
    theta = rng.uniform(0.0, math.pi / 2.0, n)
    ux, uy = np.cos(theta), np.sin(theta)
    e, r = env.max_effort, env.velocity_dependent_resistance
    v, g = env.max_actuator_velocity, env.speed_effort_gradient
    radius = rng.uniform(0.0, 0.9, n) / np.maximum((uy + r * ux) / e, (ux + g * uy) / v)
    return radius * ux, radius * uy


def _noisy(
    env: PerformanceEnvelope, v: np.ndarray, t: np.ndarray, noise: float, rng: np.random.Generator
) -> Samples:
    return (
        v + rng.normal(0.0, noise * env.no_load_velocity(), v.size),
        t + rng.normal(0.0, noise * env.max_effort, t.size),
    )


def _both_lines(env: PerformanceEnvelope, noise: float, rng: np.random.Generator) -> Samples:
    corner = _knee(env)
    v1 = rng.uniform(0.0, corner, 150)
    t2 = rng.uniform(0.0, float(env.effort_limit(corner)), 150)
    v, t = _noisy(env, np.r_[v1, env.velocity_at_effort(t2)], np.r_[env.effort_limit(v1), t2], noise, rng)
    vi, ti = _interior(env, 600, rng)
    return np.r_[v, vi], np.r_[t, ti]


def _error(env: PerformanceEnvelope, truth: PerformanceEnvelope) -> float:
    e, v = truth.max_effort, truth.max_actuator_velocity
    scale = {"max_effort": e, "max_actuator_velocity": v}
    scale |= {"velocity_dependent_resistance": e / v, "speed_effort_gradient": v / e}
    return max(abs(getattr(env, f) - getattr(truth, f)) / scale[f] for f in FIELDS)


def _radius(env: PerformanceEnvelope, ux: np.ndarray, uy: np.ndarray) -> np.ndarray:
    """The boundary's distance from the origin along unit rays (ux, uy) in (|v|, |tau|)."""
    e, r = env.max_effort, env.velocity_dependent_resistance
    v, g = env.max_actuator_velocity, env.speed_effort_gradient
    return 1.0 / np.maximum((uy + r * ux) / e, (ux + g * uy) / v)


def _region_error(env: PerformanceEnvelope, truth: PerformanceEnvelope) -> float:
    """Largest relative difference of the boundaries' radii along rays from the origin."""
    theta = np.linspace(0.0, math.pi / 2.0, 721)
    ux, uy = np.cos(theta) / truth.max_actuator_velocity, np.sin(theta) / truth.max_effort  # rays in caps
    return float(np.max(np.abs(_radius(env, ux, uy) / _radius(truth, ux, uy) - 1.0)))


def _recovery(trials: int, noise: float, q: float, seed: int) -> str:
    rng = np.random.default_rng(seed)
    errors, regions = [], []
    for _ in range(trials):
        truth = _envelope(rng)
        v, t = _both_lines(truth, noise, rng)
        env = fit_samples(v, t, FitOptions(outlier_quantile=q, bootstrap=0)).envelope
        errors.append(_error(env, truth))
        regions.append(_region_error(env, truth))
    missed = sum(e > 0.05 for e in errors)
    return (
        f"parameters: median {np.median(errors):.2e}, worst {max(errors):.2e}, "
        f"missing 5 %: {missed}/{trials}; "
        f"region: worst {max(regions):.2e}"
    )


def _one_line(trials: int, noise: float, q: float, seed: int) -> str:
    rng = np.random.default_rng(seed)
    invented = 0
    for _ in range(trials):
        truth = _envelope(rng)
        top = rng.uniform(0.3, 0.95) * _knee(truth)  # the sweep stops below the knee
        v = rng.uniform(0.0, top, 200)
        v, t = _noisy(truth, v, truth.effort_limit(v), noise, rng)
        vi = rng.uniform(0.0, 0.85 * top, 300)
        ti = truth.effort_limit(vi) * rng.uniform(0.0, 0.9, vi.size)
        result = fit_samples(np.r_[v, vi], np.r_[t, ti], FitOptions(outlier_quantile=q, bootstrap=0))
        invented += math.isfinite(result.envelope.max_actuator_velocity)
    return f"invented a speed limit: {invented}/{trials}"


def _speed_line(trials: int, noise: float, q: float, seed: int) -> str:
    rng = np.random.default_rng(seed)
    missed = 0
    for _ in range(trials):
        limit, gradient = rng.uniform(1.0, 100.0), rng.uniform(0.01, 10.0)
        truth = PerformanceEnvelope(
            max_effort=limit / gradient, max_actuator_velocity=limit, speed_effort_gradient=gradient
        )
        t = rng.uniform(0.0, limit / gradient, 200)
        v, t = _noisy(truth, truth.velocity_at_effort(t), t, noise, rng)
        vi, ti = _interior(truth, 300, rng)
        env = fit_samples(np.r_[v, vi], np.r_[t, ti], FitOptions(outlier_quantile=q, bootstrap=0)).envelope
        read_as_eq2 = math.isfinite(env.max_actuator_velocity) and env.velocity_dependent_resistance == 0.0
        missed += not (read_as_eq2 and _error(env, truth) <= 0.05)
        # a speed line alone: max_effort is its stall effort, eq. 1 never binds below it
    return f"not eq. 2 within 5 %: {missed}/{trials}"


def _timing(sizes: list[int]) -> None:
    truth = PerformanceEnvelope(
        max_effort=40.0,
        max_actuator_velocity=30.0,
        velocity_dependent_resistance=0.4,
        speed_effort_gradient=0.25,
    )
    print("\ntiming (a quarter of the samples saturated, the rest interior)")
    for n in sizes:
        rng = np.random.default_rng(0)
        v = rng.uniform(0.0, truth.no_load_velocity(), n // 4)
        vi, ti = _interior(truth, n - n // 4, rng)
        for noise, q in ((0.0, 0.0), (0.005, 0.5)):
            vs, ts = _noisy(truth, v, truth.effort_limit(v), noise, rng)
            vs, ts = np.r_[vs, vi], np.r_[ts, ti]
            times = []
            for bootstrap in (0, 50):
                start = time.perf_counter()
                fit_samples(vs, ts, FitOptions(outlier_quantile=q, bootstrap=bootstrap))
                times.append(time.perf_counter() - start)
            print(
                f"  {n:>7} samples, noise {noise:.1%}, quantile {q:g}: "
                f"{times[0]:.3f} s, with 50 bootstrap resamples {times[1]:.3f} s"
            )


def main() -> None:
    """Run the recovery sweep and the timing."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--sizes", default="1000,10000,100000")
    args = parser.parse_args()
    cases: list[tuple[str, Callable[[int, float, float, int], str], float, float]] = [
        ("both lines, clean, quantile 0", _recovery, 0.0, 0.0),
        ("both lines, 0.5 % noise, quantile 0.5", _recovery, 0.005, 0.5),
        ("both lines, 1 % noise, quantile 0.5", _recovery, 0.01, 0.5),
        ("both lines, 2 % noise, quantile 0.5", _recovery, 0.02, 0.5),
        ("both lines, 0.5 % noise, quantile 0 (containing)", _recovery, 0.005, 0.0),
        ("one line, clean, quantile 0", _one_line, 0.0, 0.0),
        ("one line, 1 % noise, quantile 0.5", _one_line, 0.01, 0.5),
        ("one line, 2 % noise, quantile 0.5", _one_line, 0.02, 0.5),
        ("speed line, clean, quantile 0", _speed_line, 0.0, 0.0),
        ("speed line, 1 % noise, quantile 0.5", _speed_line, 0.01, 0.5),
    ]
    print(f"recovery over {args.trials} random envelopes per case (interior samples: 2 per saturated one)")
    for index, (label, run, noise, q) in enumerate(cases):
        start = time.perf_counter()
        summary = run(args.trials, noise, q, index)
        print(f"  {label:50s} {summary}  ({time.perf_counter() - start:.1f} s)")
    _timing([int(size) for size in args.sizes.split(",")])


if __name__ == "__main__":
    main()

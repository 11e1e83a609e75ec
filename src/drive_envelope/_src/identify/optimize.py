"""The search: SciPy's differential evolution over batched replays, then a least-squares polish.

0. **Restarts**: ``restarts`` independent searches (steps 1 and 2), each from its own seed drawn
   from ``seed`` (:class:`numpy.random.SeedSequence`); the lowest training cost wins. The values
   the restarts end at give each parameter's seed spread: a direction the logs do not pin (two
   lines that trade against each other) shows there as a wide range however small its
   Gauss-Newton std.
1. **Global**: :func:`scipy.optimize.differential_evolution` on the unit cube of the fitted
   parameters, ``vectorized=True``: every generation is one :meth:`Replay.errors` call that replays
   the whole population on every training log at once. The cost is the mean over logs of each
   log's mean absolute position error (plus ``velocity_weight`` times the velocity error).
2. **Local**: :func:`scipy.optimize.least_squares` (trust-region reflective, inside the bounds) on
   the per-sample position errors (each log weighted by 1/rows, ``soft_l1`` loss so it follows the
   absolute error), with a finite-difference Jacobian computed in one batched replay of ``n + 1``
   candidates. The polished point is kept only when its cost is lower.
3. **Uncertainty**: the standard deviation of each fitted parameter from the Gauss-Newton covariance
   ``s^2 (J^T J)^-1`` at the result (``s^2`` the residual variance). Samples of a trajectory are
   correlated in time, so these are lower bounds: compare held-out errors, not only the std.

Everything is seeded (``seed``): the same inputs give the same result.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.parameters import ParameterSpace
from drive_envelope._src.identify.replay import Replay

FloatArray = npt.NDArray[np.float64]
_JACOBIAN_STEP = 1e-3  # finite-difference step in the unit cube


@dataclass(frozen=True, kw_only=True, slots=True)
class SearchOptions:
    """Settings of the search."""

    generations: int = 60
    """Most differential-evolution generations (each one batched replay of the population)."""
    population: int = 10
    """Population per fitted parameter (SciPy's ``popsize``): ``population * n`` candidates."""
    polish_evaluations: int = 30
    """Most least-squares iterations of the polish (0: no polish)."""
    velocity_weight: float = 0.0
    """Weight of the mean absolute velocity error in the cost [s]: 0 fits position only."""
    seed: int = 0
    """Random seed of the search."""
    restarts: int = 3
    """Independent searches (global and polish), each seeded from ``seed``; the best is kept."""

    def __post_init__(self) -> None:
        for name in ("generations", "population", "polish_evaluations", "seed", "restarts"):
            value = getattr(self, name)
            low = 1 if name in ("population", "restarts") else 0
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise InputError(f"{name} must be an integer >= {low}, got {value!r}")
        weight = self.velocity_weight
        if not (np.isfinite(weight) and weight >= 0.0):
            raise InputError(f"velocity_weight must be a finite number >= 0 [s], got {weight!r}")


@dataclass(frozen=True, kw_only=True, slots=True)
class SearchProgress:
    """Where a running search is, for a progress display."""

    phase: str
    """``"global"`` (differential evolution) or ``"polish"`` (least squares)."""
    restart: int
    """The current restart, from 1."""
    restarts: int
    """Restarts in all."""
    generation: int
    """Generations (global) or polish iterations done in this restart."""
    generations: int
    """Most generations (global) or polish iterations of this phase."""
    best_cost: float
    """Lowest training cost seen so far, all restarts [rad or m]."""
    done: int
    """Steps done in the whole search (generations and polish iterations)."""
    total: int
    """Most steps of the whole search."""


@dataclass(frozen=True, kw_only=True, slots=True)
class SearchResult:
    """The best point found and how it was found."""

    unit: FloatArray
    """The point in the unit cube, shape ``(n,)``."""
    values: dict[str, float]
    """Every parameter's value there [SI]."""
    std: dict[str, float]
    """Standard deviation of each fitted parameter [SI] (NaN where the covariance is singular)."""
    cost: float
    """Training cost there [rad or m]."""
    generations: int
    """Differential-evolution generations run."""
    replays: int
    """Candidate replays run (population members and Jacobian columns)."""
    polished: bool
    """Whether the least-squares polish improved the point."""
    wall_time_s: float
    """Time spent [s]."""
    restart_costs: tuple[float, ...] = ()
    """The training cost each restart ended at [rad or m]."""
    spread: dict[str, tuple[float, float]] | None = None
    """Fitted parameter -> (lowest, highest) value the restarts ended at [SI]."""


def search(
    replay: Replay,
    space: ParameterSpace,
    options: SearchOptions,
    *,
    progress: Callable[[SearchProgress], None] | None = None,
) -> SearchResult:
    """Find the parameters that make the replay match the training logs best.

    Args:
        replay: The packed training logs.
        space: The fitted parameters and their intervals.
        options: Search settings.
        progress: Called with a :class:`SearchProgress` after each generation and polish iteration.

    Raises:
        InputError: SciPy is missing (the ``identify`` extra).
    """
    try:
        from scipy.optimize import differential_evolution
    except ImportError:
        raise InputError("identify needs SciPy: pip install 'drive-envelope[identify]'") from None
    start = time.perf_counter()
    counter = {"replays": 0, "generations": 0, "done": 0}
    state = _State()
    per_restart = options.generations + options.polish_evaluations
    total = options.restarts * per_restart

    def cost(unit: FloatArray) -> FloatArray:
        counter["replays"] += unit.shape[1]
        errors = replay.errors(space.to_values(unit))
        costs = errors.position.mean(axis=1)
        if options.velocity_weight and errors.velocity is not None:
            costs = costs + options.velocity_weight * errors.velocity.mean(axis=1)
        state.best = min(state.best, float(np.min(costs)))
        return np.asarray(costs)

    def tick(phase: str) -> None:
        counter["done"] += 1
        state.step = state.step + 1 if state.phase == phase else 1
        state.phase = phase
        if progress is not None:
            progress(
                SearchProgress(
                    phase=phase,
                    restart=state.restart,
                    restarts=options.restarts,
                    generation=state.step,
                    generations=options.generations if phase == "global" else options.polish_evaluations,
                    best_cost=state.best,
                    done=counter["done"],
                    total=total,
                )
            )

    def generation(*_: object) -> None:
        counter["generations"] += 1
        tick("global")

    seeds = np.random.SeedSequence(options.seed).spawn(options.restarts)
    ends: list[tuple[float, FloatArray, bool]] = []
    for index, seed in enumerate(seeds):
        state.restart, state.phase, state.step = index + 1, "", 0
        counter["done"] = index * per_restart
        best = space.to_unit(space.start)
        if options.generations > 0:
            found = differential_evolution(
                cost,
                [(0.0, 1.0)] * space.size,
                vectorized=True,
                updating="deferred",
                popsize=options.population,
                maxiter=options.generations,
                tol=1e-4,
                polish=False,
                init="sobol",
                x0=best,
                rng=np.random.default_rng(seed),
                callback=generation,
            )
            best = np.asarray(found.x, dtype=np.float64)
        best_cost = float(cost(best[:, None])[0])
        polished = False
        counter["done"] = index * per_restart + options.generations
        if options.polish_evaluations > 0:
            candidate = _polish(replay, space, best, options, counter, lambda: tick("polish"))
            candidate_cost = float(cost(candidate[:, None])[0])
            if candidate_cost < best_cost:
                best, best_cost, polished = candidate, candidate_cost, True
        ends.append((best_cost, best, polished))
    best_cost, best, polished = min(ends, key=lambda end: end[0])
    values = {name: float(array[0]) for name, array in space.to_values(best[:, None]).items()}
    std = _std(replay, space, best, counter)
    ended = [space.to_values(end[1][:, None]) for end in ends]
    spread = {
        name: (min(float(v[name][0]) for v in ended), max(float(v[name][0]) for v in ended))
        for name in space.names
    }
    return SearchResult(
        unit=best,
        values=values,
        std=std,
        cost=best_cost,
        generations=counter["generations"],
        replays=counter["replays"],
        polished=polished,
        wall_time_s=time.perf_counter() - start,
        restart_costs=tuple(end[0] for end in ends),
        spread=spread,
    )


@dataclass(slots=True)
class _State:
    """Where the search is (for progress reports)."""

    best: float = np.inf
    restart: int = 1
    phase: str = ""
    step: int = 0


def _jacobian(
    replay: Replay, space: ParameterSpace, unit: FloatArray, counter: dict[str, int]
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Residuals at ``unit`` and their Jacobian (per unit-cube coordinate), in one batched replay."""
    steps = np.where(unit + _JACOBIAN_STEP <= 1.0, _JACOBIAN_STEP, -_JACOBIAN_STEP)
    points = np.repeat(unit[:, None], space.size + 1, axis=1)
    points[np.arange(space.size), np.arange(1, space.size + 1)] += steps
    counter["replays"] += points.shape[1]
    residuals = replay.errors(space.to_values(points), residuals=True).residuals
    assert residuals is not None
    base = residuals[0]
    jacobian = (residuals[1:] - base).T / steps
    return base, jacobian, steps


def _polish(
    replay: Replay,
    space: ParameterSpace,
    unit: FloatArray,
    options: SearchOptions,
    counter: dict[str, int],
    tick: Callable[[], None],
) -> FloatArray:
    from scipy.optimize import least_squares

    cache: dict[bytes, tuple[FloatArray, FloatArray]] = {}

    def evaluate(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        key = np.asarray(x, dtype=np.float64).tobytes()
        if key not in cache:
            base, jacobian, _ = _jacobian(replay, space, np.asarray(x, dtype=np.float64), counter)
            tick()
            cache.clear()
            cache[key] = (base, jacobian)
        return cache[key]

    found = least_squares(
        lambda x: evaluate(x)[0],
        unit,
        jac=lambda x: evaluate(x)[1],
        bounds=(np.zeros(space.size), np.ones(space.size)),
        method="trf",
        loss="soft_l1",
        f_scale=max(float(np.abs(evaluate(unit)[0]).mean()), 1e-9),
        max_nfev=options.polish_evaluations,
        x_scale=np.ones(space.size),
    )
    return np.clip(np.asarray(found.x, dtype=np.float64), 0.0, 1.0)


def _std(
    replay: Replay, space: ParameterSpace, unit: FloatArray, counter: dict[str, int]
) -> dict[str, float]:
    """Gauss-Newton standard deviations of the fitted parameters at ``unit`` [SI].

    A parameter the logs do not move (a zero Jacobian column: an envelope line that never binds,
    say) gets ``inf``: not identified by these logs. The others come from the covariance of the rest.
    """
    base, jacobian, _ = _jacobian(replay, space, unit, counter)
    # d(value)/d(unit) of each coordinate: the cube's scale (log-scale ones at the value)
    values = np.array([space.to_values(unit[:, None])[name][0] for name in space.names])
    with np.errstate(divide="ignore", invalid="ignore"):
        log_span = values * (np.log(space.high) - np.log(space.low))
    scale = np.where(np.asarray(space.log_scale), log_span, space.high - space.low)
    physical = jacobian / scale
    norms = np.linalg.norm(physical, axis=0)
    seen = norms > 1e-9 * max(float(norms.max(initial=0.0)), 1e-300)
    deviations = np.full(space.size, np.inf)
    samples = int(replay.mask.sum())
    # residuals carry 1/sqrt(rows): sum(r^2) is the sum of the logs' mean square errors, and
    # s^2 (Je^T Je)^-1 for the plain errors Je = J*sqrt(rows) is sum(r^2)/dof * (J^T J)^-1
    variance = float(np.sum(base**2)) / max(samples - space.size, 1)
    if seen.any():
        kept = physical[:, seen]
        try:
            covariance = np.linalg.inv(kept.T @ kept) * variance
        except np.linalg.LinAlgError:
            covariance = np.linalg.pinv(kept.T @ kept) * variance
        deviations[seen] = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    return {name: float(value) for name, value in zip(space.names, deviations, strict=True)}

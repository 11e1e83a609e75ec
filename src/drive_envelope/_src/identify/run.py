"""System identification from bench logs: the whole job behind ``drive-envelope identify``.

:func:`identify` reads the stand and the logs, searches the fitted parameters on the training logs
(:mod:`drive_envelope._src.identify.optimize`), replays the result on the training and validation
logs and, with ``engine`` ``"physx"`` or ``"mujoco"``, replays it in that engine as well, so a user
sees the error they will get there. The result holds every parameter (value, std, fixed), the
identified envelope and stand scenario, and per-log mean absolute errors.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.log_bag import BagOptions
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.canonical import canonical_envelope
from drive_envelope._src.identify.logs import BenchLog, read_bench_log, sidecar_candidates
from drive_envelope._src.identify.optimize import SearchOptions, SearchProgress, SearchResult, search
from drive_envelope._src.identify.parameters import (
    DEFAULT_FIT,
    ParameterSpace,
    build_space,
    parameter_units,
)
from drive_envelope._src.identify.replay import Replay
from drive_envelope._src.identify.stand import IdentifyStand, read_stand
from drive_envelope._src.scenario.loads import FrictionSpec
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import Scenario

FloatArray = npt.NDArray[np.float64]
ENGINES = ("reference", "physx", "mujoco")
"""Engines the identified model can be replayed in."""
_AT_BOUND = 1e-3  # a fitted value this close to a bound (share of the interval) is reported


@dataclass(frozen=True, kw_only=True, slots=True)
class Estimate:
    """One parameter of the result."""

    value: float
    """The value [SI]."""
    std: float | None
    """Standard deviation [SI]; None for a fixed parameter, inf when the logs do not identify it."""
    fixed: bool
    """True when the stand's value was kept (not in ``--fit``)."""
    derived: str = ""
    """How the value follows from others instead (stiffness with a servo duty gain), else ``""``."""
    spread: tuple[float, float] | None = None
    """Lowest and highest value the search's restarts ended at [SI]; None for a fixed parameter."""


@dataclass(frozen=True, kw_only=True, slots=True)
class LogError:
    """The identified model's replay of one log."""

    log: BenchLog
    """The log."""
    mae_position: float
    """Mean absolute position error over every row [rad or m]."""
    mae_velocity: float | None
    """Mean absolute velocity error [rad/s or m/s], None when the log has no velocity."""
    position: FloatArray
    """Simulated position per row [rad or m]."""
    velocity: FloatArray
    """Simulated velocity per row [rad/s or m/s]."""
    effort: FloatArray
    """Simulated step-average actuator effort per row [N*m or N]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class Identification:
    """The result of :func:`identify`."""

    parameters: dict[str, Estimate]
    """Every parameter, fitted or fixed (SI)."""
    envelope: PerformanceEnvelope
    """The identified envelope."""
    scenario: Scenario
    """The stand with the identified values (``dt`` and duration of the first training log)."""
    stand: IdentifyStand | None = None
    """The identified stand: the scenario plus the servo gain and bounds (what ``-o`` writes)."""
    train: tuple[LogError, ...]
    """Replays of the training logs (reference engine)."""
    validation: tuple[LogError, ...]
    """Replays of the validation logs (reference engine)."""
    search: SearchResult
    """How the optimum was found."""
    wall_time_s: float
    """Time the whole identification took [s]."""
    engine: str = "reference"
    """The engine replayed in besides the reference."""
    engine_train: dict[str, float] = field(default_factory=dict)
    """Log file name -> position MAE in ``engine`` (training logs) [rad or m]; empty for reference."""
    engine_validation: dict[str, float] = field(default_factory=dict)
    """The same for the validation logs."""
    notes: tuple[str, ...] = ()
    """Warnings for the user (a parameter that ended on a bound, ...)."""


def identify(
    train: Sequence[str | os.PathLike[str]],
    stand: str | os.PathLike[str],
    *,
    validate: Sequence[str | os.PathLike[str]] = (),
    fit: Sequence[str] = DEFAULT_FIT,
    options: SearchOptions | None = None,
    engine: str = "reference",
    progress: Callable[[SearchProgress], None] | None = None,
    bag: BagOptions | None = None,
    joint: str | None = None,
) -> Identification:
    """Estimate the stand's parameters from bench logs.

    Args:
        train: Training logs (CSV or Parquet, see :mod:`drive_envelope._src.identify.logs`).
        stand: The stand file (:mod:`drive_envelope._src.identify.stand`).
        validate: Held-out logs, replayed with the result only.
        fit: Parameters to estimate (:data:`~drive_envelope._src.identify.parameters.IDENTIFIABLE`).
        options: Search settings (defaults: :class:`SearchOptions`).
        engine: ``"reference"``, ``"physx"`` or ``"mujoco"``: replay the result there too.
        progress: Called with a :class:`SearchProgress` after each generation and polish step.
        bag: Topics of ROS 2 bag logs (:class:`~drive_envelope._src.analysis.log_bag.BagOptions`).
        joint: The joint of a bag log to identify (None: the bag's only joint).

    Raises:
        InputError: a bad log, stand, name or engine, or an engine that cannot represent the stand.
    """
    started = time.perf_counter()
    if engine not in ENGINES:
        raise InputError(f"--engine {engine!r}: expected one of {', '.join(ENGINES)}")
    if not train:
        raise InputError("identify: give at least one training log")
    setup = read_stand(stand, parameter_units())
    train_logs = [read_bench_log(path, bag=bag, joint=joint) for path in train]
    validation_logs = [read_bench_log(path, bag=bag, joint=joint) for path in validate]
    replay = Replay(setup, train_logs)
    if "stiffness" in fit and replay.uses_duty:
        raise InputError(
            "--fit stiffness: the stand's [servo] duty_per_rad (or the logs' kp_duty_per_rad) ties "
            "stiffness to max_effort; remove stiffness from --fit or the duty gain from the stand"
        )
    space = build_space(
        setup.scenario,
        list(fit),
        bounds=setup.bounds,
        speed_scale=replay.speed_scale,
        source=setup.source,
        duty_effort=setup.duty_effort,
    )
    found = search(replay, space, options or SearchOptions(), progress=progress)
    unit = "N*m" if setup.scenario.joint.type == "revolute" else "N"
    # the errors below are those of the canonical values: what -o writes replays to the same numbers
    values, canonical_notes = canonical_envelope(found.values, unit)
    train_errors = replay_errors(replay, values)
    validation_errors = replay_errors(Replay(setup, validation_logs), values) if validation_logs else ()
    scenario = _identified(setup, values, train_logs[0])
    engine_train, engine_validation = {}, {}
    if engine != "reference":
        engine_train = _engine_mae(engine, setup, values, train_logs)
        engine_validation = _engine_mae(engine, setup, values, validation_logs)
    leaders = dict(space.tied)  # a follower (Coulomb friction) is estimated with its leader
    spread = found.spread or {}
    parameters = {
        name: Estimate(
            value=value,
            std=found.std.get(leaders.get(name, name)),
            fixed=leaders.get(name, name) not in space.names,
            spread=spread.get(leaders.get(name, name)),
        )
        for name, value in values.items()
    }
    for name in _moved(found.values, values):
        parameters[name] = dataclasses.replace(parameters[name], std=math.inf)  # the line does not bind
    if replay.uses_duty:  # stiffness is duty_per_rad * duty_effort, per log: no single value
        parameters["stiffness"] = Estimate(
            value=math.nan, std=None, fixed=True, derived="duty_per_rad * duty_effort, per log"
        )
    else:
        del parameters["duty_effort"]  # no servo gain: the drive's own stiffness
    return Identification(
        parameters=parameters,
        envelope=scenario.effective_envelope() or PerformanceEnvelope(max_effort=values["max_effort"]),
        scenario=scenario,
        stand=_identified_stand(setup, values, scenario, uses_duty=replay.uses_duty),
        train=train_errors,
        validation=validation_errors,
        search=found,
        wall_time_s=time.perf_counter() - started,
        engine=engine,
        engine_train=engine_train,
        engine_validation=engine_validation,
        notes=log_notes(setup, [*train_logs, *validation_logs])
        + _bound_notes(space, found.values)
        + canonical_notes,
    )


def _moved(before: dict[str, float], after: dict[str, float]) -> list[str]:
    """Envelope parameters canonical form moved (their line does not bind: not identified)."""
    names = ("velocity_dependent_resistance", "speed_effort_gradient")
    return [name for name in names if before[name] != after[name]]


def _identified_stand(
    setup: IdentifyStand, values: dict[str, float], scenario: Scenario, *, uses_duty: bool
) -> IdentifyStand:
    """The stand ``-o`` writes: identified values, the servo gain and bounds widened to hold them."""
    bounds = {}
    for name, (low, high) in setup.bounds.items():
        value = values[name]
        bounds[name] = (min(low, value), max(high, value))
    duty_effort = values["duty_effort"] if uses_duty else None
    if duty_effort is not None and duty_effort == values["max_effort"] and setup.duty_effort is None:
        duty_effort = None  # the loop follows max_effort, as in the stand it came from
    return IdentifyStand(
        scenario=dataclasses.replace(
            scenario,
            joint=dataclasses.replace(scenario.joint, initial_position=0.0, initial_velocity=0.0),
        ),
        duty_per_rad=setup.duty_per_rad,
        duty_effort=duty_effort,
        bounds=bounds,
        source=setup.source,
    )


def replay_errors(replay: Replay, values: dict[str, float]) -> tuple[LogError, ...]:
    """Each log of ``replay`` replayed with ``values`` [SI] (reference engine)."""
    batch = {name: np.array([value]) for name, value in values.items()}
    errors = replay.errors(batch)
    result = replay.simulate(batch)
    out = []
    for i, log in enumerate(replay.logs):
        rows = log.rows
        out.append(
            LogError(
                log=log,
                mae_position=float(errors.position[0, i]),
                mae_velocity=None if errors.velocity is None else float(errors.velocity[0, i]),
                position=result.position[:rows, i],
                velocity=result.velocity[:rows, i],
                effort=result.effort[:rows, i],
            )
        )
    return tuple(out)


def log_scenario(setup: IdentifyStand, values: dict[str, float], log: BenchLog) -> Scenario:
    """The stand with ``values`` set up to replay ``log`` (its dt, length and initial state)."""
    base = setup.scenario
    duty = log.duty_per_rad if log.duty_per_rad is not None else setup.duty_per_rad
    stiffness = duty * values["duty_effort"] if duty is not None else values["stiffness"]
    drive = dataclasses.replace(
        base.drive, stiffness=stiffness, damping=values["damping"], max_effort=values["max_effort"]
    )
    envelope = PerformanceEnvelope(
        max_effort=values["max_effort"],
        max_actuator_velocity=values["max_actuator_velocity"],
        velocity_dependent_resistance=values["velocity_dependent_resistance"],
        speed_effort_gradient=values["speed_effort_gradient"],
        joint=base.joint.type,
        name=base.name,
    )
    static = values["static_friction"]
    friction = FrictionSpec(
        static_friction=static,
        dynamic_friction=min(values["dynamic_friction"], static),
        viscous_friction=values["viscous_friction"],
    )
    pendulum = base.pendulum
    if pendulum is not None:
        pendulum = dataclasses.replace(pendulum, angle_offset=values["angle_offset"])
    joint = dataclasses.replace(
        base.joint,
        armature=values["armature"],
        initial_position=float(log.position[0]),
        initial_velocity=float(log.velocity[0]) if log.velocity is not None else 0.0,
    )
    simulation = dataclasses.replace(base.simulation, dt=log.dt, duration=(log.rows - 1) * log.dt)
    return dataclasses.replace(
        base,
        joint=joint,
        drive=drive,
        envelope=envelope,
        friction=friction,
        pendulum=pendulum,
        simulation=simulation,
        name=log.name,
    )


def log_schedule(log: BenchLog) -> DriveSchedule:
    """A log's commands as a drive schedule (``rows - 1`` steps)."""
    return DriveSchedule(
        target_position=log.target_position[:-1],
        target_velocity=log.target_velocity[:-1],
        enabled=log.enabled[:-1],
    )


def _identified(setup: IdentifyStand, values: dict[str, float], log: BenchLog) -> Scenario:
    scenario = log_scenario(setup, values, log)
    return dataclasses.replace(scenario, name=setup.scenario.name or "identified stand")


def _engine_mae(
    engine: str, setup: IdentifyStand, values: dict[str, float], logs: Sequence[BenchLog]
) -> dict[str, float]:
    """Position MAE of each log replayed in ``engine`` (physx or mujoco)."""
    return {name: errors[0] for name, errors in engine_errors(engine, setup, values, logs).items()}


def engine_errors(
    engine: str, setup: IdentifyStand, values: dict[str, float], logs: Sequence[BenchLog]
) -> dict[str, tuple[float, float | None]]:
    """Position and velocity MAE of each log replayed in ``engine`` (physx or mujoco).

    Returns:
        Log file name -> (position MAE [rad or m], velocity MAE [rad/s or m/s], None without velocity).
    """
    if not logs:
        return {}
    from drive_envelope._src.teststand.engines import engine_module

    engine_module(engine)  # a missing extra is one line naming it
    scenarios = [log_scenario(setup, values, log) for log in logs]
    schedules = [log_schedule(log) for log in logs]
    if engine == "physx":
        from drive_envelope._src.adapters.physx.stand import simulate_many

        trajectories = simulate_many(scenarios, schedules=schedules)
    else:
        from drive_envelope._src.adapters.mujoco.stand import simulate as run

        _load_mujoco_plugin()
        trajectories = [run(s, schedule=p) for s, p in zip(scenarios, schedules, strict=True)]
    return {
        log.name: (
            float(np.mean(np.abs(trajectory.position - log.position))),
            None if log.velocity is None else float(np.mean(np.abs(trajectory.velocity - log.velocity))),
        )
        for log, trajectory in zip(logs, trajectories, strict=True)
    }


def _load_mujoco_plugin() -> None:
    from drive_envelope._src.adapters.mujoco.loader import load_plugin

    load_plugin()


_SIDECAR_TOLERANCE = 0.01  # relative difference of a sidecar's bench number from the stand's


def log_notes(setup: IdentifyStand, logs: Sequence[BenchLog]) -> tuple[str, ...]:
    """Warnings for sidecars that disagree with their log or the stand (a copied or stale file)."""
    notes = []
    pendulum = setup.scenario.pendulum
    logs = list({str(log.path): log for log in logs}.values())  # a log in train and validate: once
    for log in logs:
        sidecar = log.sidecar or {}
        stem = Path(log.path).name.split(".")[0]
        named = sidecar.get("name")
        if isinstance(named, str) and named != stem:
            notes.append(
                f"{log.path}: its sidecar names the log {named!r}: a sidecar copied from another log? "
                "(its kp_duty_per_rad is used as it is; the pendulum is the stand's)"
            )
        for key, stand_key in (("mass_kg", "mass"), ("length_m", "distance")):
            value = sidecar.get(key)
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                continue
            if pendulum is None:
                notes.append(
                    f"{log.path}: its sidecar gives a pendulum ({key} = {value:g}) but {setup.source} "
                    "has no [pendulum]: gravity on the load is not modelled"
                )
                break
            expected = float(getattr(pendulum, stand_key))
            if abs(float(value) - expected) > _SIDECAR_TOLERANCE * max(abs(expected), 1e-12):
                notes.append(
                    f"{log.path}: its sidecar gives {key} = {value:g} but {setup.source} has "
                    f"pendulum.{stand_key} = {expected:g}: the replay uses the stand's "
                    f"{expected:g} (fix whichever is wrong)"
                )
    return (*notes, *duty_notes(setup, logs))


def duty_notes(setup: IdentifyStand, logs: Sequence[BenchLog]) -> tuple[str, ...]:
    """One warning per log without the sidecar gain the others have: it uses the stand's [servo] gain.

    A missing sidecar in a gain sweep would otherwise give that log a wrong stiffness silently.
    """
    if setup.duty_per_rad is None or all(log.duty_per_rad is None for log in logs):
        return ()
    paths = dict.fromkeys(Path(log.path) for log in logs if log.duty_per_rad is None)
    return tuple(
        f"{path}: no kp_duty_per_rad in a sidecar (other logs have one; looked for "
        f"{', '.join(os.path.relpath(p, path.parent) for p in sidecar_candidates(path))}): uses the stand's "
        f"servo.duty_per_rad = {setup.duty_per_rad:g}"
        for path in paths
    )


def _bound_notes(space: ParameterSpace, values: dict[str, float]) -> tuple[str, ...]:
    notes = []
    for i, name in enumerate(space.names):
        low, high = float(space.low[i]), float(space.high[i])
        span = high - low
        value = values[name]
        for side, bound in (("lower", low), ("upper", high)):
            if abs(value - bound) <= _AT_BOUND * span and not (side == "lower" and bound == 0.0):
                notes.append(
                    f"{name} = {value:.6g} ended at its {side} bound {bound:.6g}: widen [bounds] {name} "
                    "in the stand file"
                )
    return tuple(notes)


def mean_error(errors: Sequence[LogError]) -> float:
    """Mean of the logs' position MAEs [rad or m] (NaN without logs)."""
    return float(np.mean([e.mae_position for e in errors])) if errors else math.nan

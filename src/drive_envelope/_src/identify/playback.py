"""Replaying logs through a stand: ``drive-envelope replay LOG... --stand STAND``.

Each log's commands (targets, ``torque_enable``, its sidecar's duty gain) are replayed from its
first sample, as identification replays them (:class:`~drive_envelope._src.identify.replay.Replay`,
the same batched reference solver), so an identified stand (``identify -o``) replays its held-out
logs to identify's ``validation`` errors. ``engine="physx"`` or ``"mujoco"`` replays them there
instead (the errors a user sees in that engine).
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from drive_envelope._src.analysis.log_bag import BagOptions
from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.logs import BenchLog, read_bench_log
from drive_envelope._src.identify.parameters import parameter_units, start_values
from drive_envelope._src.identify.replay import Replay
from drive_envelope._src.identify.run import ENGINES, engine_errors, log_notes, replay_errors
from drive_envelope._src.identify.stand import IdentifyStand, StandWarning, read_stand


@dataclass(frozen=True, kw_only=True, slots=True)
class Playback:
    """Replays of logs through one stand."""

    stand: IdentifyStand
    """The stand."""
    engine: str
    """The engine the logs were replayed in."""
    errors: dict[str, tuple[float, float | None]]
    """Log file name -> (position MAE [rad or m], velocity MAE [rad/s or m/s] or None)."""
    logs: tuple[BenchLog, ...]
    """The logs, in the order given."""
    wall_time_s: float
    """Time taken [s]."""


def stand_values(stand: IdentifyStand) -> dict[str, float]:
    """Every identify parameter's value in the stand [SI].

    ``duty_effort`` is the stand's ``[servo] duty_effort``, else ``max_effort``.
    """
    return start_values(stand.scenario, stand.duty_effort)


def replay_logs(
    logs: Sequence[str | os.PathLike[str]],
    stand: str | os.PathLike[str],
    *,
    engine: str = "reference",
    bag: BagOptions | None = None,
    joint: str | None = None,
) -> Playback:
    """Replay ``logs`` through ``stand`` in ``engine`` (``bag`` and ``joint`` for ROS 2 bags).

    Warns:
        StandWarning: as identify warns: once per log without the sidecar ``kp_duty_per_rad`` other
            logs have (it is replayed with the stand's ``[servo] duty_per_rad``), and per sidecar that
            names another log or gives a pendulum other than the stand's.

    Raises:
        InputError: a bad log, stand or engine, or no log.
    """
    started = time.perf_counter()
    if engine not in ENGINES:
        raise InputError(f"--engine {engine!r}: expected one of {', '.join(ENGINES)}")
    if not logs:
        raise InputError("replay: give at least one log")
    setup = read_stand(stand, parameter_units())
    read = [read_bench_log(path, bag=bag, joint=joint) for path in logs]
    names = [log.name for log in read]
    if len(set(names)) != len(names):
        twice = sorted({name for name in names if names.count(name) > 1})
        raise InputError(
            f"replay: log file name(s) given twice: {', '.join(twice)}; reports key logs by name"
        )
    for note in log_notes(setup, read):  # copied or stale sidecars, missing gains: as identify says
        warnings.warn(note, StandWarning, stacklevel=2)
    values = stand_values(setup)
    errors: dict[str, tuple[float, float | None]] = {}
    if engine == "reference":
        for group in _same_step(read):  # one batched replay per sampling step
            for error in replay_errors(Replay(setup, group), values):
                errors[error.log.name] = (error.mae_position, error.mae_velocity)
    else:
        errors = engine_errors(engine, setup, values, read)
    return Playback(
        stand=setup,
        engine=engine,
        errors={log.name: errors[log.name] for log in read},
        logs=tuple(read),
        wall_time_s=time.perf_counter() - started,
    )


def _same_step(logs: Sequence[BenchLog]) -> list[list[BenchLog]]:
    groups: list[list[BenchLog]] = []
    for log in logs:
        for group in groups:
            if abs(group[0].dt - log.dt) <= 1e-6 * max(group[0].dt, log.dt):
                group.append(log)
                break
        else:
            groups.append([log])
    return groups


def playback_to_dict(playback: Playback) -> dict[str, Any]:
    """The ``--json`` object, keyed as identify's ``validation``.

    ``mae_position`` {log: rad}, ``mae_position_mean``, the same for velocity when every log has
    one, then ``engine``, ``stand`` and ``wall_time_s``.
    """
    position = {name: value[0] for name, value in playback.errors.items()}
    data: dict[str, Any] = {
        "mae_position": position,
        "mae_position_mean": float(np.mean(list(position.values()))),
    }
    velocities = {name: value[1] for name, value in playback.errors.items()}
    if all(value is not None for value in velocities.values()):
        data["mae_velocity"] = velocities
        data["mae_velocity_mean"] = float(np.mean([float(v) for v in velocities.values() if v is not None]))
    data.update(engine=playback.engine, stand=playback.stand.source, wall_time_s=playback.wall_time_s)
    return data


def playback_text(playback: Playback) -> str:
    """Per-log errors for people (mrad and mrad/s, or mm and mm/s)."""
    from drive_envelope._src.format import format_table

    revolute = playback.stand.scenario.joint.type == "revolute"
    unit = "mrad" if revolute else "mm"
    rows = []
    for name, (position, velocity) in playback.errors.items():
        rows.append([name, f"{1e3 * position:.3f}", "-" if velocity is None else f"{1e3 * velocity:.3f}"])
    mean = float(np.mean([value[0] for value in playback.errors.values()]))
    header = ["log", f"MAE position [{unit}]", f"MAE velocity [{unit}/s]"]
    return (
        f"{playback.stand.source} in {playback.engine}\n"
        + format_table(header, rows)
        + f"\nmean position error {1e3 * mean:.3f} {unit} over {len(rows)} log(s); "
        + f"{playback.wall_time_s:.1f} s"
    )

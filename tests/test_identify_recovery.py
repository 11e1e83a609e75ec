"""identify recovers known parameters from logs the reference stand itself produced.

Ground truth: a pendulum servo (duty-gain drive, envelope, Coulomb + viscous friction, armature,
angle offset) replays two commanded trajectories with an unpowered span; the logs are written as
a user would write them. identify, started far from the truth, must find parameters whose replay
matches the logs (sub-mrad) and values close to the truth; the batched objective must equal
per-log reference runs; the std must be small where the logs identify a parameter.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import InputError
from drive_envelope._src.identify.logs import read_bench_log
from drive_envelope._src.identify.optimize import SearchOptions
from drive_envelope._src.identify.replay import Replay
from drive_envelope._src.identify.run import identify, log_scenario, log_schedule
from drive_envelope._src.identify.stand import read_stand
from drive_envelope._src.teststand.engines import reference

pytest.importorskip("scipy")

TRUTH = {
    "max_effort": 0.55,
    "max_actuator_velocity": 20.0,
    "velocity_dependent_resistance": 0.02,
    "speed_effort_gradient": 0.0,
    "stiffness": 0.0,
    "duty_effort": 0.55,  # the servo loop's full-duty effort is the stall effort here
    "damping": 0.025,
    "static_friction": 0.03,
    "dynamic_friction": 0.03,
    "viscous_friction": 0.004,
    "armature": 0.0015,
    "angle_offset": 0.02,
}

STAND = """
name = "synthetic servo"
[joint]
inertia = 1e-6
armature = {armature}
[drive]
max_effort = {max_effort}
damping = {damping}
[envelope]
max_actuator_velocity = 20.0
velocity_dependent_resistance = 0.02
[servo]
duty_per_rad = 1.15
[pendulum]
mass = 0.49
distance = 0.1
angle_offset = {angle_offset}
[friction]
static_friction = {friction}
dynamic_friction = {friction}
viscous_friction = 0.004
[simulation]
solver = "pgs"
position_iterations = 1
velocity_iterations = 0
"""


def _stand(tmp_path: Path, **values: float) -> Path:
    path = tmp_path / "stand.toml"
    path.write_text(STAND.format(**values), encoding="utf-8")
    return path


def _write_log(
    path: Path, time: np.ndarray, columns: dict[str, np.ndarray], duty: float | None = None
) -> None:
    header = ["time", *columns]
    rows = np.column_stack([time, *columns.values()])
    path.write_text(
        ",".join(header) + "\n" + "\n".join(",".join(f"{x:.17g}" for x in row) for row in rows) + "\n",
        encoding="utf-8",
    )
    if duty is not None:
        path.with_suffix(".json").write_text(json.dumps({"kp_duty_per_rad": duty}), encoding="utf-8")


def _logs(tmp_path: Path, stand: Path) -> list[Path]:
    """Two logs the truth produced: a sine sweep (duty 1.15) and steps with a free fall (duty 0.6)."""
    setup = read_stand(stand)
    dt, rows = 0.005, 401
    t = np.arange(rows) * dt
    commands = [
        (1.15, 1.0 * np.sin(2 * np.pi * 1.2 * t) * np.sin(2 * np.pi * 0.4 * t), np.ones(rows, bool)),
        (0.6, np.where(t < 0.8, 1.2, -0.4), t < 1.2),
    ]
    paths = []
    for i, (duty, target, enabled) in enumerate(commands):
        path = tmp_path / f"log{i}.csv"
        columns = {
            "position": np.zeros(rows),
            "target_position": target,
            "torque_enable": enabled.astype(float),
        }
        _write_log(path, t, columns, duty)
        log = read_bench_log(path)  # the commands, to run the truth through the stand
        truth = reference.simulate(log_scenario(setup, TRUTH, log), schedule=log_schedule(log))
        columns.update(position=truth.position, velocity=truth.velocity)
        _write_log(path, t, columns, duty)
        paths.append(path)
    return paths


def test_batched_errors_equal_reference_runs(tmp_path: Path) -> None:
    """Score candidates in one batched pass exactly as per-log reference runs would."""
    stand = _stand(
        tmp_path, armature=0.0015, max_effort=0.55, damping=0.025, angle_offset=0.02, friction=0.03
    )
    logs = [read_bench_log(p) for p in _logs(tmp_path, stand)]
    setup = read_stand(stand)
    replay = Replay(setup, logs)
    candidates = {
        name: np.array([value, value * 1.1 if name == "max_effort" else value])
        for name, value in TRUTH.items()
    }
    errors = replay.errors(candidates)
    assert errors.position[0].max() < 1e-12  # the truth replays its own logs
    other = {name: float(values[1]) for name, values in candidates.items()}
    for i, log in enumerate(logs):
        run = reference.simulate(log_scenario(setup, other, log), schedule=log_schedule(log))
        assert errors.position[1, i] == pytest.approx(np.mean(np.abs(run.position - log.position)), rel=1e-10)


def test_identify_recovers_the_truth(tmp_path: Path) -> None:
    """Start 40 % off and recover max_effort, damping, friction, armature and offset to a few %."""
    truth = _stand(
        tmp_path, armature=0.0015, max_effort=0.55, damping=0.025, angle_offset=0.02, friction=0.03
    )
    logs = _logs(tmp_path, truth)
    start = _stand(tmp_path, armature=0.0025, max_effort=0.8, damping=0.015, angle_offset=0.0, friction=0.05)
    fit = ["max_effort", "damping", "static_friction", "armature", "angle_offset"]
    result = identify(
        logs[:1], start, validate=logs[1:], fit=fit, options=SearchOptions(generations=40, seed=1)
    )
    assert max(e.mae_position for e in result.train) < 1e-3
    assert max(e.mae_position for e in result.validation) < 2e-3
    for name in fit:
        assert result.parameters[name].value == pytest.approx(TRUTH[name], rel=0.05, abs=2e-3), name
        std = result.parameters[name].std
        assert not result.parameters[name].fixed and std is not None and std < 0.05 * max(TRUTH[name], 0.02)
    assert (
        result.parameters["dynamic_friction"].value == result.parameters["static_friction"].value
    )  # Coulomb
    assert result.parameters["viscous_friction"].fixed and result.parameters["viscous_friction"].std is None
    assert result.envelope.max_effort == result.parameters["max_effort"].value


def test_same_seed_same_result(tmp_path: Path) -> None:
    """Give the same parameters for the same inputs and seed (the search is seeded)."""
    truth = _stand(
        tmp_path, armature=0.0015, max_effort=0.55, damping=0.025, angle_offset=0.02, friction=0.03
    )
    logs = _logs(tmp_path, truth)[:1]
    options = SearchOptions(generations=3, population=4, polish_evaluations=2, seed=7)
    a = identify(logs, truth, fit=["max_effort", "damping"], options=options)
    b = identify(logs, truth, fit=["max_effort", "damping"], options=options)
    assert {k: v.value for k, v in a.parameters.items()} == {k: v.value for k, v in b.parameters.items()}


def test_parameters_the_logs_never_exercise_are_not_identified(tmp_path: Path) -> None:
    """Report std inf for a speed line the logs never reach (max_actuator_velocity searched in 100..1000)."""
    truth = _stand(
        tmp_path, armature=0.0015, max_effort=0.55, damping=0.025, angle_offset=0.02, friction=0.03
    )
    logs = _logs(tmp_path, truth)[:1]
    fast = tmp_path / "fast.toml"
    text = truth.read_text(encoding="utf-8").replace(
        "max_actuator_velocity = 20.0", "max_actuator_velocity = 200.0"
    )
    fast.write_text(text + "[bounds]\nmax_actuator_velocity = [100.0, 1000.0]\n", encoding="utf-8")
    options = SearchOptions(generations=2, population=4, polish_evaluations=0)
    result = identify(logs, fast, fit=["max_effort", "max_actuator_velocity"], options=options)
    assert result.parameters["max_actuator_velocity"].std == float("inf")
    assert np.isfinite(result.parameters["max_effort"].std)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("fit", "message"),
    [
        (["max_torque"], "unknown parameter"),
        (["damping", "damping"], "named twice"),
        (["stiffness"], "ties stiffness to max_effort"),
    ],
)
def test_bad_fit_lists_are_one_line(tmp_path: Path, fit: list[str], message: str) -> None:
    """Refuse unknown, repeated or tied parameter names with one line."""
    stand = _stand(
        tmp_path, armature=0.0015, max_effort=0.55, damping=0.025, angle_offset=0.02, friction=0.03
    )
    logs = _logs(tmp_path, stand)[:1]
    with pytest.raises(InputError, match=message):
        identify(logs, stand, fit=fit)


def test_angle_offset_needs_a_pendulum(tmp_path: Path) -> None:
    """Refuse --fit angle_offset on a stand without [pendulum]."""
    stand = _stand(
        tmp_path, armature=0.0015, max_effort=0.55, damping=0.025, angle_offset=0.02, friction=0.03
    )
    logs = _logs(tmp_path, stand)[:1]
    text = stand.read_text(encoding="utf-8")
    head, _, tail = text.partition("[pendulum]")
    no_pendulum = tmp_path / "flat.toml"
    no_pendulum.write_text(
        head + tail.partition("[friction]")[1] + tail.partition("[friction]")[2], encoding="utf-8"
    )
    with pytest.raises(InputError, match=r"has no \[pendulum\] table"):
        identify(logs, no_pendulum, fit=["angle_offset"])
    result = dataclasses.replace(read_stand(no_pendulum))
    assert result.scenario.pendulum is None

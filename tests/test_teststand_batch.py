"""The batched replay (``teststand.batch``) is the reference engine, element by element.

Every element of one batch is a different stand (drive kind, envelope, friction, pendulum,
armature, loads) run through a schedule with unpowered spans; each must equal
``reference.simulate`` of the same scenario (a batch of one, built from the scenario by the
engine, not by this file's ``_stand``) to ~1e-12, on PGS and TGS with and without velocity
iterations. An element that overflows is flagged with the step and what overflowed.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from drive_envelope import PerformanceEnvelope
from drive_envelope._src.scenario.loads import FrictionSpec, PendulumSpec
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import DriveSpec, JointSpec, LoadSpec, Scenario, SimulationSpec
from drive_envelope._src.teststand.batch import (
    OVERFLOW_LAW,
    OVERFLOW_REQUEST,
    OVERFLOW_STATE,
    BatchResult,
    BatchSolver,
    BatchStand,
    simulate_batch,
)
from drive_envelope._src.teststand.engines import reference

ENV = PerformanceEnvelope(
    max_effort=0.6, max_actuator_velocity=12.0, velocity_dependent_resistance=0.03, speed_effort_gradient=0.05
)


def _variants() -> list[tuple[str, dict[str, object]]]:
    pendulum = PendulumSpec(mass=0.49, distance=0.1, angle_offset=0.05)
    friction = FrictionSpec(static_friction=0.03, dynamic_friction=0.02, viscous_friction=0.01)
    position_drive = DriveSpec(stiffness=0.7, damping=0.03, max_effort=0.6)
    return [
        ("envelope_pendulum_friction", {"pendulum": pendulum, "friction": friction, "armature": 1.6e-3}),
        ("plain_drive", {"envelope": None, "pendulum": pendulum}),
        ("unlimited_drive", {"envelope": None, "drive": DriveSpec(stiffness=0.7, damping=0.03)}),
        (
            "drive_off",
            {"envelope": None, "drive": DriveSpec(stiffness=0.7, max_effort=0.0), "pendulum": pendulum},
        ),
        ("loads", {"load": LoadSpec(applied_effort=0.05, external_effort=-0.1), "friction": friction}),
        ("viscous_only", {"friction": FrictionSpec(viscous_friction=0.02), "pendulum": pendulum}),
        ("no_friction_drive", {"drive": position_drive, "armature": 5e-3}),
    ]


def _scenario(name: str, options: dict[str, object], solver: str, iterations: tuple[int, int]) -> Scenario:
    fields = {
        "joint": JointSpec(inertia=2e-3, armature=float(options.get("armature", 0.0)), initial_position=0.1),
        "drive": options.get("drive", DriveSpec(stiffness=0.7, damping=0.03, max_effort=0.6)),
        "envelope": options.get("envelope", ENV),
        "pendulum": options.get("pendulum"),
        "friction": options.get("friction", FrictionSpec()),
        "load": options.get("load", LoadSpec()),
        "simulation": SimulationSpec(
            dt=0.005,
            duration=1.5,
            solver=solver,
            position_iterations=iterations[0],
            velocity_iterations=iterations[1],
        ),
    }
    return Scenario(name=name, **fields)  # type: ignore[arg-type]


def _schedule(steps: int) -> DriveSchedule:
    t = np.arange(steps) * 0.005
    return DriveSchedule(
        target_position=1.2 * np.sin(2 * np.pi * 0.7 * t),
        target_velocity=0.3 * np.cos(3 * t),
        enabled=~((t > 0.6) & (t < 0.9)),
    )


def _stand(scenarios: list[Scenario]) -> BatchStand:
    def column(get):  # type: ignore[no-untyped-def]
        return np.array([float(get(s)) for s in scenarios])

    def envelope(s: Scenario, field: str, default: float) -> float:
        env = s.effective_envelope()
        return default if env is None else getattr(env, field)

    return BatchStand(
        inertia=column(lambda s: s.effective_inertia),
        stiffness=column(lambda s: s.drive.stiffness),
        damping=column(lambda s: s.drive.damping),
        max_effort=column(lambda s: s.drive.max_effort),
        max_actuator_velocity=column(lambda s: envelope(s, "max_actuator_velocity", math.inf)),
        velocity_dependent_resistance=column(lambda s: envelope(s, "velocity_dependent_resistance", 0.0)),
        speed_effort_gradient=column(lambda s: envelope(s, "speed_effort_gradient", 0.0)),
        static_friction=column(lambda s: s.friction.static_friction),
        dynamic_friction=column(lambda s: s.friction.dynamic_friction),
        viscous_friction=column(lambda s: s.friction.viscous_friction),
        gravity_torque=column(
            lambda s: (
                0.0 if s.pendulum is None else s.pendulum.mass * s.simulation.gravity * s.pendulum.distance
            )
        ),
        angle_offset=column(lambda s: 0.0 if s.pendulum is None else s.pendulum.angle_offset),
        applied_effort=column(lambda s: s.load.applied_effort),
        external_effort=column(lambda s: s.load.external_effort),
    )


@pytest.mark.parametrize(
    ("solver", "iterations"), [("pgs", (1, 0)), ("pgs", (4, 1)), ("tgs", (4, 1)), ("tgs", (2, 0))]
)
def test_batch_equals_reference_on_every_element(solver: str, iterations: tuple[int, int]) -> None:
    """Give every element the reference engine's trajectory (position, velocity, effort) to 1e-12."""
    scenarios = [_scenario(name, options, solver, iterations) for name, options in _variants()]
    steps = scenarios[0].simulation.steps
    schedule = _schedule(steps)
    result = simulate_batch(
        BatchSolver(
            dt=0.005, solver=solver, position_iterations=iterations[0], velocity_iterations=iterations[1]
        ),  # type: ignore[arg-type]
        _stand(scenarios),
        initial_position=0.1,
        initial_velocity=0.0,
        target_position=schedule.target_position,
        target_velocity=schedule.target_velocity,
        enabled=schedule.enabled,
    )
    assert not result.diverged.any()
    for i, scenario in enumerate(scenarios):
        ref = reference.simulate(scenario, schedule=schedule)
        for column in ("position", "velocity", "effort"):
            np.testing.assert_allclose(
                getattr(result, column)[:, i],
                getattr(ref, column),
                rtol=0,
                atol=1e-12,
                err_msg=f"{scenario.name}: {column}",
            )


def test_acceleration_drive_equals_reference() -> None:
    """Scale the gains by the inertia for an acceleration drive, as the reference does."""
    scenario = _scenario("acceleration", {"pendulum": PendulumSpec(mass=0.2, distance=0.1)}, "tgs", (4, 1))
    scenario = dataclasses.replace(
        scenario, drive=DriveSpec(type="acceleration", stiffness=300.0, damping=20.0, max_effort=0.6)
    )
    schedule = _schedule(scenario.simulation.steps)
    result = simulate_batch(
        BatchSolver(
            dt=0.005, solver="tgs", position_iterations=4, velocity_iterations=1, drive_type="acceleration"
        ),
        _stand([scenario]),
        initial_position=0.1,
        initial_velocity=0.0,
        target_position=schedule.target_position,
        target_velocity=schedule.target_velocity,
        enabled=schedule.enabled,
    )
    ref = reference.simulate(scenario, schedule=schedule)
    np.testing.assert_allclose(result.position[:, 0], ref.position, rtol=0, atol=1e-12)


def test_a_diverging_element_is_flagged_not_fatal() -> None:
    """Flag an element whose state overflows and keep the others' results."""
    good = _scenario("good", {}, "pgs", (1, 0))
    stand = _stand([good, good])
    broken = dataclasses.replace(
        stand, external_effort=np.array([0.0, 1e308]), inertia=np.array([2e-3, 1e-300])
    )
    steps = good.simulation.steps
    result = simulate_batch(
        BatchSolver(dt=0.005),
        broken,
        initial_position=0.1,
        initial_velocity=0.0,
        target_position=np.zeros(steps),
        target_velocity=np.zeros(steps),
        enabled=np.ones(steps),
    )
    assert result.diverged.tolist() == [False, True]
    assert np.isfinite(result.position[:, 0]).all() and np.isnan(result.position[-1, 1])


def _run(stand: BatchStand, steps: int, **options: object) -> BatchResult:
    return simulate_batch(
        BatchSolver(dt=0.005),
        stand,
        initial_position=0.1,
        initial_velocity=0.0,
        target_position=np.full(steps, 1.0),
        target_velocity=np.full(steps, 5.0),
        enabled=np.ones(steps),
        **options,  # type: ignore[arg-type]
    )


def test_a_non_finite_drive_law_or_request_diverges_although_the_state_is_finite() -> None:
    """Flag the law (even of a drive that is off) and an infinite request, whose clamp is finite."""
    good = _scenario("good", {}, "pgs", (1, 0))
    stand = _stand([good, good, good])
    broken = dataclasses.replace(
        stand,
        damping=np.array([0.03, 1e308, 0.03]),  # dt*damping*target_velocity overflows
        max_effort=np.array([0.6, 0.0, 0.6]),
        external_effort=np.array([0.0, 0.0, 1e308]),  # a finite push, an infinite request
        inertia=np.array([2e-3, 2e-3, 1e-10]),
    )
    result = _run(broken, 40)
    assert result.diverged.tolist() == [False, True, True]
    assert result.diverged_step.tolist() == [-1, 0, 0]
    assert result.overflow.tolist() == [0, OVERFLOW_LAW, OVERFLOW_REQUEST]
    assert np.isfinite(result.position[:, 0]).all()
    assert np.isnan(result.position[1:, 1:]).all() and (result.position[0, 1:] == 0.1).all()


def test_the_diverging_step_is_the_first_whose_state_overflows() -> None:
    """Name the step from which the state is not finite; rows up to it keep their values."""
    good = _scenario("good", {}, "pgs", (1, 0))
    stand = dataclasses.replace(
        _stand([good, good]), max_effort=np.array([0.6, 0.0]), external_effort=np.array([0.0, 1e305])
    )
    # the velocity grows by 1e305 / 2e-3 * 0.005 = 2.5e305 a step, the position after n steps is
    # n * (n + 1) / 2 * 0.005 * 2.5e305: 1.792e308 after 535, beyond float64's 1.798e308 after 536
    result = _run(stand, 1000)
    assert result.overflow.tolist() == [0, OVERFLOW_STATE]
    assert result.diverged_step.tolist() == [-1, 535]
    assert result.position[535, 1] == pytest.approx(535 * 536 / 2 * 0.005 * 2.5e305)
    assert np.isnan(result.position[536:, 1]).all() and np.isfinite(result.position[:, 0]).all()
    assert _run(stand, 535).diverged.tolist() == [False, False]
    assert _run(stand, 536).diverged.tolist() == [False, True]


def test_progress_every_4096_steps_and_a_batch_that_all_diverged_stops() -> None:
    """Report (done, steps) every 4096 steps and at the end; stop once every element diverged."""
    good = _scenario("good", {}, "pgs", (1, 0))
    calls: list[tuple[int, int]] = []
    _run(_stand([good]), 9000, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(4096, 9000), (8192, 9000), (9000, 9000)]
    calls.clear()
    empty = _run(_stand([good]), 0, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(0, 0)] and empty.position.tolist() == [[0.1]] and empty.diverged_step.tolist() == [-1]
    calls.clear()
    broken = dataclasses.replace(
        _stand([good]), max_effort=np.array([0.0]), external_effort=np.array([1e306])
    )
    result = _run(broken, 9000, progress=lambda done, total: calls.append((done, total)))
    assert calls == [] and result.diverged.tolist() == [True] and np.isnan(result.position[-1]).all()


def test_an_envelope_without_effort_limit_keeps_its_speed_line() -> None:
    """max_effort inf with a finite max_actuator_velocity still clamps (only inf, inf skips the clamp)."""
    good = _scenario("good", {}, "pgs", (1, 0))
    stand = dataclasses.replace(
        _stand([good, good]),
        max_effort=np.array([math.inf, math.inf]),
        max_actuator_velocity=np.array([3.0, math.inf]),
        damping=np.array([20.0, 20.0]),
    )
    result = _run(stand, 200)
    assert result.velocity[:, 0].max() <= 3.0 + 1e-12 < result.velocity[:, 1].max()

"""The batched replay (``teststand.batch``) is the reference engine, element by element.

Every element of one batch is a different stand (drive kind, envelope, friction, pendulum,
armature, loads) run through a schedule with unpowered spans; each must equal
``reference.simulate`` of the same scenario to ~1e-12 (both are float64; only the order of a few
sums differs), on PGS and TGS with and without velocity iterations.
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
from drive_envelope._src.teststand.batch import BatchSolver, BatchStand, simulate_batch
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

"""Parity of the ``reference`` engine with real PhysX (ovphysx 0.7, CPU) on designed scenarios.

Every scenario runs on both solvers (PGS and TGS), all of them in one module fixture. The plain
drive (no envelope API, only maxForce) with an applied joint force is limited drive + applied
TOGETHER to +-maxForce, as SEMANTICS.md states and the reference engine models (ovphysx 0.3.7
clamped the drive alone; 0.7 agrees with the reference). Tolerances (per step, from the issue):
velocity ``1e-5 + 5e-5*max|v|``, effort ``1e-4 + 1e-3*max_effort``, position
``1e-5 + 1e-4*path length``; stiff position steps braking on an envelope curve, where PhysX's float32
rounding is amplified, allow ``1e-3*max|v|`` and ``2e-2*max_effort``.

The bench loads (issue 16) run at the same tolerances: a gravity pendulum (free, with an angle
offset, lifted by a drive), PhysX 5.6 joint friction (static above dynamic, viscous; a Coulomb
coast to a stop; with and without velocity iterations), armature (with applied and external
efforts), all of them together, and a BAM-like replay with per-step targets and unpowered spans
(a drive schedule: the runner writes targets and zero gains every step). With friction, PhysX's
effort column is drive + applied + friction (ovphysx 0.7 has no drive-force read); it is compared
with the reference's drive + applied effort plus the friction its momentum balance implies.
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import PerformanceEnvelope
from drive_envelope._src.scenario.loads import FrictionSpec, PendulumSpec
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import (
    DriveSpec,
    JointSpec,
    LoadSpec,
    Scenario,
    SimulationSpec,
    load_scenario,
)

pytestmark = [pytest.mark.physx, pytest.mark.usd]

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
_ENV = PerformanceEnvelope(
    max_effort=10.0, max_actuator_velocity=6.0, velocity_dependent_resistance=0.4, speed_effort_gradient=0.2
)


def _scenario(
    name: str,
    solver: str,
    *,
    drive: DriveSpec,
    envelope: PerformanceEnvelope | None = _ENV,
    joint: str = "revolute",
    inertia: float = 0.05,
    load: LoadSpec | None = None,
    initial_velocity: float = 0.0,
    dt: float = 1.0 / 240.0,
    duration: float = 0.25,
    stiff: bool = False,
) -> tuple[Scenario, bool]:
    return (
        Scenario(
            name=f"{name}[{solver}]",
            joint=JointSpec(type=joint, inertia=inertia, initial_velocity=initial_velocity),  # type: ignore[arg-type]
            drive=drive,
            envelope=envelope,
            load=load or LoadSpec(),
            simulation=SimulationSpec(
                dt=dt, duration=duration, solver=solver, position_iterations=4, velocity_iterations=1
            ),  # type: ignore[arg-type]
        ),
        stiff,
    )


def _cases(solver: str) -> list[tuple[Scenario, bool]]:
    no_slopes = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=6.0)
    resistance_only = PerformanceEnvelope(max_effort=10.0, velocity_dependent_resistance=1.5)
    gradient_only = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=8.0, speed_effort_gradient=0.5)
    linear = PerformanceEnvelope(
        joint="prismatic",
        max_effort=80.0,
        max_actuator_velocity=0.8,
        velocity_dependent_resistance=20.0,
        speed_effort_gradient=0.002,
    )
    velocity_drive = DriveSpec(damping=50.0, target_velocity=40.0, max_effort=10.0)
    return [
        _scenario("velocity_saturation", solver, envelope=no_slopes, drive=velocity_drive),
        _scenario("resistance_line", solver, envelope=resistance_only, drive=velocity_drive),
        _scenario("gradient", solver, envelope=gradient_only, drive=velocity_drive),
        _scenario("both_curves", solver, drive=velocity_drive),
        _scenario("constant_load", solver, drive=velocity_drive, load=LoadSpec(external_effort=-4.0)),
        _scenario(
            "applied_effort",
            solver,
            drive=DriveSpec(damping=2.0, target_velocity=3.0, max_effort=10.0),
            load=LoadSpec(applied_effort=6.0),
        ),
        _scenario(
            "braking",
            solver,
            drive=DriveSpec(damping=50.0, target_velocity=-2.0, max_effort=10.0),
            initial_velocity=5.5,
        ),
        _scenario(
            "overspeed_release",
            solver,
            drive=DriveSpec(damping=50.0, target_velocity=0.0, max_effort=10.0),
            initial_velocity=7.5,
            load=LoadSpec(external_effort=1.0),
        ),
        _scenario(
            "plain_drive",
            solver,
            envelope=None,
            drive=DriveSpec(damping=50.0, target_velocity=40.0, max_effort=10.0),
            load=LoadSpec(applied_effort=3.0),
        ),
        _scenario(
            "prismatic",
            solver,
            joint="prismatic",
            inertia=2.0,
            envelope=linear,
            drive=DriveSpec(damping=4000.0, target_velocity=2.0, max_effort=80.0),
        ),
        _scenario(
            "position_step",
            solver,
            drive=DriveSpec(stiffness=400.0, damping=8.0, target_position=0.3, max_effort=10.0),
        ),
        _scenario(
            "acceleration_drive",
            solver,
            drive=DriveSpec(
                type="acceleration", stiffness=400.0, damping=30.0, target_position=0.2, max_effort=10.0
            ),
        ),
        _scenario(
            "stiff_position_step",
            solver,
            drive=DriveSpec(stiffness=2000.0, damping=8.0, target_position=0.3, max_effort=10.0),
            stiff=True,
        ),
    ]


def _bundled_plain_drive() -> list[tuple[Scenario, bool]]:
    """examples/scenarios/plain_drive_applied_effort.toml as shipped (PGS) and on TGS."""
    scenario = load_scenario(EXAMPLES / "plain_drive_applied_effort.toml")
    tgs = dataclasses.replace(scenario.simulation, solver="tgs")
    return [
        (dataclasses.replace(scenario, name="plain_drive_applied_effort[pgs]"), False),
        (dataclasses.replace(scenario, name="plain_drive_applied_effort[tgs]", simulation=tgs), False),
    ]


_SERVO = PerformanceEnvelope(max_effort=1.0, max_actuator_velocity=8.0, velocity_dependent_resistance=0.02,
                             speed_effort_gradient=0.5)  # fmt: skip
_PENDULUM = PendulumSpec(mass=0.5, distance=0.1)
_FRICTION = FrictionSpec(static_friction=0.3, dynamic_friction=0.2, viscous_friction=0.02)


def _load_case(
    name: str,
    solver: str,
    *,
    drive: DriveSpec = DriveSpec(max_effort=1.0),  # noqa: B008 (frozen)
    envelope: PerformanceEnvelope | None = _SERVO,
    armature: float = 0.0,
    position: float = 0.0,
    velocity: float = 0.0,
    iterations: tuple[int, int] = (4, 1),
    pendulum: PendulumSpec | None = None,
    friction: FrictionSpec = FrictionSpec(),  # noqa: B008 (frozen)
    load: LoadSpec = LoadSpec(),  # noqa: B008 (frozen)
) -> tuple[Scenario, bool]:
    """A bench-load scenario: servo-scale numbers, dt = 5 ms, 1 s."""
    simulation = SimulationSpec(
        dt=0.005,
        duration=1.0,
        solver=solver,  # type: ignore[arg-type]
        position_iterations=iterations[0],
        velocity_iterations=iterations[1],
    )
    joint = JointSpec(inertia=1e-3, armature=armature, initial_position=position, initial_velocity=velocity)
    scenario = Scenario(
        name=f"{name}[{solver}]",
        joint=joint,
        drive=drive,
        envelope=envelope,
        pendulum=pendulum,
        friction=friction,
        load=load,
        simulation=simulation,
    )
    return scenario, False


def _load_cases(solver: str) -> list[tuple[Scenario, bool]]:
    velocity_drive = DriveSpec(damping=1.0, target_velocity=5.0, max_effort=1.0)
    return [
        _load_case("free_pendulum", solver, pendulum=_PENDULUM, position=1.0),
        _load_case(
            "pendulum_offset",
            solver,
            pendulum=PendulumSpec(mass=0.5, distance=0.1, angle_offset=0.3),
            position=0.5,
        ),
        _load_case(
            "pendulum_drive",
            solver,
            pendulum=_PENDULUM,
            drive=DriveSpec(stiffness=5.0, damping=0.05, target_position=1.5, max_effort=1.0),
        ),
        _load_case("friction_breakaway", solver, drive=velocity_drive, friction=_FRICTION),
        _load_case(
            "friction_no_velocity_iteration",
            solver,
            drive=velocity_drive,
            friction=_FRICTION,
            iterations=(4, 0),
        ),
        _load_case(
            "coulomb_coast",
            solver,
            envelope=None,
            drive=DriveSpec(max_effort=0.0),
            velocity=3.0,
            friction=FrictionSpec(static_friction=0.05, dynamic_friction=0.03, viscous_friction=0.001),
        ),
        _load_case(
            "armature",
            solver,
            armature=4e-3,
            drive=DriveSpec(stiffness=2.0, damping=0.05, target_position=0.5, max_effort=1.0),
        ),
        _load_case(
            "armature_loads",
            solver,
            armature=4e-3,
            drive=DriveSpec(damping=0.5, target_velocity=3.0, max_effort=1.0),
            load=LoadSpec(external_effort=-0.3, applied_effort=0.1),
        ),
        _load_case(
            "all_loads",
            solver,
            armature=2e-3,
            pendulum=PendulumSpec(mass=0.5, distance=0.1, angle_offset=0.1),
            friction=FrictionSpec(static_friction=0.03, dynamic_friction=0.02, viscous_friction=0.01),
            drive=DriveSpec(stiffness=3.0, damping=0.05, target_position=1.0, max_effort=1.0),
        ),
    ]


def _schedule_case(solver: str) -> tuple[Scenario, bool]:
    """A BAM-like bench replay: XL330-like servo, sinusoidal targets, unpowered from 1 s to 1.5 s."""
    envelope = PerformanceEnvelope(
        max_effort=0.6, max_actuator_velocity=12.0, velocity_dependent_resistance=0.03
    )
    scenario = Scenario(
        name=f"bench_schedule[{solver}]",
        joint=JointSpec(inertia=1e-5, armature=1.6e-3),
        drive=DriveSpec(stiffness=0.69, damping=0.03, max_effort=0.6),
        envelope=envelope,
        pendulum=PendulumSpec(mass=0.49, distance=0.1, angle_offset=0.016),
        friction=FrictionSpec(static_friction=0.01, dynamic_friction=0.01, viscous_friction=0.01),
        simulation=SimulationSpec(
            dt=0.005, duration=2.0, solver=solver, position_iterations=4, velocity_iterations=1
        ),  # type: ignore[arg-type]
    )
    return scenario, False


def _schedule(steps: int) -> DriveSchedule:
    t = np.arange(steps) * 0.005
    return DriveSchedule(
        target_position=1.2 * np.sin(2 * np.pi * 0.8 * t) * np.sin(2 * np.pi * 0.3 * t),
        target_velocity=np.zeros(steps),
        enabled=~((t > 1.0) & (t < 1.5)),
    )


def _bundled_loads() -> list[tuple[Scenario, bool]]:
    """examples/scenarios/loads/*.toml as shipped."""
    return [(load_scenario(path), False) for path in sorted((EXAMPLES / "loads").glob("*.toml"))]


CASES = (
    _cases("pgs")
    + _cases("tgs")
    + _bundled_plain_drive()
    + _bundled_loads()
    + _load_cases("pgs")
    + _load_cases("tgs")
    + [_schedule_case("pgs"), _schedule_case("tgs")]
)


def _schedule_of(scenario: Scenario) -> DriveSchedule | None:
    return _schedule(scenario.simulation.steps) if scenario.name.startswith("bench_schedule") else None


@pytest.fixture(scope="module")
def runs() -> dict[str, tuple[object, object, bool]]:
    from drive_envelope._src.teststand.engines import physx, reference

    scenarios = [scenario for scenario, _ in CASES]
    schedules = [_schedule_of(scenario) for scenario in scenarios]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the authoring warnings are about user assets, not the stand
        results = physx.simulate_many(scenarios, schedules)
    return {
        s.name: (reference.simulate(s, schedule=_schedule_of(s)), r, stiff)
        for (s, stiff), r in zip(CASES, results, strict=True)
    }


def _friction_effort(scenario: Scenario, ref: object) -> np.ndarray:
    """The reference's step-average friction from its momentum balance: I*dv/dt - efforts - gravity."""
    position, velocity, effort = ref.position, ref.velocity, ref.effort  # type: ignore[attr-defined]
    outside = scenario.load.external_effort
    if scenario.pendulum is not None:
        outside = outside + scenario.pendulum.gravity_effort(position[:-1], scenario.simulation.gravity)
    friction = np.zeros_like(effort)
    friction[1:] = (
        scenario.effective_inertia * np.diff(velocity) / scenario.simulation.dt - effort[1:] - outside
    )
    return friction if scenario.friction.active else np.zeros_like(effort)


@pytest.mark.parametrize("name", [s.name for s, _ in CASES])
def test_reference_matches_physx_every_step(runs: dict[str, tuple[object, object, bool]], name: str) -> None:
    """Match PhysX's position, velocity and effort at every step within the issue's tolerances."""
    ref, phx, stiff = runs[name]
    scenario = next(s for s, _ in CASES if s.name == name)
    max_effort = scenario.drive.max_effort if scenario.drive.max_effort > 0 else 1.0
    v_scale = float(np.abs(ref.velocity).max())  # type: ignore[attr-defined]
    path = float(np.abs(np.diff(ref.position)).sum())  # type: ignore[attr-defined]
    v_tol = (1e-3 if stiff else 5e-5) * v_scale + 1e-5
    e_tol = (2e-2 if stiff else 1e-3) * max_effort + 1e-4
    q_tol = 1e-5 + 1e-4 * path
    expected = {"effort": ref.effort + _friction_effort(scenario, ref)}  # type: ignore[attr-defined]
    for column, tol in (("velocity", v_tol), ("effort", e_tol), ("position", q_tol)):
        a, b = expected.get(column, getattr(ref, column)), getattr(phx, column)
        err = np.abs(a - b)
        i = int(np.argmax(err))
        assert err[i] <= tol, f"{name}: {column} step {i}: reference {a[i]!r} physx {b[i]!r} (tol {tol:.3g})"


def test_physx_trajectory_has_reference_layout(runs: dict[str, tuple[object, object, bool]]) -> None:
    """Give PhysX trajectories the reference's rows, time axis and engine label."""
    ref, phx, _ = runs["velocity_saturation[pgs]"]
    assert len(phx) == len(ref)  # type: ignore[arg-type]
    np.testing.assert_array_equal(phx.time, ref.time)  # type: ignore[attr-defined]
    assert phx.engine == "physx" and phx.effort[0] == 0.0  # type: ignore[attr-defined]
    assert "jointProjectedForce" in phx.metadata["effort_source"]  # type: ignore[attr-defined]


def test_velocity_settles_on_max_actuator_velocity(runs: dict[str, tuple[object, object, bool]]) -> None:
    """Settle PhysX's joint velocity on maxActuatorVelocity (the envelope read from USD)."""
    _, phx, _ = runs["velocity_saturation[pgs]"]
    assert phx.velocity[-1] == pytest.approx(6.0, rel=1e-6)  # type: ignore[attr-defined]


@pytest.mark.parametrize("solver", ["pgs", "tgs"])
def test_plain_drive_limits_drive_and_applied_together(
    runs: dict[str, tuple[object, object, bool]], solver: str
) -> None:
    """Hold drive + applied effort at maxForce 10 N*m on a plain drive (applied 15 N*m, drive -5)."""
    _, phx, _ = runs[f"plain_drive_applied_effort[{solver}]"]
    dt, inertia = 0.0083333333, 0.05
    # first steps: the drive pulls the same way as the applied 15 N*m, the total is clamped to 10
    # (the drive alone clamped to 10 with 15 on top would give 25 N*m and twice the speed gain)
    np.testing.assert_allclose(phx.effort[1:4], 10.0, rtol=1e-6)  # type: ignore[attr-defined]
    np.testing.assert_allclose(phx.velocity[1:4], 10.0 * dt / inertia * np.arange(1, 4), rtol=1e-5)  # type: ignore[attr-defined]

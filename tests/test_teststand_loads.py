"""The bench loads of the test stand: gravity pendulum, PhysX joint friction, armature, schedules.

Goldens are closed forms worked by hand from PhysX's solver order (drive, then friction, each
iteration; gravity and external efforts from the start of the step): a PGS step under gravity, a
Coulomb coast that stops on a known step and stays stopped, the break-away threshold, the geometric
series k PGS iterations make of viscous friction, the armature's share of the response, and the
small-oscillation period of the pendulum.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import InputError, PerformanceEnvelope
from drive_envelope._src.scenario.loads import STANDARD_GRAVITY, FrictionSpec, PendulumSpec
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import (
    DriveSpec,
    JointSpec,
    LoadSpec,
    Scenario,
    SimulationSpec,
    load_scenario,
)
from drive_envelope._src.teststand.engines import reference
from drive_envelope._src.teststand.engines import simulate as run_engine

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"


def _stand(
    *,
    solver: str = "pgs",
    iterations: tuple[int, int] = (1, 0),
    inertia: float = 0.01,
    armature: float = 0.0,
    drive: DriveSpec | None = None,
    pendulum: PendulumSpec | None = None,
    friction: FrictionSpec | None = None,
    load: LoadSpec | None = None,
    position: float = 0.0,
    velocity: float = 0.0,
    dt: float = 0.01,
    duration: float = 1.0,
) -> Scenario:
    return Scenario(
        joint=JointSpec(
            inertia=inertia, armature=armature, initial_position=position, initial_velocity=velocity
        ),
        drive=drive or DriveSpec(max_effort=0.0),
        pendulum=pendulum,
        friction=friction or FrictionSpec(),
        load=load or LoadSpec(),
        simulation=SimulationSpec(
            dt=dt,
            duration=duration,
            solver=solver,  # type: ignore[arg-type]
            position_iterations=iterations[0],
            velocity_iterations=iterations[1],
        ),
    )


def test_pgs_step_under_gravity_is_semi_implicit_euler() -> None:
    """Take one PGS step: v1 = v0 + dt*tau_g(q0)/I with I = inertia + m*d^2, q1 = q0 + v1*dt."""
    pendulum = PendulumSpec(mass=0.5, distance=0.2, angle_offset=0.1)
    scenario = _stand(inertia=0.003, pendulum=pendulum, position=0.7, velocity=0.4, dt=0.01)
    state = reference.step(scenario, 0.7, 0.4)
    inertia = 0.003 + 0.5 * 0.2**2
    torque = -0.5 * STANDARD_GRAVITY * 0.2 * math.sin(0.7 + 0.1)
    v1 = 0.4 + 0.01 * torque / inertia
    assert state.velocity == pytest.approx(v1, rel=1e-15)
    assert state.position == pytest.approx(0.7 + v1 * 0.01, rel=1e-15)
    assert state.effort == 0.0  # gravity is not actuator effort


def test_tgs_substeps_apply_the_start_of_step_gravity() -> None:
    """Apply gravity from the start-of-step angle in every TGS substep (PhysX forms it once)."""
    pendulum = PendulumSpec(mass=1.0, distance=0.1)
    scenario = _stand(solver="tgs", iterations=(4, 0), pendulum=pendulum, position=0.5, dt=0.02)
    state = reference.step(scenario, 0.5, 0.0)
    accel = -STANDARD_GRAVITY * 0.1 * math.sin(0.5) / (0.01 + 0.01)
    h = 0.005
    velocities = accel * h * np.arange(1, 5)
    assert state.velocity == pytest.approx(velocities[-1], rel=1e-14)
    assert state.position == pytest.approx(0.5 + h * velocities.sum(), rel=1e-14)


def test_small_oscillations_have_the_pendulum_period() -> None:
    """Swing with the period 2*pi*sqrt(I/(m*g*d)) at small amplitude (0.5 % at dt = 1 ms)."""
    pendulum = PendulumSpec(mass=0.49, distance=0.1)
    scenario = _stand(inertia=1e-6, armature=0.0016, pendulum=pendulum, position=0.01, dt=0.001, duration=3.0)
    run = reference.simulate(scenario)
    crossings = np.flatnonzero(np.diff(np.signbit(run.position)))
    period = 2.0 * np.mean(np.diff(run.time[crossings]))
    expected = 2.0 * math.pi * math.sqrt((1e-6 + 0.0016 + 0.49 * 0.01) / (0.49 * STANDARD_GRAVITY * 0.1))
    assert period == pytest.approx(expected, rel=5e-3)


def test_coulomb_coast_stops_on_the_predicted_step_and_sticks() -> None:
    """Lose F*dt/I of speed per step, stop exactly on the step the closed form gives, then stay put."""
    friction = FrictionSpec(static_friction=0.05, dynamic_friction=0.05)
    scenario = _stand(friction=friction, velocity=2.0, dt=0.01, duration=1.0)
    run = reference.simulate(scenario)
    per_step = 0.05 * 0.01 / 0.01  # 0.05 rad/s
    steps = math.ceil(2.0 / per_step - 1e-9)
    np.testing.assert_allclose(run.velocity[:steps], 2.0 - per_step * np.arange(steps), atol=1e-12)
    assert np.all(run.velocity[steps:] == 0.0)
    assert np.all(run.position[steps:] == run.position[steps])


def test_static_friction_holds_below_break_away_and_dynamic_acts_above() -> None:
    """Hold against 0.29 N*m with static 0.3; slip against 0.31 with dynamic 0.2: a = (0.31-0.2)/I."""
    friction = FrictionSpec(static_friction=0.3, dynamic_friction=0.2)
    held = reference.simulate(_stand(friction=friction, load=LoadSpec(external_effort=0.29)))
    assert np.all(held.velocity == 0.0)
    slipping = reference.simulate(
        _stand(friction=friction, load=LoadSpec(external_effort=0.31), duration=0.05)
    )
    np.testing.assert_allclose(np.diff(slipping.velocity), (0.31 - 0.2) * 0.01 / 0.01, rtol=1e-12)


@pytest.mark.parametrize("iterations", [(1, 0), (2, 0), (4, 1)])
def test_viscous_friction_iterations_sum_a_geometric_series(iterations: tuple[int, int]) -> None:
    """Scale the speed by sum_{j<=k} (-a)^j, a = c*dt/I, after k PGS iterations (implicit as k grows).

    PhysX runs at least one velocity iteration even with 0 configured (its reported velocity comes
    from that sweep; real PhysX's viscous spin agrees, tests/test_physx_chain.py), so
    k = position_iterations + max(1, velocity_iterations).
    """
    friction = FrictionSpec(viscous_friction=0.002)
    scenario = _stand(iterations=iterations, friction=friction, velocity=3.0, dt=0.01)
    state = reference.step(scenario, 0.0, 3.0)
    a = 0.002 * 0.01 / 0.01
    k = iterations[0] + max(1, iterations[1])
    assert state.velocity == pytest.approx(3.0 * sum((-a) ** j for j in range(k + 1)), rel=1e-13)
    assert state.friction == pytest.approx((state.velocity - 3.0) * 0.01 / 0.01, rel=1e-12)


def test_drive_answers_friction_within_a_pgs_step() -> None:
    """Settle a damping drive against Coulomb friction F at v = v* - F/c (several iterations)."""
    drive = DriveSpec(damping=1.0, target_velocity=5.0, max_effort=10.0)
    friction = FrictionSpec(static_friction=0.2, dynamic_friction=0.2)
    run = reference.simulate(_stand(iterations=(4, 1), drive=drive, friction=friction, duration=2.0))
    assert run.velocity[-1] == pytest.approx(5.0 - 0.2 / 1.0, rel=1e-9)
    assert run.effort[-1] == pytest.approx(0.2, rel=1e-9)


def test_armature_adds_to_the_response() -> None:
    """Respond with 1/(inertia + armature): a force drive's first step from rest."""
    drive = DriveSpec(damping=2.0, target_velocity=4.0, max_effort=100.0)
    with_armature = reference.step(_stand(inertia=0.01, armature=0.03, drive=drive), 0.0, 0.0)
    plain = reference.step(_stand(inertia=0.04, drive=drive), 0.0, 0.0)
    assert with_armature == plain
    assert with_armature.velocity == pytest.approx(4.0 * (2.0 * 0.01 / 0.04) / (1.0 + 2.0 * 0.01 / 0.04))


def test_schedule_of_constant_targets_is_the_scenario() -> None:
    """Give the same trajectory with a constant schedule as with the scenario's own targets."""
    drive = DriveSpec(stiffness=20.0, damping=0.5, target_position=0.8, target_velocity=0.1, max_effort=1.0)
    scenario = _stand(
        solver="tgs", iterations=(4, 1), drive=drive, pendulum=PendulumSpec(mass=0.3, distance=0.1)
    )
    steps = scenario.simulation.steps
    schedule = DriveSchedule(
        target_position=np.full(steps, 0.8), target_velocity=np.full(steps, 0.1), enabled=np.ones(steps, bool)
    )
    a, b = reference.simulate(scenario), reference.simulate(scenario, schedule=schedule)
    np.testing.assert_array_equal(a.position, b.position)
    np.testing.assert_array_equal(a.effort, b.effort)


def test_unpowered_steps_have_no_drive_effort() -> None:
    """Swing free while the drive is off (zero gains): no effort, the joint follows gravity alone."""
    drive = DriveSpec(stiffness=20.0, damping=0.5, target_position=1.0, max_effort=1.0)
    pendulum = PendulumSpec(mass=0.3, distance=0.1)
    scenario = _stand(drive=drive, pendulum=pendulum, position=0.5)
    steps = scenario.simulation.steps
    off = DriveSchedule(
        target_position=np.ones(steps), target_velocity=np.zeros(steps), enabled=np.zeros(steps, bool)
    )
    free = reference.simulate(dataclasses.replace(scenario, drive=DriveSpec(max_effort=1.0)))
    run = reference.simulate(scenario, schedule=off)
    assert np.all(run.effort == 0.0)
    np.testing.assert_array_equal(run.position, free.position)


def test_schedule_of_the_wrong_length_is_refused() -> None:
    """Refuse a schedule whose length is not the number of steps, naming both."""
    scenario = _stand(duration=0.1)
    schedule = DriveSchedule(
        target_position=np.zeros(5), target_velocity=np.zeros(5), enabled=np.ones(5, bool)
    )
    with pytest.raises(InputError, match="5 steps, the scenario 10"):
        reference.simulate(scenario, schedule=schedule)


# -- files ------------------------------------------------------------------------------------------


def test_bench_tables_read_with_units(tmp_path: Path) -> None:
    """Read [pendulum], [friction], joint.armature and simulation.gravity with units, SI inside."""
    path = tmp_path / "bench.toml"
    path.write_text(
        """
[joint]
inertia = "10 g*cm^2"
armature = "16 kg*cm^2"
[drive]
max_effort = "0.6 N*m"
[pendulum]
mass = "490 g"
distance = "10 cm"
angle_offset = "1 deg"
[friction]
static_friction = "30 mN*m"
dynamic_friction = "20 mN*m"
viscous_friction = "0.01 N*m*s/rad"
[simulation]
gravity = "9.81 m/s^2"
""",
        encoding="utf-8",
    )
    scenario = load_scenario(path, ["pendulum.mass=0.5"])
    assert scenario.joint.armature == pytest.approx(16e-4)
    pendulum = scenario.pendulum
    assert pendulum is not None and pendulum.mass == 0.5
    assert (pendulum.distance, pendulum.angle_offset) == pytest.approx((0.1, math.radians(1)))
    assert scenario.friction.static_friction == pytest.approx(0.03)
    assert scenario.friction.dynamic_friction == pytest.approx(0.02)
    assert scenario.simulation.gravity == pytest.approx(9.81)
    assert scenario.effective_inertia == pytest.approx(1e-6 + 16e-4 + 0.5 * 0.01)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "[joint]\ntype='prismatic'\ninertia=1\n[pendulum]\nmass=1\ndistance=0.1",
            "[pendulum] needs a revolute joint",
        ),
        ("[joint]\ninertia=1\n[pendulum]\nmass=1", "missing required key 'pendulum.distance'"),
        ("[joint]\ninertia=1\n[pendulum]\nmass=1\ndistance=0.1\nlength=2", "unknown key 'pendulum.length'"),
        (
            "[joint]\ninertia=1\n[friction]\nstatic_friction=0.1\ndynamic_friction=0.2",
            "must be <= friction.static",
        ),
        ("[joint]\ninertia=1\n[friction]\nviscous_friction=-1", "friction.viscous_friction must be >= 0"),
        ("[joint]\ninertia=1\narmature=-0.1", "joint.armature must be >= 0"),
        ("[joint]\ninertia=1\n[simulation]\ngravity='9.8 m/s'", "simulation.gravity"),
    ],
)
def test_bad_bench_tables_are_one_line(tmp_path: Path, text: str, message: str) -> None:
    """Refuse bad bench-load values with one line naming the file and the key."""
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputError, match=r"bad\.toml") as caught:
        load_scenario(path)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_dynamic_friction_alone_is_coulomb_friction(tmp_path: Path) -> None:
    """Read a lone dynamic_friction as Coulomb friction (static = dynamic), which PhysX then runs."""
    path = tmp_path / "coulomb.toml"
    path.write_text("[joint]\ninertia=1\n[friction]\ndynamic_friction=0.1\n", encoding="utf-8")
    friction = load_scenario(path).friction
    assert friction == FrictionSpec(static_friction=0.1, dynamic_friction=0.1) and friction.active


def test_engines_that_lack_a_load_refuse_it() -> None:
    """Refuse a bench load on an engine module that does not declare it (never drop it silently)."""
    import types

    from drive_envelope._src.teststand.engines import check_loads

    scenario = _stand(pendulum=PendulumSpec(mass=1.0, distance=0.1))
    with pytest.raises(InputError, match=r"does not represent \[pendulum\]"):
        check_loads(scenario, "toy", types.ModuleType("toy"))
    check_loads(scenario, "reference", reference)


@pytest.mark.parametrize("name", ["pendulum_swing", "friction_breakaway_tgs", "armature_step_tgs"])
def test_bench_example_scenarios_run(name: str) -> None:
    """Run the bundled bench-load scenarios on the reference engine."""
    scenario = load_scenario(EXAMPLES / "loads" / f"{name}.toml")
    run = run_engine(scenario, "reference")
    assert len(run) == scenario.simulation.steps + 1 and np.isfinite(run.position).all()


def test_envelope_limits_drive_on_a_pendulum() -> None:
    """Hold |effort| within the envelope while the drive lifts a pendulum."""
    env = PerformanceEnvelope(max_effort=0.4, max_actuator_velocity=8.0, velocity_dependent_resistance=0.02)
    scenario = dataclasses.replace(
        _stand(
            drive=DriveSpec(stiffness=5.0, damping=0.05, target_position=2.0, max_effort=0.4),
            pendulum=PendulumSpec(mass=0.49, distance=0.1),
            dt=0.005,
            duration=2.0,
        ),
        envelope=env,
    )
    run = reference.simulate(scenario)
    limit = env.effort_limit(run.velocity)
    assert np.all(np.abs(run.effort) <= limit + 1e-9)

"""The ``mujoco`` engine of ``drive-envelope simulate`` against the ``reference`` engine.

The stand runs the plugin with the scenario's PhysX solver (``set_solver``: PGS's sweeps, TGS's
substeps, their iteration counts), so PGS and TGS scenarios must agree at every step within the
issue's tolerances (velocity 1e-5 + 5e-5*max|v|, effort 1e-4 + 1e-3*max_effort, position 1e-5 +
1e-4*path length). Measured: float64 rounding, at most 1.6e-12 rad/s on the shipped scenarios
(``step_response_tgs``), so the tolerance, set by PhysX's float32 rows of docs/parity.md, leaves a
margin of 1e7 and still fails on any change of the iteration (one solve per step on TGS: 4 rad/s).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _edge_scenarios import EDGE_CASES
from _mujoco_plugin import mujoco_with_plugin
from drive_envelope.teststand import Scenario, Trajectory, load_scenario, scenario_from_mapping, simulate

pytestmark = pytest.mark.mujoco

SCENARIOS = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
PGS_FILES = sorted(SCENARIOS.glob("*_pgs.toml"))
TGS_FILES = sorted(
    file for file in SCENARIOS.glob("*.toml") if load_scenario(file).simulation.solver == "tgs"
)


@pytest.fixture(scope="module", autouse=True)
def plugin() -> None:
    mujoco_with_plugin()


def _assert_agree(scenario: Scenario, mj: Trajectory, ref: Trajectory) -> None:
    max_effort = (
        scenario.drive.max_effort if np.isfinite(scenario.drive.max_effort) else np.abs(ref.effort).max()
    )
    path = np.abs(np.diff(ref.position)).sum()
    v_tol = 1e-5 + 5e-5 * np.abs(ref.velocity).max()
    e_tol = 1e-4 + 1e-3 * max_effort
    q_tol = 1e-5 + 1e-4 * path
    np.testing.assert_allclose(mj.velocity, ref.velocity, rtol=0, atol=v_tol)
    np.testing.assert_allclose(mj.effort, ref.effort, rtol=0, atol=e_tol)
    np.testing.assert_allclose(mj.position, ref.position, rtol=0, atol=q_tol)


@pytest.mark.parametrize("file", PGS_FILES, ids=[f.stem for f in PGS_FILES])
def test_pgs_example_scenarios_agree_with_reference_every_step(file: Path) -> None:
    """Agree with the reference engine at every step on each shipped PGS scenario."""
    scenario = load_scenario(file)
    _assert_agree(scenario, simulate(scenario, "mujoco"), simulate(scenario, "reference"))


CASES = EDGE_CASES


@pytest.mark.parametrize("name", sorted(CASES))
def test_pgs_edge_scenarios_agree_with_reference_every_step(name: str) -> None:
    """Agree on prismatic, acceleration, applied/external effort, plain, off and unlimited drives."""
    data = {
        **CASES[name],
        "simulation": {"solver": "pgs", "dt": 1 / 120, "duration": 0.75, "position_iterations": 2},
    }
    scenario = scenario_from_mapping(data, source=name)
    _assert_agree(scenario, simulate(scenario, "mujoco"), simulate(scenario, "reference"))


@pytest.mark.parametrize("file", TGS_FILES, ids=[f.stem for f in TGS_FILES])
def test_tgs_example_scenarios_agree_with_reference_every_step(file: Path) -> None:
    """Agree with the reference at every step on each shipped TGS scenario, transients included."""
    scenario = load_scenario(file)
    mj = simulate(scenario, "mujoco")
    _assert_agree(scenario, mj, simulate(scenario, "reference"))
    assert mj.metadata["plugin_solver"] == "tgs"


# on the speed line with G/substep > response a TGS drive can brake by at most (v_max - |v|)/(G/h - r)
# per substep: the plugin's float64 lands exactly on 0.5 m/s, the reference 1e-16 below, PhysX's
# float32 6e-8 below, and each lets go at a different step (test_tgs_speed_line_knife_edge)
_KNIFE_EDGE = ("prismatic_acceleration_drive",)
_FRICTIONLESS_LOADS = ("free_pendulum", "pendulum_lift", "armature_step")


@pytest.mark.parametrize("iterations", [(4, 1), (4, 0), (2, 3)], ids=["4-1", "4-0", "2-3"])
@pytest.mark.parametrize("name", sorted(set(CASES) - set(_KNIFE_EDGE)) + list(_FRICTIONLESS_LOADS))
def test_tgs_edge_scenarios_agree_with_reference_every_step(name: str, iterations: tuple[int, int]) -> None:
    """Agree on TGS with 4/1, 4/0 and 2/3 iterations: applied/external, plain, off, unlimited, pendulum."""
    data = {
        **{**CASES, **LOAD_CASES}[name],
        "simulation": {
            "solver": "tgs",
            "dt": 0.005,
            "duration": 1.0,
            "position_iterations": iterations[0],
            "velocity_iterations": iterations[1],
        },
    }
    scenario = scenario_from_mapping(data, source=name)
    _assert_agree(scenario, simulate(scenario, "mujoco"), simulate(scenario, "reference"))


def _lift(solver: str, position_iterations: int, velocity_iterations: int) -> Scenario:
    data = {
        **LOAD_CASES["pendulum_lift"],
        "simulation": {
            "solver": solver,
            "dt": 0.005,
            "duration": 1.0,
            "position_iterations": position_iterations,
            "velocity_iterations": velocity_iterations,
        },
    }
    return scenario_from_mapping(data, source="lift")


def test_zero_velocity_iterations_agree_with_physx_rule() -> None:
    """TGS with 0 velocity iterations skips the re-clamp; PGS with 0 still runs one sweep, as PhysX does.

    Both engines follow the scenario's count: on the lifted pendulum TGS 4/0 ends 1.8e-3 rad/s from
    TGS 4/1 (its last substep's clamp is not redone at the step's total), PGS 1/0 is PGS 1/1 to the
    bit (PhysX runs max(1, velocity_iterations) sweeps).
    """
    runs = {}
    for key in (("tgs", 4, 0), ("tgs", 4, 1), ("pgs", 1, 0), ("pgs", 1, 1)):
        scenario = _lift(*key)
        mj, ref = simulate(scenario, "mujoco"), simulate(scenario, "reference")
        _assert_agree(scenario, mj, ref)
        runs[key] = mj
    apart = np.abs(runs["tgs", 4, 0].velocity - runs["tgs", 4, 1].velocity).max()
    assert apart > 1e-3
    np.testing.assert_array_equal(runs["pgs", 1, 0].velocity, runs["pgs", 1, 1].velocity)
    np.testing.assert_array_equal(runs["pgs", 1, 0].effort, runs["pgs", 1, 1].effort)


def test_tgs_speed_line_knife_edge() -> None:
    """Pin the one TGS edge case that differs: a drive on its speed line told to stop.

    With 4 substeps of 1.25 ms the per-substep gradient G/h = 1.6 (m/s)/(N*s) exceeds the response
    r = 0.5, so from |v| the drive can brake by at most (v_max - |v|)/(G/h - r) per substep: the
    plugin reaches 0.5 m/s exactly in float64 and never brakes, the reference stays 1e-16 below and
    lets go 80 steps in (real PhysX, float32, 6e-8 below: earlier still). PGS clamps once per step
    (G/dt = 0.4 < r) and all three agree.
    """
    data = {
        **CASES["prismatic_acceleration_drive"],
        "simulation": {"solver": "tgs", "dt": 0.005, "duration": 1.0, "position_iterations": 4},
    }
    scenario = scenario_from_mapping(data, source="knife")
    mj, ref = simulate(scenario, "mujoco"), simulate(scenario, "reference")
    assert mj.velocity[-1] == 0.5
    assert abs(ref.velocity[-1]) < 1e-3
    head = slice(0, 40)  # the approach, before either sits on the line
    np.testing.assert_allclose(mj.velocity[head], ref.velocity[head], rtol=0, atol=1e-12)


def test_cli_simulate_with_mujoco_engine(tmp_path: Path) -> None:
    """Write the mujoco engine's trajectory from the command line."""
    from drive_envelope._src.cli.main import main

    out = tmp_path / "run.csv"
    assert main(["simulate", str(PGS_FILES[0]), "--engine", "mujoco", "-o", str(out)]) == 0
    assert out.read_text().splitlines()[0] == "time,position,velocity,effort"


def test_a_diverging_run_stops_with_one_line_instead_of_a_silent_reset(tmp_path: Path) -> None:
    """Stop with an InputError when MuJoCo flags |v| > 1e10 (it used to reset to v = 0 and exit 0)."""
    from drive_envelope import InputError

    data = {
        "joint": {"type": "revolute", "inertia": 1e-6},
        "drive": {"stiffness": 0.0, "damping": 0.0, "max_effort": 0},
        "load": {"applied_effort": 1e9},
        "simulation": {"solver": "pgs", "dt": 0.01, "duration": 0.05, "position_iterations": 1},
    }
    scenario = scenario_from_mapping(data, source="runaway")
    with pytest.raises(
        InputError, match=r"MuJoCo stopped at step 1 \(t = 0.01 s\): Nan, Inf or huge value in Q(VEL|ACC)"
    ):
        simulate(scenario, "mujoco")
    from drive_envelope._src.cli.main import main

    file = tmp_path / "runaway.toml"
    file.write_text(
        '[joint]\ntype = "revolute"\ninertia = 1e-6\n[drive]\nstiffness = 0\ndamping = 0\nmax_effort = 0\n'
        "[load]\napplied_effort = 1e9\n[simulation]\nsolver = 'pgs'\ndt = 0.01\nduration = 0.05\n"
    )
    out = tmp_path / "run.csv"
    assert main(["simulate", str(file), "--engine", "mujoco", "-o", str(out)]) == 2
    assert not out.exists()


def test_an_inertia_below_mujocos_minimum_is_a_one_line_error() -> None:
    """Refuse joint.inertia < 1e-15 (MuJoCo's mjMINVAL) naming the key, instead of a compile traceback."""
    from drive_envelope import InputError

    data = {
        "joint": {"type": "revolute", "inertia": 1e-16},
        "drive": {"stiffness": 1.0, "damping": 0.1, "max_effort": 1},
        "simulation": {"solver": "pgs", "dt": 0.01, "duration": 0.05, "position_iterations": 1},
    }
    with pytest.raises(
        InputError, match=r"key 'joint.inertia' = 1e-16: the mujoco engine needs at least 1e-15"
    ):
        simulate(scenario_from_mapping(data, source="tiny"), "mujoco")


# -- bench loads (issue 16): pendulum, armature, friction, schedules ---------------------------------

LOAD_CASES: dict[str, dict[str, Any]] = {
    "free_pendulum": {
        "joint": {"inertia": 1e-3, "initial_position": 1.0},
        "drive": {"max_effort": 0},
        "pendulum": {"mass": 0.5, "distance": 0.1, "angle_offset": 0.2},
    },
    "pendulum_lift": {
        "joint": {"inertia": 1e-6, "armature": 1.6e-3},
        "drive": {"stiffness": 5.0, "damping": 0.05, "target_position": 1.5, "max_effort": 1.0},
        "envelope": {
            "max_actuator_velocity": 8.0,
            "velocity_dependent_resistance": 0.02,
            "speed_effort_gradient": 0.5,
        },
        "pendulum": {"mass": 0.5, "distance": 0.1},
    },
    "armature_step": {
        "joint": {"inertia": 1e-3, "armature": 4e-3},
        "drive": {"stiffness": 2.0, "damping": 0.05, "target_position": 0.5, "max_effort": 1.0},
        "envelope": {"max_actuator_velocity": 8.0, "velocity_dependent_resistance": 0.02},
        "load": {"external_effort": -0.3, "applied_effort": 0.1},
    },
    "coulomb_drive": {
        "joint": {"inertia": 1e-3},
        "drive": {"damping": 1.0, "target_velocity": 5.0, "max_effort": 1.0},
        "friction": {"static_friction": 0.2, "dynamic_friction": 0.2},
    },
    "coulomb_coast": {
        "joint": {"inertia": 1e-3, "initial_velocity": 3.0},
        "drive": {"max_effort": 0},
        "friction": {"static_friction": 0.05, "dynamic_friction": 0.05},
    },
    "pendulum_friction": {
        "joint": {"inertia": 1e-6, "armature": 1.6e-3, "initial_position": 0.8},
        "drive": {"max_effort": 0},
        "pendulum": {"mass": 0.49, "distance": 0.1},
        "friction": {"static_friction": 0.03, "dynamic_friction": 0.03},
    },
}


# a drive against Coulomb friction differs even at PGS 1/0: PhysX runs one more sweep (its drive then
# answers the friction within the step, 4.8 rad/s), MuJoCo solves drive then friction once (3.8)
_DRIVE_AGAINST_FRICTION = ("coulomb_drive",)


@pytest.mark.parametrize("name", sorted(set(LOAD_CASES) - set(_DRIVE_AGAINST_FRICTION)))
def test_bench_loads_agree_with_pgs_every_step(name: str) -> None:
    """Agree every step with PhysX PGS (one position, no velocity iteration): gravity, armature, Coulomb."""
    data = {
        **LOAD_CASES[name],
        "simulation": {
            "solver": "pgs",
            "dt": 0.005,
            "duration": 1.0,
            "position_iterations": 1,
            "velocity_iterations": 0,
        },
    }
    scenario = scenario_from_mapping(data, source=name)
    _assert_agree(scenario, simulate(scenario, "mujoco"), simulate(scenario, "reference"))


def test_pendulum_example_agrees_every_step() -> None:
    """Agree every step on the bundled pendulum scenario (PGS, one iteration)."""
    scenario = load_scenario(SCENARIOS / "loads" / "pendulum_swing.toml")
    _assert_agree(scenario, simulate(scenario, "mujoco"), simulate(scenario, "reference"))


def test_more_pgs_iterations_let_physx_answer_friction_within_the_step() -> None:
    """Show the documented difference: with 4+1 iterations PhysX's drive answers the friction.

    MuJoCo solves the actuator once, then friction: a damping drive against 0.2 N*m of Coulomb
    friction settles at 5 - 1.2 rad/s there (the drive never sees the friction), at 5 - 0.2 in
    PhysX with several iterations (and in the reference), as the closed forms say.
    """
    data = {
        **LOAD_CASES["coulomb_drive"],
        "friction": {"static_friction": 0.2, "dynamic_friction": 0.2},
        "simulation": {
            "solver": "pgs",
            "dt": 0.005,
            "duration": 1.0,
            "position_iterations": 4,
            "velocity_iterations": 1,
        },
    }
    scenario = scenario_from_mapping(data, source="iterations")
    mj, ref = simulate(scenario, "mujoco"), simulate(scenario, "reference")
    assert ref.velocity[-1] == pytest.approx(4.8, rel=1e-9)
    # PGS 1/0 too: PhysX reports the velocity of one more sweep, whose drive answers the friction
    data["simulation"] = {**data["simulation"], "position_iterations": 1, "velocity_iterations": 0}
    single = scenario_from_mapping(data, source="iterations")
    assert simulate(single, "reference").velocity[-1] == pytest.approx(4.8, rel=1e-9)
    assert simulate(single, "mujoco").velocity[-1] == pytest.approx(3.8, rel=1e-9)
    assert mj.velocity[-1] == pytest.approx(3.8, rel=1e-9)


def test_tgs_friction_parts_where_mujoco_solves_frictionloss_after_the_drive() -> None:
    """Pin the TGS friction difference: PhysX clips friction per substep inside the drive's sweep.

    MuJoCo's frictionloss is a constraint after the plugin's drive rows: the damping drive against
    0.2 N*m ends 0.59 rad/s below the reference on TGS 4/1 (3.96 against 4.55 rad/s), and a coasting
    joint stops at the same velocity but 5.6e-3 rad off (the plugin's substep positions never saw
    the friction).
    """
    sim = {"solver": "tgs", "dt": 0.005, "duration": 1.0, "position_iterations": 4, "velocity_iterations": 1}
    drive = scenario_from_mapping({**LOAD_CASES["coulomb_drive"], "simulation": sim}, source="drive")
    mj, ref = simulate(drive, "mujoco"), simulate(drive, "reference")
    assert ref.velocity[-1] - mj.velocity[-1] == pytest.approx(0.59, abs=0.01)
    coast = scenario_from_mapping({**LOAD_CASES["coulomb_coast"], "simulation": sim}, source="coast")
    mj, ref = simulate(coast, "mujoco"), simulate(coast, "reference")
    np.testing.assert_allclose(mj.velocity, ref.velocity, rtol=0, atol=1e-12)
    assert np.abs(mj.position - ref.position).max() == pytest.approx(5.6e-3, rel=0.01)


def test_break_away_above_sliding_friction_is_refused() -> None:
    """Refuse static_friction > dynamic_friction: MuJoCo's frictionloss is one Coulomb value."""
    from drive_envelope import InputError

    data = {**LOAD_CASES["coulomb_drive"], "friction": {"static_friction": 0.3, "dynamic_friction": 0.2}}
    with pytest.raises(
        InputError, match=r"'friction.static_friction' = 0.3: the mujoco engine has one Coulomb"
    ):
        simulate(scenario_from_mapping(data, source="breakaway"), "mujoco")


def test_schedule_with_unpowered_spans_agrees_every_step() -> None:
    """Replay per-step targets with the drive off for a while (zero gains), every step equal to PGS."""
    from drive_envelope._src.scenario.schedule import DriveSchedule

    data = {
        "joint": {"inertia": 1e-5, "armature": 1.6e-3},
        "drive": {"stiffness": 0.69, "damping": 0.03, "max_effort": 0.6},
        "envelope": {"max_actuator_velocity": 12.0, "velocity_dependent_resistance": 0.03},
        "pendulum": {"mass": 0.49, "distance": 0.1, "angle_offset": 0.016},
        # no friction: against a drive PhysX's extra velocity sweep answers it, MuJoCo's stand cannot
        "simulation": {
            "solver": "pgs",
            "dt": 0.005,
            "duration": 3.0,
            "position_iterations": 1,
            "velocity_iterations": 0,
        },
    }
    scenario = scenario_from_mapping(data, source="schedule")
    steps = scenario.simulation.steps
    t = np.arange(steps) * 0.005
    schedule = DriveSchedule(
        target_position=1.2 * np.sin(2 * np.pi * 0.5 * t),
        target_velocity=np.zeros(steps),
        enabled=~((t > 1.0) & (t < 2.0)),
    )
    mj = simulate(scenario, "mujoco", schedule=schedule)
    ref = simulate(scenario, "reference", schedule=schedule)
    _assert_agree(scenario, mj, ref)
    assert np.all(mj.effort[1:][~schedule.enabled] == 0.0)


def test_viscous_friction_is_implicit_damping_in_mujoco() -> None:
    """Decay as v0/(1+a)^n in MuJoCo (implicit joint damping) and v0*(1-a+a^2)^n in PhysX PGS(1, 0).

    ``a = c*dt/I``: PhysX clips a budget ``c*|v|*dt`` at the velocity before friction, and with 0
    velocity iterations still runs one more sweep, whose budget ``c*(1-a)*|v|*dt`` gives back
    ``a^2*v``; MuJoCo's Euler integrator damps the end-of-step velocity; they agree to O(a^2).
    """
    data = {
        "joint": {"inertia": 1e-3, "initial_velocity": 3.0},
        "drive": {"max_effort": 0},
        "friction": {"viscous_friction": 0.01},
        "simulation": {
            "solver": "pgs",
            "dt": 0.005,
            "duration": 0.5,
            "position_iterations": 1,
            "velocity_iterations": 0,
        },
    }
    scenario = scenario_from_mapping(data, source="viscous")
    mj, ref = simulate(scenario, "mujoco"), simulate(scenario, "reference")
    a = 0.01 * 0.005 / 1e-3
    n = np.arange(len(ref))
    np.testing.assert_allclose(ref.velocity, 3.0 * (1 - a + a * a) ** n, rtol=1e-12)
    np.testing.assert_allclose(mj.velocity, 3.0 / (1 + a) ** n, rtol=1e-12)

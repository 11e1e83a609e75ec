"""The ``newton`` engine of ``drive-envelope simulate`` against the ``reference`` engine.

The stand computes the drive as the scenario's PhysX solver iterates it (PGS sweeps or TGS
substeps, a Warp kernel with Newton's own joint response) and applies it as joint effort before
``SolverFeatherstone``'s step (``drive="physx"``, what ``simulate --engine newton`` runs). PGS
scenarios must agree at every step within the tolerances the mujoco engine meets (velocity 1e-5 +
5e-5*max|v|, effort 1e-4 + 1e-3*max_effort, position 1e-5 + 1e-4*path length); TGS scenarios within
real PhysX's float32 tolerance, 3e-3*max(1, max|column|): Newton's state is float32 as PhysX's is,
and braking along the speed line amplifies its rounding (step_response_tgs: 3.4e-4 rad/s, 1.07
times the float64 engines' tolerance; real PhysX itself 2.0e-3). Newton's own actuator stack
(``DrivePD`` + ``ClampingPerformanceEnvelope``, implicit, ``drive="actuator"``) is one solve per
step: held on PGS, and on TGS it warns.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _edge_scenarios import EDGE_CASES
from drive_envelope.errors import InputError
from drive_envelope.teststand import Scenario, Trajectory, load_scenario, scenario_from_mapping, simulate

pytestmark = pytest.mark.newton

SCENARIOS = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
PGS_FILES = sorted(SCENARIOS.glob("*_pgs.toml"))
TGS_FILES = sorted(
    file for file in SCENARIOS.glob("*.toml") if load_scenario(file).simulation.solver == "tgs"
)


def _actuator(scenario: Scenario) -> Trajectory:
    """The stand on Newton's own actuator stack (one implicit solve per step)."""
    from drive_envelope._src.adapters.newton.stand import simulate as stand

    return stand(scenario, drive="actuator")


def _assert_float32_agree(run: Trajectory, ref: Trajectory) -> None:
    """Real PhysX's tolerance (tests/test_teststand_physx.py): 3e-3 * max(1, max|column|)."""
    for column in ("velocity", "effort", "position"):
        expected = getattr(ref, column)
        tol = 3e-3 * max(1.0, float(np.abs(expected).max()))
        np.testing.assert_allclose(getattr(run, column), expected, rtol=0, atol=tol, err_msg=column)


def _assert_agree(scenario: Scenario, run: Trajectory, ref: Trajectory) -> None:
    max_effort = (
        scenario.drive.max_effort if np.isfinite(scenario.drive.max_effort) else np.abs(ref.effort).max()
    )
    path = np.abs(np.diff(ref.position)).sum()
    v_tol = 1e-5 + 5e-5 * np.abs(ref.velocity).max()
    e_tol = 1e-4 + 1e-3 * max_effort
    q_tol = 1e-5 + 1e-4 * path
    np.testing.assert_allclose(run.velocity, ref.velocity, rtol=0, atol=v_tol)
    np.testing.assert_allclose(run.effort, ref.effort, rtol=0, atol=e_tol)
    np.testing.assert_allclose(run.position, ref.position, rtol=0, atol=q_tol)


@pytest.mark.parametrize("file", PGS_FILES, ids=[f.stem for f in PGS_FILES])
def test_pgs_example_scenarios_agree_with_reference_every_step(file: Path) -> None:
    """Agree with the reference engine at every step on each shipped PGS scenario."""
    scenario = load_scenario(file)
    run, ref = simulate(scenario, "newton"), simulate(scenario, "reference")
    assert run.engine == "newton" and run.metadata["drive"] == "physx"
    _assert_agree(scenario, run, ref)
    actuator = _actuator(scenario)
    assert actuator.metadata["effort_mode"] == "implicit"
    _assert_agree(scenario, actuator, ref)


CASES: dict[str, dict[str, Any]] = {
    **EDGE_CASES,
    # the same prismatic drive stopping short of its speed limit (Newton cannot brake from it: below)
    "prismatic_acceleration_drive": {
        **EDGE_CASES["prismatic_acceleration_drive"],
        "drive": {**EDGE_CASES["prismatic_acceleration_drive"]["drive"], "target_position": 0.05},
    },
    "pendulum_with_armature": {
        "joint": {"type": "revolute", "inertia": 0.02, "armature": 0.01, "initial_position": 1.0},
        "drive": {"stiffness": 30.0, "damping": 2.0, "target_position": 1.5, "max_effort": 3},
        "envelope": {
            "max_actuator_velocity": 4.0,
            "velocity_dependent_resistance": 0.1,
            "speed_effort_gradient": 0.5,
        },
        "pendulum": {"mass": 2.0, "distance": 0.2, "angle_offset": 0.3},
    },
    "overspeed_lets_go_under_load": {
        "joint": {"type": "revolute", "inertia": 0.05, "initial_velocity": 4.0},
        "drive": {"damping": 5.0, "target_velocity": 0.0, "max_effort": 2},
        "envelope": {"max_actuator_velocity": 3.0, "speed_effort_gradient": 0.5},
        "load": {"external_effort": 0.5},
    },
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_pgs_edge_scenarios_agree_with_reference_every_step(name: str) -> None:
    """Agree on prismatic, acceleration, loads, plain, off, unlimited, pendulum + armature, overspeed."""
    data = {
        **CASES[name],
        "simulation": {"solver": "pgs", "dt": 1 / 120, "duration": 0.75, "position_iterations": 2},
    }
    scenario = scenario_from_mapping(data, source=name)
    ref = simulate(scenario, "reference")
    _assert_agree(scenario, simulate(scenario, "newton"), ref)
    if name != "prismatic_acceleration_drive":  # Newton's implicit solve cannot brake from v_max (below)
        _assert_agree(scenario, _actuator(scenario), ref)


def test_external_load_is_in_the_implicit_prediction() -> None:
    """Pass the external load to the implicit solve: under a braking load the drive sits on L(v_end)."""
    data = {
        "joint": {"type": "revolute", "inertia": 0.05},
        "drive": {"damping": 20.0, "target_velocity": 10.0, "max_effort": 2},
        "envelope": {"max_actuator_velocity": 3.0, "speed_effort_gradient": 0.5},
        "load": {"external_effort": -0.5},
        "simulation": {"solver": "pgs", "dt": 0.01, "duration": 1.0},
    }
    scenario = scenario_from_mapping(data, source="load")
    run = _actuator(scenario)
    env = scenario.effective_envelope()
    assert env is not None
    # saturated at every step: the effort is the envelope's limit at the END-of-step velocity
    limit = env.effort_limit(run.velocity[1:])
    np.testing.assert_allclose(run.effort[1:], limit, rtol=0, atol=1e-5)
    # and it settles where the drive balances the load on the speed line: v = 3 - 0.5 * 0.5
    assert run.velocity[-1] == pytest.approx(2.75, abs=1e-5)
    assert run.effort[-1] == pytest.approx(0.5, abs=1e-5)


def test_implicit_solve_cannot_brake_from_exactly_the_speed_limit() -> None:
    """Pin a difference of Newton's implicit mode: on the speed line with zero effort, p = 0 is a root.

    Newton solves ``p = dt * clip(drive(v(p)), -L(v(p)), L(v(p)))``. A joint exactly at
    max_actuator_velocity has ``L(v(0)) = 0``, so the zero impulse solves it and Newton's solve,
    warm-started there, stops: the drive cannot brake. PhysX takes the largest feasible impulse
    along the request and brakes (the reference does). In float32 a saturated joint reaches the
    speed limit exactly, so this happens whenever a drive that ran at top speed is told to stop.
    """
    data = {
        "joint": {"type": "prismatic", "inertia": 2.0},
        "drive": {
            "type": "acceleration",
            "stiffness": 400.0,
            "damping": 30.0,
            "target_position": 0.2,
            "max_effort": 50,
        },
        "envelope": {
            "max_actuator_velocity": 0.5,
            "velocity_dependent_resistance": 20.0,
            "speed_effort_gradient": 0.002,
        },
        "simulation": {"solver": "pgs", "dt": 1 / 120, "duration": 0.75},
    }
    scenario = scenario_from_mapping(data, source="stuck")
    from drive_envelope._src.errors import EngineWarning

    with pytest.warns(EngineWarning, match=r"let the drive go in 50 step\(s\)"):
        run = _actuator(scenario)
    ref = simulate(scenario, "reference")
    _assert_agree(scenario, simulate(scenario, "newton"), ref)  # PhysX's clamp, as the kernel runs it
    at_limit = int(np.argmax(run.velocity == np.float32(0.5)))
    assert at_limit > 0
    np.testing.assert_allclose(run.velocity[: at_limit + 1], ref.velocity[: at_limit + 1], atol=1e-5)
    assert np.all(run.velocity[at_limit:] == np.float32(0.5)) and np.all(run.effort[at_limit + 1 :] == 0.0)
    assert ref.velocity[-1] == pytest.approx(0.0, abs=2e-3) and ref.position[-1] == pytest.approx(
        0.2, abs=1e-3
    )


@pytest.mark.parametrize("file", TGS_FILES, ids=[f.stem for f in TGS_FILES])
def test_tgs_example_scenarios_agree_with_reference_every_step(file: Path) -> None:
    """Agree at every step on each shipped TGS scenario, transients included (float32 tolerance)."""
    scenario = load_scenario(file)
    run, ref = simulate(scenario, "newton"), simulate(scenario, "reference")
    assert run.metadata["drive_solver"] == "tgs"
    _assert_float32_agree(run, ref)
    # one solve per step would miss by up to 4 rad/s here (docs/parity.md): the test can fail
    assert np.abs(run.velocity - ref.velocity).max() < 3.5e-4


@pytest.mark.parametrize("iterations", [(4, 1), (4, 0), (2, 3)], ids=["4-1", "4-0", "2-3"])
@pytest.mark.parametrize("name", sorted(CASES))
def test_tgs_edge_scenarios_agree_with_reference_every_step(name: str, iterations: tuple[int, int]) -> None:
    """Agree on TGS with 4/1, 4/0 and 2/3 iterations: loads, plain, off, unlimited, pendulum, overspeed."""
    data = {
        **CASES[name],
        "simulation": {"solver": "tgs", "dt": 1 / 120, "duration": 0.75,
                       "position_iterations": iterations[0], "velocity_iterations": iterations[1]},
    }  # fmt: skip
    scenario = scenario_from_mapping(data, source=name)
    _assert_float32_agree(simulate(scenario, "newton"), simulate(scenario, "reference"))


def test_zero_velocity_iterations_agree_with_physx_rule() -> None:
    """TGS 4/0 skips the velocity re-clamp, PGS 1/0 runs one sweep anyway: Newton follows both counts."""
    runs = {}
    for solver, position, velocity in (("tgs", 4, 0), ("tgs", 4, 1), ("pgs", 1, 0), ("pgs", 1, 1)):
        data = {
            **CASES["pendulum_with_armature"],
            "simulation": {"solver": solver, "dt": 0.005, "duration": 1.0,
                           "position_iterations": position, "velocity_iterations": velocity},
        }  # fmt: skip
        scenario = scenario_from_mapping(data, source="lift")
        run = simulate(scenario, "newton")
        _assert_agree(scenario, run, simulate(scenario, "reference"))
        runs[solver, position, velocity] = run
    assert np.abs(runs["tgs", 4, 0].velocity - runs["tgs", 4, 1].velocity).max() > 1e-3
    np.testing.assert_array_equal(runs["pgs", 1, 0].velocity, runs["pgs", 1, 1].velocity)


def test_actuator_stack_on_tgs_warns_with_the_measured_size() -> None:
    """Newton's own actuator stack solves once per step: on TGS it warns once, and it does differ."""
    from drive_envelope._src.errors import EngineWarning

    scenario = load_scenario(SCENARIOS / "step_response_tgs.toml")
    with pytest.warns(EngineWarning, match=r"once per step, PhysX's TGS per substep"):
        run = _actuator(scenario)
    assert np.abs(run.velocity - simulate(scenario, "reference").velocity).max() > 1.0


def test_refuses_what_float32_cannot_hold() -> None:
    """Refuse friction (no Newton model), a tiny inertia and a gain beyond float32, naming the key."""
    rubbing = scenario_from_mapping(
        {"joint": {"inertia": 1.0}, "friction": {"static_friction": 0.1}}, source="rub"
    )
    with pytest.raises(InputError, match=r"--engine newton: this engine does not represent \[friction\]"):
        simulate(rubbing, "newton")  # the engine registry refuses it: the module does not list it
    from drive_envelope._src.adapters.newton.stand import simulate as stand

    with pytest.raises(InputError, match=r"\[friction\]: the newton engine has no PhysX joint friction"):
        stand(rubbing)  # and the adapter, called directly
    tiny = scenario_from_mapping({"joint": {"inertia": 1e-20}}, source="tiny")
    with pytest.raises(InputError, match=r"key 'joint.inertia' = 1e-20: the newton engine needs at least"):
        simulate(tiny, "newton")
    stiff = scenario_from_mapping({"joint": {"inertia": 1.0}, "drive": {"stiffness": 1e35}}, source="stiff")
    with pytest.raises(InputError, match=r"key 'drive.stiffness' = 1e\+35"):
        simulate(stiff, "newton")


def test_cli_simulate_with_newton_engine_keeps_stdout_clean(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """Write the newton engine's trajectory from the command line, with nothing of Warp's on stdout."""
    from drive_envelope._src.cli.main import main

    out = tmp_path / "run.csv"
    assert main(["simulate", str(PGS_FILES[0]), "--engine", "newton", "-o", str(out)]) == 0
    assert out.read_text().splitlines()[0] == "time,position,velocity,effort"
    assert main(["simulate", str(PGS_FILES[0]), "--engine", "newton"]) == 0
    lines = capfd.readouterr().out.splitlines()
    assert lines[0] == "time,position,velocity,effort" and all(line[0].isdigit() for line in lines[1:])


def test_a_drive_let_go_beyond_the_speed_line_is_a_warning() -> None:
    """From rest, a load that alone would pass max_actuator_velocity in one step: Newton's p = 0 root.

    10 N*m on 0.001 kg*m^2 for 5 ms gives 50 rad/s, beyond the AK80-6's 37.7 rad/s: Newton lets the
    drive go at the first step, where PhysX and the reference brake and hold the joint; from the
    next step on the joint is too fast for any braking within the envelope (PhysX would let go too),
    so one step is counted, in one EngineWarning.
    """
    from drive_envelope._src.errors import EngineWarning

    data = {
        "joint": {"inertia": 0.001},
        "drive": {"stiffness": 50.0, "damping": 2.0},
        "envelope": {"datasheet": "tmotor-ak80-6"},
        "load": {"external_effort": -10.0},
        "simulation": {"solver": "pgs", "dt": 0.005, "duration": 0.1, "position_iterations": 1,
                       "velocity_iterations": 0},
    }  # fmt: skip
    scenario = scenario_from_mapping(data, source="runaway")
    with pytest.warns(EngineWarning, match=r"let the drive go in 1 step\(s\), first at t = 0\.005 s"):
        run = _actuator(scenario)
    ref = simulate(scenario, "reference")
    _assert_agree(scenario, simulate(scenario, "newton"), ref)  # the kernel brakes and holds
    assert np.all(run.effort[1:] == 0.0) and abs(run.velocity[-1]) > 100.0
    assert np.abs(ref.velocity).max() < 37.7 and abs(ref.velocity[-1]) < 1.0  # braked and held
    assert np.all(ref.effort[1:] > 5.0)


@pytest.mark.parametrize("file", PGS_FILES, ids=lambda p: p.stem)
def test_runs_that_agree_with_physx_draw_no_warning(file: Path) -> None:
    import warnings

    from drive_envelope._src.errors import EngineWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error", EngineWarning)
        simulate(load_scenario(file), "newton")


def test_cli_on_a_tgs_scenario_says_nothing_and_ends_at_real_physx(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``simulate --engine newton`` on the TGS actuator_swing: no warning, real PhysX's 0.12655 rad/s."""
    from drive_envelope._src.cli.main import main

    out = tmp_path / "swing.csv"
    assert (
        main(["simulate", str(SCENARIOS / "actuator_swing.toml"), "--engine", "newton", "-o", str(out)]) == 0
    )
    assert "TGS" not in capsys.readouterr().err
    header, *_, last = out.read_text().splitlines()
    assert float(last.split(",")[header.split(",").index("velocity")]) == pytest.approx(0.12655, abs=1e-4)

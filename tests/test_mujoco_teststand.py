"""The ``mujoco`` engine of ``drive-envelope simulate`` against the ``reference`` engine.

PGS scenarios must agree at every step within the issue's tolerances (velocity 1e-5 + 5e-5*max|v|,
effort 1e-4 + 1e-3*max_effort, position 1e-5 + 1e-4*path length): one implicit solve per step is
what PGS does for an isolated DOF. TGS integrates and clamps per substep, so transients differ;
where the drive runs on the envelope (saturated at max_actuator_velocity, or at a constant load)
velocity and effort still agree.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drive_envelope.teststand import Scenario, Trajectory, load_scenario, scenario_from_mapping, simulate

pytestmark = pytest.mark.mujoco

SCENARIOS = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
PGS_FILES = sorted(SCENARIOS.glob("*_pgs.toml"))


@pytest.fixture(scope="module", autouse=True)
def plugin() -> None:
    pytest.importorskip("mujoco")
    from drive_envelope._src.adapters.mujoco import build, loader

    try:
        loader.load_plugin()
    except build.PluginError:
        build.build_plugin(quiet=True)  # `make setup` normally built it
        loader.load_plugin()


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


CASES: dict[str, dict[str, Any]] = {
    "prismatic_acceleration_drive": {
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
    },
    "applied_and_external_effort": {
        "joint": {"type": "revolute", "inertia": 0.02, "initial_velocity": -2.0},
        "drive": {
            "stiffness": 50.0,
            "damping": 1.0,
            "target_position": -1.0,
            "target_velocity": 0.5,
            "max_effort": 4,
        },
        "envelope": {
            "max_actuator_velocity": 6.0,
            "velocity_dependent_resistance": 0.3,
            "speed_effort_gradient": 0.2,
        },
        "load": {"applied_effort": 1.5, "external_effort": -0.8},
    },
    "stiff_step_plain_drive": {
        "joint": {"type": "revolute", "inertia": 0.01},
        "drive": {"stiffness": 5000.0, "damping": 10.0, "target_position": 1.0, "max_effort": 20},
        "load": {"applied_effort": 5.0},
    },
    "drive_off_applied_only": {
        "joint": {"type": "revolute", "inertia": 0.1},
        "drive": {"stiffness": 10.0, "damping": 1.0, "target_position": 1.0, "max_effort": 0},
        "load": {"applied_effort": 0.7},
    },
    "unlimited_drive": {
        "joint": {"type": "prismatic", "inertia": 1.0},
        "drive": {"stiffness": 100.0, "damping": 5.0, "target_position": -0.3},
    },
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_pgs_edge_scenarios_agree_with_reference_every_step(name: str) -> None:
    """Agree on prismatic, acceleration, applied/external effort, plain, off and unlimited drives."""
    data = {
        **CASES[name],
        "simulation": {"solver": "pgs", "dt": 1 / 120, "duration": 0.75, "position_iterations": 2},
    }
    scenario = scenario_from_mapping(data, source=name)
    _assert_agree(scenario, simulate(scenario, "mujoco"), simulate(scenario, "reference"))


@pytest.mark.parametrize("stem", ["velocity_saturation_tgs", "constant_load_tgs", "overspeed_release_tgs"])
def test_tgs_agrees_where_the_drive_runs_on_the_envelope(stem: str) -> None:
    """Match velocity and effort on TGS steps where the drive sits on the envelope boundary."""
    scenario = load_scenario(SCENARIOS / f"{stem}.toml")
    mj, ref = simulate(scenario, "mujoco"), simulate(scenario, "reference")
    env = scenario.effective_envelope()
    assert env is not None
    effort_margin, velocity_margin = env.margins(ref.velocity, ref.effort)
    on_boundary = (np.minimum(effort_margin, velocity_margin) < 1e-6) | (ref.effort == 0.0)
    on_boundary[0] = False
    assert on_boundary.sum() > 10
    v_tol = 1e-5 + 5e-5 * np.abs(ref.velocity).max()
    e_tol = 1e-4 + 1e-3 * env.max_effort
    np.testing.assert_allclose(mj.velocity[on_boundary], ref.velocity[on_boundary], rtol=0, atol=v_tol)
    np.testing.assert_allclose(mj.effort[on_boundary], ref.effort[on_boundary], rtol=0, atol=e_tol)


def test_tgs_transient_differs_by_per_substep_integration() -> None:
    """Show the documented TGS difference: a stiff step response's transient is not one solve per step."""
    scenario = load_scenario(SCENARIOS / "step_response_tgs.toml")
    mj, ref = simulate(scenario, "mujoco"), simulate(scenario, "reference")
    assert np.abs(mj.velocity - ref.velocity).max() > 1e-2
    assert mj.metadata["note"].endswith("so transients differ")


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

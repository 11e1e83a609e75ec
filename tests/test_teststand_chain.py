"""Chain scenarios and the reference engine for chains (fast; no engine needed).

Golden values are closed forms: a pendulum's and a two-link planar arm's mass matrix and gravity
efforts from the textbook formulas, and the one-joint reference engine on a chain of one.
"""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain import (
    ChainJoint,
    ChainScenario,
    chain_from_mapping,
    chain_from_scenario,
    load_stand,
)
from drive_envelope._src.scenario.spec import SimulationSpec, scenario_from_mapping
from drive_envelope._src.teststand.engines import simulate
from drive_envelope._src.teststand.engines.chain import simulate_chain
from drive_envelope._src.teststand.engines.chain_dynamics import ChainModel

EXAMPLES = Path(__file__).parent.parent / "examples" / "scenarios"
ARMS = sorted((EXAMPLES / "chains").glob("arm3_*.toml"))


def _two_link(q2: float) -> tuple[ChainScenario, float, float, float]:
    m1, m2, l1, c1, c2, i1, i2 = 2.0, 1.5, 0.4, 0.2, 0.25, 0.03, 0.02
    joints = (
        ChainJoint(name="a", axis="y", mass=m1, com=(c1, 0.0, 0.0), inertia=(0.01, i1, 0.01)),
        ChainJoint(name="b", axis="y", parent=0, origin=(l1, 0.0, 0.0), mass=m2, com=(c2, 0.0, 0.0),
                   inertia=(0.01, i2, 0.01), armature=0.005),
    )  # fmt: skip
    scenario = ChainScenario(joints=joints, simulation=SimulationSpec(gravity=9.81))
    m11 = i1 + i2 + m1 * c1**2 + m2 * (l1**2 + c2**2 + 2 * l1 * c2 * math.cos(q2))
    m12 = i2 + m2 * (c2**2 + l1 * c2 * math.cos(q2))
    m22 = i2 + m2 * c2**2 + 0.005
    return scenario, m11, m12, m22


@pytest.mark.parametrize("q2", [0.0, 0.7, -2.1])
def test_two_link_mass_matrix_matches_the_closed_form(q2: float) -> None:
    scenario, m11, m12, m22 = _two_link(q2)
    model = ChainModel(scenario)
    matrix = model.mass_matrix(model.kinematics(np.array([0.3, q2])))
    np.testing.assert_allclose(matrix, [[m11, m12], [m12, m22]], rtol=1e-13)


def test_bias_is_gravity_and_coriolis_of_the_closed_form() -> None:
    scenario, *_ = _two_link(0.0)
    model = ChainModel(scenario)
    q, v = np.array([0.3, 0.8]), np.array([1.2, -0.7])
    # positive rotation about Y lowers +X: gravity's effort helps, h = -m*g*lever*cos(angle)
    g, m1, m2, l1, c1, c2 = 9.81, 2.0, 1.5, 0.4, 0.2, 0.25
    gravity = np.array(
        [
            -(m1 * c1 + m2 * l1) * g * math.cos(q[0]) - m2 * c2 * g * math.cos(q[0] + q[1]),
            -m2 * c2 * g * math.cos(q[0] + q[1]),
        ]
    )
    hh = -m2 * l1 * c2 * math.sin(q[1])
    coriolis = np.array([hh * (2 * v[0] * v[1] + v[1] ** 2), -hh * v[0] ** 2])
    np.testing.assert_allclose(model.bias(model.kinematics(q), v), gravity + coriolis, rtol=1e-12)


ONE_JOINT = {
    "joint": {"type": "revolute", "inertia": 0.002, "armature": 0.001, "initial_position": 0.4},
    "drive": {"stiffness": 3.0, "damping": 0.05, "target_position": 2.0, "max_effort": 0.4},
    "envelope": {"max_actuator_velocity": 6.0, "velocity_dependent_resistance": 0.02},
    "pendulum": {"mass": 0.3, "distance": 0.1, "angle_offset": 0.2},
    "friction": {"static_friction": 0.03, "dynamic_friction": 0.02, "viscous_friction": 0.004},
    "load": {"applied_effort": 0.05},
}


@pytest.mark.parametrize("solver", [("pgs", 1, 0), ("pgs", 3, 2), ("tgs", 4, 1), ("tgs", 2, 0)])
def test_one_joint_scenario_is_a_chain_of_one(solver: tuple[str, int, int]) -> None:
    name, pos, vel = solver
    simulation = {"dt": 0.005, "duration": 1.0, "solver": name, "position_iterations": pos,
                  "velocity_iterations": vel}  # fmt: skip
    scenario = scenario_from_mapping({**ONE_JOINT, "simulation": simulation}, default_name="bench")
    one = simulate(scenario)
    chain = simulate_chain(chain_from_scenario(scenario))
    np.testing.assert_allclose(chain.velocity[:, 0], one.velocity, rtol=0, atol=1e-11)
    np.testing.assert_allclose(chain.position[:, 0], one.position, rtol=0, atol=1e-11)
    np.testing.assert_allclose(chain.effort[:, 0], one.effort, rtol=0, atol=1e-9)
    assert np.ptp(one.velocity) > 1.0  # it moved: the pendulum, drive and friction all act


def test_arm_examples_load_and_release_at_the_speed_line() -> None:
    assert [path.stem for path in ARMS] == ["arm3_pgs_1_0", "arm3_tgs_4_1"]
    for path in ARMS:
        scenario = load_stand(path)
        assert isinstance(scenario, ChainScenario) and scenario.names == ("shoulder", "elbow", "wrist")
        assert scenario.is_chain and scenario.simulation.steps == 240
        run = simulate(scenario)
        shoulder = run.joint("shoulder")
        # the shoulder pushes below its 1 rad/s line, then PhysX's clamp lets go (zero effort)
        released = int(np.flatnonzero(np.abs(shoulder.effort[1:]) < 0.02)[0]) + 1
        assert released == 12
        assert np.all(shoulder.velocity[1:released] < 1.0) and shoulder.velocity[released + 1] > 1.0
        assert np.all(shoulder.effort[1:released] > 0.02)


def test_chain_file_errors_name_the_key(tmp_path: Path) -> None:
    base = {"simulation": {"dt": 0.01, "duration": 0.1}}
    joint = {"name": "a", "mass": 1.0, "inertia": [0.1, 0.1, 0.1]}
    cases = [
        ({"joints": [joint, {**joint, "name": "b", "parent": "c"}]}, "joints[1].parent"),
        ({"joints": [{"name": "a", "inertia": [1, 1, 1]}]}, "joints[0].mass"),
        ({"joints": [{**joint, "inertia": [1, 1]}]}, "joints[0].inertia"),
        ({"joints": [{**joint, "axis": "w"}]}, "joints[0].axis"),
        ({"joints": [{**joint, "drive": {"stiffnes": 1.0}}]}, "joints[0].drive.stiffnes"),
        ({"joints": [{**joint, "envelope": {"max_actuator_velocity": -1}, "drive": {"max_effort": 1}}]},
         "joints[0].envelope.max_actuator_velocity"),
        ({"joints": [joint, joint]}, "used twice"),
        ({"joints": []}, "joints"),
    ]  # fmt: skip
    for data, key in cases:
        with pytest.raises(InputError, match=key.replace("[", r"\[").replace("]", r"\]")) as info:
            chain_from_mapping({**base, **data}, source="arm.toml")
        assert str(info.value).startswith("arm.toml") and "\n" not in str(info.value)


def test_simulate_cli_writes_a_chain_and_refuses_engines_without_chains(tmp_path: Path) -> None:
    out = tmp_path / "arm.csv"
    cli = [sys.executable, "-m", "drive_envelope", "simulate", str(ARMS[0])]
    done = subprocess.run([*cli, "-o", str(out)], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    header = out.read_text().splitlines()[0].split(",")
    assert header[:4] == ["time", "shoulder.position", "shoulder.velocity", "shoulder.effort"]
    assert len(out.read_text().splitlines()) == 242
    refused = subprocess.run([*cli, "--engine", "newton"], capture_output=True, text=True, check=False)
    import importlib.util

    expected = "chain scenarios" if importlib.util.find_spec("newton") else "needs the Python package"
    assert refused.returncode == 2 and expected in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


def test_chain_validation() -> None:
    joint = ChainJoint(name="a", mass=1.0, inertia=(1.0, 1.0, 1.0))
    with pytest.raises(InputError, match="earlier joint"):
        ChainScenario(joints=(dataclasses.replace(joint, parent=0),))
    with pytest.raises(InputError, match="inertia"):
        ChainJoint(name="a", mass=1.0, inertia=(1.0, 0.0, 1.0))

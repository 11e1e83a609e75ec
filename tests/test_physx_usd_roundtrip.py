"""PhysX itself reads back what ``drive_envelope.usd`` writes (real PhysX through ovphysx 0.7, CPU).

maxForce, the drive gains and the three envelope values are read from PhysX's joint properties
(ovphysx 0.7's ``ARTICULATION_JOINT`` attributes ``jointMaxForce``, ``jointStiffness``,
``jointMaxActuatorVelocity``, ``jointVelocityDependentResistance``, ``jointSpeedEffortGradient``:
live PhysX state, angular values folded back to degrees as USD stores them). The envelope is also
read from PhysX's behaviour against closed forms (SEMANTICS.md): the velocity settles exactly on
maxActuatorVelocity, the first step from rest exerts ``maxEffort / (1 + r*R*dt)``, and against a
constant load ``L`` the speed settles on ``maxActuatorVelocity - speedEffortGradient*L``. They run
in a centimetre-gram stage, so the degree conversion and the stage-unit scaling are both exercised
(the parity tests use SI stages).
"""

from __future__ import annotations

import math
import shutil
import warnings
from pathlib import Path

import pytest

from drive_envelope import PerformanceEnvelope
from drive_envelope._src.scenario.spec import DriveSpec, JointSpec, LoadSpec, Scenario, SimulationSpec

pytestmark = [pytest.mark.physx, pytest.mark.usd]

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
DT = 1.0 / 240.0


def _scenario(joint: str, envelope: PerformanceEnvelope, inertia: float, load: float = 0.0) -> Scenario:
    return Scenario(
        name=joint,
        joint=JointSpec(type=joint, inertia=inertia),  # type: ignore[arg-type]
        drive=DriveSpec(damping=1.0e3, target_velocity=100.0, max_effort=envelope.max_effort),
        envelope=envelope,
        load=LoadSpec(external_effort=load),
        simulation=SimulationSpec(
            dt=DT, duration=0.25, solver="pgs", position_iterations=4, velocity_iterations=1
        ),
    )


REVOLUTE = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=6.0, velocity_dependent_resistance=0.4)
GRADIENT = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=6.0, speed_effort_gradient=0.1)
PRISMATIC = PerformanceEnvelope(
    joint="prismatic", max_effort=80.0, max_actuator_velocity=0.8, velocity_dependent_resistance=20.0
)
CASES = [
    _scenario("revolute", REVOLUTE, 0.05),
    _scenario("revolute", GRADIENT, 0.05, load=-2.0),
    _scenario("prismatic", PRISMATIC, 2.0),
]


@pytest.fixture(scope="module")
def runs() -> list[object]:
    """The cases in a centimetre-gram stage (the parity tests cover SI stages)."""
    from drive_envelope._src.adapters.physx.stand import simulate_many
    from drive_envelope.usd import StageUnits

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate_many(CASES, units=StageUnits(meters_per_unit=0.01, kilograms_per_unit=0.001))  # type: ignore[return-value]


def test_velocity_settles_on_max_actuator_velocity(runs: list[object]) -> None:
    """Read maxActuatorVelocity (degrees on angular drives, stage units on linear ones)."""
    assert runs[0].velocity[-1] == pytest.approx(6.0, rel=2e-6)  # type: ignore[attr-defined]
    assert runs[2].velocity[-1] == pytest.approx(0.8, rel=2e-6)  # type: ignore[attr-defined]


def test_first_step_effort_reads_resistance(runs: list[object]) -> None:
    """Read velocityDependentResistance from the first step's effort maxEffort/(1 + r*R*dt)."""
    assert runs[0].effort[1] == pytest.approx(10.0 / (1.0 + 0.4 * DT / 0.05), rel=2e-6)  # type: ignore[attr-defined]
    assert runs[2].effort[1] == pytest.approx(80.0 / (1.0 + 20.0 * DT / 2.0), rel=2e-6)  # type: ignore[attr-defined]


def test_loaded_speed_reads_speed_effort_gradient(runs: list[object]) -> None:
    """Read speedEffortGradient from the loaded steady speed v_max - G*L = 6 - 0.1*2."""
    trajectory = runs[1]
    assert trajectory.velocity[-1] == pytest.approx(5.8, rel=2e-6)  # type: ignore[attr-defined]
    assert trajectory.effort[-1] == pytest.approx(2.0, rel=1e-4)  # type: ignore[attr-defined]


@pytest.fixture(scope="module")
def robot_dofs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, float]]:
    """What PhysX loaded for the example robot after ``drive-envelope usd apply --map``."""
    from drive_envelope._src.adapters.physx.runner import inspect_drives
    from drive_envelope._src.cli.main import main

    folder = tmp_path_factory.mktemp("robot")
    (folder / "usd").mkdir()
    (folder / "envelopes").mkdir()
    for name in ("robot.usda", "map.toml", "linear_actuator.toml"):
        shutil.copy(EXAMPLES / "usd" / name, folder / "usd" / name)
    shutil.copy(EXAMPLES / "envelopes" / "demo.toml", folder / "envelopes" / "demo.toml")
    robot, out = folder / "usd" / "robot.usda", folder / "robot_env.usda"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        argv = ["usd", "apply", str(robot), "--map", str(robot.with_name("map.toml")), "--output", str(out)]
        assert main(argv) == 0
    return inspect_drives(out)


def test_physx_loads_max_force_and_gains_of_applied_robot(robot_dofs: dict[str, dict[str, float]]) -> None:
    """Find maxForce in stage units and the per-degree gains as authored in PhysX's joint properties."""
    shoulder, slide = robot_dofs["/Robot/joints/shoulder"], robot_dofs["/Robot/joints/slide"]
    # centimetre stage: torques in kg*cm^2/s^2 (1e4 per N*m), forces in kg*cm/s^2 (100 per N)
    assert shoulder["max_force"] / 1e4 == pytest.approx(12.05568, rel=1e-6)
    assert slide["max_force"] / 1e2 == pytest.approx(120.0, rel=1e-6)
    # ovphysx 0.7 reports angular gains per degree, as USD stores them (the example writes 2)
    assert shoulder["stiffness"] == pytest.approx(2.0, rel=1e-6)


def test_physx_loads_envelope_of_applied_robot(robot_dofs: dict[str, dict[str, float]]) -> None:
    """Read the three envelope values back from PhysX's joint properties and convert them to SI."""
    deg = math.pi / 180.0
    shoulder, slide = robot_dofs["/Robot/joints/shoulder"], robot_dofs["/Robot/joints/slide"]
    # demo.toml: 360 rpm = 37.699 rad/s, G = 0.570248 (rad/s)/(N*m) (see `drive-envelope usd show`);
    # angular values come back per degree, torques in kg*cm^2/s^2 (1e4 per N*m)
    assert shoulder["max_actuator_velocity"] * deg == pytest.approx(12.0 * math.pi, rel=1e-6)
    assert shoulder["speed_effort_gradient"] * deg * 1e4 == pytest.approx(0.570248, rel=1e-5)
    assert shoulder["velocity_dependent_resistance"] == 0.0
    # linear_actuator.toml: 0.25 m/s = 25 cm/s; 40 N*s/m = 40 kg/s, the same number in kg-cm-s
    assert slide["max_actuator_velocity"] == pytest.approx(25.0, rel=1e-6)
    assert slide["velocity_dependent_resistance"] == pytest.approx(40.0, rel=1e-6)
    assert slide["speed_effort_gradient"] == 0.0

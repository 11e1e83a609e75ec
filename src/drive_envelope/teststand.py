"""The test stand: one actuated joint simulated with PhysX's drive and performance envelope.

``load_scenario("stand.toml", overrides=["drive.target_velocity=12"])`` reads a scenario file,
``simulate(scenario, engine="reference")`` runs it and returns a :class:`Trajectory` (time,
position, velocity and the step-average total actuator effort, SI), which ``save_trajectory`` writes
as CSV, JSON or Parquet. A run of more than ``max_steps`` steps (:data:`MAX_STEPS` by default) is
refused before it starts. The ``reference`` engine is a float64 NumPy model of the PhysX articulation solver
(PGS and TGS); ``mujoco`` and ``physx`` need their extras.

A multi-DOF stand: a file with a ``[[joints]]`` list is a :class:`ChainScenario` (a fixed-base
chain or tree of driven links under gravity; ``load_stand`` reads either kind), run by the
``reference`` engine (PhysX's articulation solver: Gauss-Seidel drive rows root to leaf) and
``physx``, giving a :class:`ChainTrajectory`. ``urdf_joints(path)`` reads a URDF robot's joints
as ``[[joints]]`` entries (``drive_envelope.mujoco.mjcf_joints`` an MJCF's).

A bench's loads: :class:`PendulumSpec` (a point mass pulled by gravity), :class:`FrictionSpec`
(PhysX 5.6 joint friction: static, dynamic, viscous) and ``JointSpec.armature``; a
:class:`DriveSchedule` replays per-step drive targets and power states (``simulate(..., schedule=)``).
"""

from __future__ import annotations

from drive_envelope._src.scenario.chain import (
    ChainJoint,
    ChainScenario,
    chain_from_scenario,
    load_chain_scenario,
    load_stand,
)
from drive_envelope._src.scenario.chain_trajectory import ChainTrajectory, save_chain_trajectory
from drive_envelope._src.scenario.import_urdf import urdf_joints
from drive_envelope._src.scenario.loads import STANDARD_GRAVITY, FrictionSpec, PendulumSpec
from drive_envelope._src.scenario.schedule import DriveSchedule
from drive_envelope._src.scenario.spec import (
    DriveSpec,
    JointSpec,
    LoadSpec,
    Scenario,
    SimulationSpec,
    load_scenario,
    scenario_from_mapping,
)
from drive_envelope._src.scenario.trajectory import (
    Trajectory,
    read_trajectory,
    save_trajectory,
    trajectory_to_csv,
    trajectory_to_json,
)
from drive_envelope._src.teststand.engines import ENGINES, MAX_STEPS, engine_names, simulate

__all__ = [
    "ENGINES",
    "MAX_STEPS",
    "STANDARD_GRAVITY",
    "ChainJoint",
    "ChainScenario",
    "ChainTrajectory",
    "DriveSchedule",
    "DriveSpec",
    "FrictionSpec",
    "JointSpec",
    "LoadSpec",
    "PendulumSpec",
    "Scenario",
    "SimulationSpec",
    "Trajectory",
    "chain_from_scenario",
    "engine_names",
    "load_chain_scenario",
    "load_scenario",
    "load_stand",
    "read_trajectory",
    "save_chain_trajectory",
    "save_trajectory",
    "scenario_from_mapping",
    "simulate",
    "trajectory_to_csv",
    "trajectory_to_json",
    "urdf_joints",
]

"""A chain scenario on real PhysX (the ``ovphysx`` 0.7 wheel, CPU): the ``physx`` engine for chains.

The scenario is authored as a USD articulation (:mod:`~drive_envelope._src.adapters.physx.chain_scene`)
and stepped by PhysX in this process with the one-joint stand's set-up
(:mod:`~drive_envelope._src.adapters.physx.runner`): the initial joint state is written and the link
poses updated, then per step the applied joint efforts (``jointActuationForce``) and the external
joint efforts (a torque, or a force, on the link and its opposite on the parent: a pure joint
effort) are written, PhysX steps, and every joint's ``jointPosition``, ``jointVelocity`` and
``jointProjectedForce`` are read (degrees on revolute joints, converted here).

The projected force is what the joint passes to its link, not the drive's effort (ovphysx 0.7 has
no drive-force read): on a chain it also carries the links' weight and motion, so the effort
columns of a physx chain run hold it as it is and ``metadata["effort_source"]`` says so.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from drive_envelope._src.adapters.physx.chain_scene import (
    CHAIN_PATH,
    build_chain_stage,
    joint_path,
    link_path,
    zero_pose,
)
from drive_envelope._src.adapters.physx.runner import _STATE, _attached, _physx, _row, _sample, _write
from drive_envelope._src.adapters.physx.stand import check_time_step
from drive_envelope._src.scenario.chain import ChainScenario
from drive_envelope._src.scenario.chain_frames import rotate
from drive_envelope._src.scenario.chain_trajectory import ChainTrajectory, chain_run

EFFORT_SOURCE = (
    "PhysX jointProjectedForce: the joint force projected on each DOF, which on a chain also carries "
    "the links' weight and motion (ovphysx 0.7 has no read of the drive's own force)"
)
"""What the ``effort`` columns of a physx chain run hold."""


def simulate_chain(scenario: ChainScenario) -> ChainTrajectory:
    """Run a chain scenario on PhysX (float32: agreement with ``reference`` to float32 precision).

    Raises:
        InputError: a time step PhysX cannot take, or ovphysx
            (>= 0.7) / physx-usd-schemas missing.
        DriveEnvelopeError: PhysX itself failed.
    """
    check_time_step(scenario)
    stage = build_chain_stage(scenario)  # held: the layer dies with the stage
    usda = stage.GetRootLayer().ExportToString()
    with _physx() as physx, _attached(physx, usda=usda):
        position, velocity, effort = _step(physx, scenario)
    return chain_run(
        scenario, "physx", position, velocity, effort, precision="float32", effort_source=EFFORT_SOURCE
    )


def _step(physx: Any, scenario: ChainScenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from ovphysx.types import SimObjectType

    joint_type, link_type = SimObjectType.ARTICULATION_JOINT, SimObjectType.ARTICULATION_LINK
    joints = scenario.joints
    paths = [joint_path(joint) for joint in joints]
    # revolute DOFs are read and written in degrees
    scale = np.array([math.degrees(1.0) if joint.type == "revolute" else 1.0 for joint in joints])
    physx.warmup()
    for joint, path, factor in zip(joints, paths, scale, strict=True):
        _write(physx, joint_type, "jointPosition", path, _row(joint.initial_position * factor))
        _write(physx, joint_type, "jointVelocity", path, _row(joint.initial_velocity * factor))
    physx.update_articulations_kinematic(pattern=CHAIN_PATH)
    applied = [(path, _row(j.load.applied_effort)) for j, path in zip(joints, paths, strict=True)
               if j.load.applied_effort != 0.0]  # fmt: skip
    wrenches = _external_wrenches(scenario)
    steps = scenario.simulation.steps
    samples = np.zeros((3, steps + 1, len(joints)))
    samples[:2, 0] = _sample(physx, _STATE[:2], paths)
    for i in range(1, steps + 1):
        for path, row in applied:
            _write(physx, joint_type, "jointActuationForce", path, row)
        for path, wrench in wrenches.items():
            _write(physx, link_type, "wrench", path, wrench)
        physx.step_sync(scenario.simulation.dt)
        samples[:, i] = _sample(physx, _STATE, paths)
    samples[:2] /= scale
    return samples[0], samples[1], samples[2]


def _external_wrenches(scenario: ChainScenario) -> dict[str, np.ndarray]:
    """Link wrenches ``[force, torque, point]`` (world) that make each joint's external effort.

    The effort acts on the link along (about) the joint axis at zero pose, and its opposite on
    the parent link, so it is a pure joint effort (the fixed base takes no write). A constant
    world-frame wrench is exact for joints whose axis does not turn, as in planar chains.
    """
    wrenches: dict[str, np.ndarray] = {}
    for joint, (orient, _) in zip(scenario.joints, zero_pose(scenario), strict=True):
        effort = joint.load.external_effort
        if effort == 0.0:
            continue
        wrench = np.zeros(9, dtype=np.float32)
        start = 3 if joint.type == "revolute" else 0
        wrench[start : start + 3] = np.multiply(rotate(orient, joint.axis_vector), effort)
        targets = [(link_path(joint), 1.0)]
        if joint.parent >= 0:
            targets.append((link_path(scenario.joints[joint.parent]), -1.0))
        for path, sign in targets:
            wrenches[path] = wrenches.get(path, np.zeros(9, dtype=np.float32)) + sign * wrench
    return wrenches

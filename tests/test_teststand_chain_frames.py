"""Turned frames, vector axes and full inertia tensors in chain scenarios (issue 21, robot-scale).

The property: a chain described in other frames is the same chain. The 3-link arm of
``examples/scenarios/chains`` is rewritten with every link frame turned by its own random rotation
``Q_k`` (each joint's ``quat`` becomes ``Q_parent' @ Q_k``, its ``origin`` ``Q_parent' @ origin``,
its axis, centre of mass and inertia are expressed in the turned frame: a vector axis, the
principal axes ``Q_k'``, or the full tensor ``Q_k' @ I @ Q_k``) and the whole arm is yawed about
the vertical (gravity's axis, so the physics cannot change). Every engine must then give the
original's trajectory: the reference to float64 round-off, MuJoCo with the plugin the same, real
PhysX to float32 noise of its own run of the original.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drive_envelope._src.errors import InputError
from drive_envelope._src.io.files import read_mapping
from drive_envelope._src.scenario.chain import ChainJoint, ChainScenario, chain_from_mapping, load_stand
from drive_envelope._src.scenario.chain_frames import (
    full_inertia,
    principal_inertia,
    quat_from_matrix,
    quat_from_rpy,
    quat_multiply,
    quat_taking_x_to,
    quat_to_matrix,
    rotate,
)
from drive_envelope._src.teststand.engines import simulate

ARM = Path(__file__).parent.parent / "examples" / "scenarios" / "chains" / "arm3_pgs_1_0.toml"
ARM_TGS = ARM.with_name("arm3_tgs_4_1.toml")


def _conj(q: tuple[float, ...]) -> tuple[float, float, float, float]:
    return (q[0], -q[1], -q[2], -q[3])


def _random_quat(rng: np.random.Generator) -> tuple[float, float, float, float]:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


def turned(path: Path, seed: int = 7, yaw: float = 0.9) -> dict[str, Any]:
    """The scenario file's mapping with every link frame turned, the arm yawed about Z."""
    data = read_mapping(path)
    rng = np.random.default_rng(seed)
    turns = [_random_quat(rng) for _ in data["joints"]]
    base = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))  # the whole arm about the vertical
    joints = []
    for k, entry in enumerate(data["joints"]):
        q_parent = base if k == 0 else turns[k - 1]
        q_k = turns[k]
        axis = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}[entry["axis"]]
        new = {key: value for key, value in entry.items() if key not in ("axis", "origin", "com", "inertia")}
        new["quat"] = list(quat_multiply(_conj(q_parent), q_k) if k else quat_multiply(base, q_k))
        origin = entry.get("origin", [0.0, 0.0, 0.0])
        new["origin"] = list(rotate(_conj(q_parent), origin) if k else rotate(base, origin))
        new["axis"] = list(rotate(_conj(q_k), axis))
        new["com"] = list(rotate(_conj(q_k), entry["com"]))
        if k == 1:  # one link as the full tensor in its turned frame, the others as principal axes
            tensor = full_inertia(entry["inertia"], _conj(q_k))
            new["inertia"] = [
                tensor[0][0],
                tensor[1][1],
                tensor[2][2],
                tensor[0][1],
                tensor[0][2],
                tensor[1][2],
            ]
        else:
            new["inertia"] = entry["inertia"]
            new["inertia_quat"] = list(_conj(q_k))
        joints.append(new)
    return {**data, "joints": joints}


def test_quaternion_helpers_agree_with_closed_forms() -> None:
    # URDF rpy = Rz(yaw) Ry(pitch) Rx(roll)
    roll, pitch, yaw = 0.3, -1.1, 2.0
    rx = np.array([[1, 0, 0], [0, math.cos(roll), -math.sin(roll)], [0, math.sin(roll), math.cos(roll)]])
    ry = np.array([[math.cos(pitch), 0, math.sin(pitch)], [0, 1, 0], [-math.sin(pitch), 0, math.cos(pitch)]])
    rz = np.array([[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]])
    np.testing.assert_allclose(quat_to_matrix(quat_from_rpy(roll, pitch, yaw)), rz @ ry @ rx, atol=1e-15)
    q = quat_from_rpy(roll, pitch, yaw)
    np.testing.assert_allclose(quat_from_matrix(quat_to_matrix(q)), q, atol=1e-15)
    for axis in [(0.0, 0.0, 1.0), (-1.0, 0.0, 0.0), (0.6, 0.0, -0.8), (1.0, 0.0, 0.0)]:
        np.testing.assert_allclose(rotate(quat_taking_x_to(axis), (1.0, 0.0, 0.0)), axis, atol=1e-15)
    # the FR3 link1 tensor (fr3.urdf): principal moments and axes rebuild it
    tensor = (
        (0.0239273, 1.33e-05, -0.000114),
        (1.33e-05, 0.0224822, -0.001995),
        (-0.000114, -0.001995, 0.0063501),
    )
    moments, axes = principal_inertia(tensor, "inertia")
    np.testing.assert_allclose(full_inertia(moments, axes), tensor, atol=1e-16)
    assert math.isclose(sum(moments), 0.0239273 + 0.0224822 + 0.0063501, rel_tol=1e-14)


def test_turned_file_reads_back_the_same_chain() -> None:
    original = load_stand(ARM)
    chain = chain_from_mapping(turned(ARM), source="turned")
    assert isinstance(original, ChainScenario)
    assert chain.names == original.names and chain.is_chain
    assert all(not isinstance(joint.axis, str) for joint in chain.joints)
    assert chain.joints[1].inertia_quat != (1.0, 0.0, 0.0, 0.0)  # the full tensor's own axes
    np.testing.assert_allclose(
        sorted(chain.joints[1].inertia), sorted(original.joints[1].inertia), rtol=1e-12
    )


@pytest.mark.parametrize("path", [ARM, ARM_TGS], ids=["pgs_1_0", "tgs_4_1"])
def test_turned_arm_runs_as_the_original_on_the_reference(path: Path) -> None:
    original, chain = load_stand(path), chain_from_mapping(turned(path), source="turned")
    a, b = simulate(original), simulate(chain)
    np.testing.assert_allclose(b.velocity, a.velocity, rtol=0, atol=1e-10)
    np.testing.assert_allclose(b.position, a.position, rtol=0, atol=1e-11)
    np.testing.assert_allclose(b.effort, a.effort, rtol=0, atol=1e-8)
    assert a.velocity[:, 0].max() > 2.0  # the shoulder let go and fell through: the test sees it all


@pytest.mark.mujoco
def test_turned_arm_runs_as_the_original_in_mujoco() -> None:
    original, chain = load_stand(ARM), chain_from_mapping(turned(ARM), source="turned")
    a, b = simulate(original, "mujoco"), simulate(chain, "mujoco")
    np.testing.assert_allclose(b.velocity, a.velocity, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.position, a.position, rtol=0, atol=1e-10)


@pytest.mark.physx
@pytest.mark.usd
@pytest.mark.slow
@pytest.mark.parametrize("path", [ARM, ARM_TGS], ids=["pgs_1_0", "tgs_4_1"])
def test_turned_arm_runs_as_the_original_on_real_physx(path: Path) -> None:
    original, chain = load_stand(path), chain_from_mapping(turned(path), source="turned")
    reference, physx = simulate(original), simulate(chain, "physx")
    # PhysX builds the turned USD (orient ops, localRot0/1, principalAxes) and follows the model
    assert np.abs(physx.velocity - reference.velocity).max() < 1e-5
    assert np.abs(physx.position - reference.position).max() < 1e-5


def test_frame_keys_are_checked() -> None:
    base = {"simulation": {"dt": 0.01, "duration": 0.1}}
    joint = {"name": "a", "mass": 1.0, "inertia": [0.1, 0.1, 0.1]}
    cases = [
        ({**joint, "axis": [0, 0, 0]}, "joints[0].axis"),
        ({**joint, "axis": [1, "a", 0]}, "joints[0].axis"),
        ({**joint, "quat": [0, 0, 0, 0]}, "joints[0].quat"),
        ({**joint, "quat": [1, 0, 0]}, "joints[0].quat"),
        ({**joint, "quat": [1, 0, 0, 0], "rpy": [0, 0, 0]}, "joints[0].rpy"),
        ({**joint, "rpy": [0, 0]}, "joints[0].rpy"),
        ({**joint, "inertia": [0.1, 0.1, 0.1, 0, 0]}, "joints[0].inertia"),
        ({**joint, "inertia": [0.1, 0.1, 0.1, 0.2, 0, 0]}, "joints[0].inertia"),  # not positive definite
        (
            {**joint, "inertia": [0.1, 0.1, 0.1, 0, 0, 0], "inertia_quat": [1, 0, 0, 0]},
            "joints[0].inertia_quat",
        ),
        ({**joint, "inertia_quat": "up"}, "joints[0].inertia_quat"),
    ]
    for entry, key in cases:
        with pytest.raises(InputError) as info:
            chain_from_mapping({**base, "joints": [entry]}, source="arm.toml")
        message = str(info.value)
        assert "\n" not in message and message.startswith("arm.toml:") and key in message, message


def test_constructor_normalizes_axis_and_quaternions() -> None:
    joint = ChainJoint(
        name="a", axis=(0.0, 3.0, 4.0), quat=(-2.0, 0.0, 0.0, 0.0), mass=1.0, inertia=(1.0, 1.0, 1.0)
    )
    assert joint.axis_vector == (0.0, 0.6, 0.8) and joint.axis_index is None
    assert joint.quat == (1.0, 0.0, 0.0, 0.0)
    assert ChainJoint(name="b", axis="y", mass=1.0, inertia=(1.0, 1.0, 1.0)).axis_vector == (0.0, 1.0, 0.0)

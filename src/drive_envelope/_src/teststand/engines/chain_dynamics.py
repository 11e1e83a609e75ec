"""Rigid-body dynamics of a chain scenario in joint space (float64): mass matrix and bias forces.

The reference engine needs what PhysX's Featherstone articulation forms at the start of a step: the
joint-space mass matrix ``M(q)`` (with armature on its diagonal), whose inverse gives each DOF's
unit response ``(M^-1)_ii`` (PhysX ``getImpulseSelfResponse``) and the propagation of one DOF's
impulse to every joint (the column ``M^-1[:, i]``), and the bias ``h(q, v)`` (Coriolis, centrifugal
and gravity efforts). ``M`` comes from the link Jacobians, ``h`` from one recursive Newton-Euler
pass, both in world coordinates. A link's frame is its parent's turned by the joint's fixed
rotation and then by the joint about its axis in that frame (URDF's and MJCF's order; see
:mod:`~drive_envelope._src.scenario.chain`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.scenario.chain import ChainScenario
from drive_envelope._src.scenario.chain_frames import quat_to_matrix

FloatArray = npt.NDArray[np.float64]


def _rotation(axis: int | None, vector: FloatArray, angle: float) -> FloatArray:
    """Right-handed rotation by ``angle`` [rad] about the X, Y or Z axis (0, 1, 2) or a unit vector."""
    c, s = np.cos(angle), np.sin(angle)
    if axis is None:  # Rodrigues: c*I + s*[a]x + (1 - c)*a*a'
        x, y, z = vector
        cross = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        return np.asarray(c * np.eye(3) + s * cross + (1.0 - c) * np.outer(vector, vector))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    rotation = np.eye(3)
    rotation[i, i], rotation[i, j], rotation[j, i], rotation[j, j] = c, -s, s, c
    return rotation


@dataclass(frozen=True, kw_only=True, slots=True)
class Kinematics:
    """World poses of a chain's links at one joint position."""

    rotation: FloatArray
    """Link frame rotations, shape ``(n, 3, 3)``."""
    origin: FloatArray
    """Joint (link frame origin) positions [m], shape ``(n, 3)``."""
    axis: FloatArray
    """Joint axes in the world, shape ``(n, 3)``."""
    com: FloatArray
    """Link centres of mass [m], shape ``(n, 3)``."""
    inertia: FloatArray
    """Link inertia tensors about the centre of mass in the world [kg*m^2], shape ``(n, 3, 3)``."""


class ChainModel:
    """The constant data of a chain and its kinematics and dynamics at a joint state."""

    def __init__(self, scenario: ChainScenario) -> None:
        joints = scenario.joints
        self.dofs = len(joints)
        self.parent = [joint.parent for joint in joints]
        self.axis = [joint.axis_index for joint in joints]
        self.local_axis = np.array([joint.axis_vector for joint in joints], dtype=np.float64)
        # the fixed rotation of each link frame in its parent's (identity: parallel frames)
        self.fixed = np.array([quat_to_matrix(joint.quat) for joint in joints], dtype=np.float64)
        self.turned = [joint.quat != (1.0, 0.0, 0.0, 0.0) for joint in joints]
        self.revolute = np.array([joint.type == "revolute" for joint in joints])
        self.origin = np.array([joint.origin for joint in joints], dtype=np.float64)
        self.local_com = np.array([joint.com for joint in joints], dtype=np.float64)
        self.mass = np.array([joint.mass for joint in joints], dtype=np.float64)
        principal = np.array([quat_to_matrix(joint.inertia_quat) for joint in joints], dtype=np.float64)
        moments = np.array([np.diag(joint.inertia) for joint in joints], dtype=np.float64)
        self.local_inertia = principal @ moments @ principal.transpose(0, 2, 1)
        self.armature = np.array([joint.armature for joint in joints], dtype=np.float64)
        self.gravity = np.array([0.0, 0.0, -scenario.simulation.gravity])
        # ancestors[k, j]: joint j moves link k (j is k or one of its ancestors)
        self.ancestors = np.zeros((self.dofs, self.dofs), dtype=bool)
        for k in range(self.dofs):
            j = k
            while j >= 0:
                self.ancestors[k, j] = True
                j = self.parent[j]

    def kinematics(self, position: FloatArray) -> Kinematics:
        """The links' world poses at joint position ``position`` [rad or m]."""
        n = self.dofs
        rotation = np.empty((n, 3, 3))
        origin = np.empty((n, 3))
        axis = np.empty((n, 3))
        for k in range(n):
            p = self.parent[k]
            parent_rotation = rotation[p] if p >= 0 else np.eye(3)
            parent_origin = origin[p] if p >= 0 else np.zeros(3)
            frame = parent_rotation @ self.fixed[k] if self.turned[k] else parent_rotation
            axis[k] = frame @ self.local_axis[k]
            origin[k] = parent_origin + parent_rotation @ self.origin[k]
            if self.revolute[k]:
                rotation[k] = frame @ _rotation(self.axis[k], self.local_axis[k], float(position[k]))
            else:
                rotation[k] = frame
                origin[k] += axis[k] * position[k]
        com = origin + np.einsum("kij,kj->ki", rotation, self.local_com)
        inertia = rotation @ self.local_inertia @ rotation.transpose(0, 2, 1)
        return Kinematics(rotation=rotation, origin=origin, axis=axis, com=com, inertia=inertia)

    def mass_matrix(self, kin: Kinematics) -> FloatArray:
        """Joint-space mass matrix, armature on the diagonal [kg*m^2, kg*m or kg]."""
        n = self.dofs
        # Jacobians of each link's centre of mass (linear) and rotation (angular), shape (n, 3, n)
        linear = np.zeros((n, 3, n))
        angular = np.zeros((n, 3, n))
        for j in range(n):
            moved = self.ancestors[:, j]
            if self.revolute[j]:
                angular[moved, :, j] = kin.axis[j]
                linear[moved, :, j] = np.cross(kin.axis[j], kin.com[moved] - kin.origin[j])
            else:
                linear[moved, :, j] = kin.axis[j]
        matrix = np.einsum("k,kin,kim->nm", self.mass, linear, linear)
        matrix += np.einsum("kin,kij,kjm->nm", angular, kin.inertia, angular)
        return matrix + np.diag(self.armature)

    def bias(self, kin: Kinematics, velocity: FloatArray) -> FloatArray:
        """Coriolis, centrifugal and gravity efforts ``h(q, v)``: ``M*qdd + h`` is the joint effort.

        One recursive Newton-Euler pass with zero joint accelerations and the base accelerating
        at ``-gravity`` [N*m or N].
        """
        n = self.dofs
        omega = np.zeros((n, 3))
        alpha = np.zeros((n, 3))
        accel = np.zeros((n, 3))  # linear acceleration of each link frame's origin
        for k in range(n):
            p = self.parent[k]
            w_p = omega[p] if p >= 0 else np.zeros(3)
            a_p = alpha[p] if p >= 0 else np.zeros(3)
            acc_p = accel[p] if p >= 0 else -self.gravity
            o_p = kin.origin[p] if p >= 0 else np.zeros(3)
            lever = kin.origin[k] - o_p
            acc = acc_p + np.cross(a_p, lever) + np.cross(w_p, np.cross(w_p, lever))
            rate = kin.axis[k] * velocity[k]
            if self.revolute[k]:
                omega[k] = w_p + rate
                alpha[k] = a_p + np.cross(w_p, rate)
            else:
                omega[k], alpha[k] = w_p, a_p
                acc = acc + 2.0 * np.cross(w_p, rate)
            accel[k] = acc
        force = np.zeros((n, 3))
        moment = np.zeros((n, 3))  # about each link frame's origin
        for k in range(n):
            arm = kin.com[k] - kin.origin[k]
            a_com = accel[k] + np.cross(alpha[k], arm) + np.cross(omega[k], np.cross(omega[k], arm))
            f = self.mass[k] * a_com
            spin = kin.inertia[k] @ omega[k]
            force[k] = f
            moment[k] = kin.inertia[k] @ alpha[k] + np.cross(omega[k], spin) + np.cross(arm, f)
        effort = np.empty(n)
        for k in range(n - 1, -1, -1):
            effort[k] = kin.axis[k] @ (moment[k] if self.revolute[k] else force[k])
            p = self.parent[k]
            if p >= 0:
                force[p] += force[k]
                moment[p] += moment[k] + np.cross(kin.origin[k] - kin.origin[p], force[k])
        return effort

"""Frames of chain scenarios: unit quaternions ``(w, x, y, z)``, rotations and inertia tensors.

Pure Python (float64), one convention for every consumer: a quaternion ``(w, x, y, z)`` is the
rotation MuJoCo's ``quat`` and USD's ``GfQuat(real, imaginary)`` mean, taking a vector from a
child frame to its parent's (``v_parent = R(q) @ v_child``). URDF's ``rpy`` is the fixed-axis
roll, pitch, yaw: ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from drive_envelope._src.errors import InputError

Quaternion = tuple[float, float, float, float]
Matrix3 = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]
IDENTITY: Quaternion = (1.0, 0.0, 0.0, 0.0)
"""The identity rotation."""


def quat_normalize(value: Sequence[float], name: str) -> Quaternion:
    """``value`` as a unit quaternion ``(w, x, y, z)``; one sign (``w >= 0``) for one rotation.

    Raises:
        InputError: not four finite numbers, or all zero; ``name`` says where.
    """
    if isinstance(value, (str, bytes)) or len(value) != 4:
        raise InputError(f"{name} must be a quaternion [w, x, y, z] (4 numbers), got {value!r}")
    items = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, (int, float)) or not math.isfinite(item):
            raise InputError(f"{name} must be a quaternion [w, x, y, z] of finite numbers, got {value!r}")
        items.append(float(item))
    norm = math.sqrt(sum(item * item for item in items))
    if not norm > 1e-12:
        raise InputError(f"{name} must be a non-zero quaternion [w, x, y, z], got {value!r}")
    sign = -1.0 if items[0] < 0.0 else 1.0
    w, x, y, z = (sign * item / norm for item in items)
    return (w, x, y, z)


def unit_vector(value: Sequence[float], name: str) -> tuple[float, float, float]:
    """``value`` scaled to length 1 (a joint axis, as MuJoCo and URDF normalize theirs).

    Raises:
        InputError: not three finite numbers, or (nearly) zero; ``name`` says where.
    """
    if isinstance(value, (str, bytes)) or len(value) != 3:
        raise InputError(f"{name} must be 'x', 'y', 'z' or three numbers [x, y, z], got {value!r}")
    items = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, (int, float)) or not math.isfinite(item):
            raise InputError(f"{name} must be three finite numbers [x, y, z], got {value!r}")
        items.append(float(item))
    norm = math.sqrt(sum(item * item for item in items))
    if not norm > 1e-9:
        raise InputError(f"{name} must be a non-zero vector [x, y, z], got {value!r}")
    return (items[0] / norm, items[1] / norm, items[2] / norm)


def quat_multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    """The rotation ``R(a) @ R(b)`` as a quaternion."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> Quaternion:
    """URDF's ``origin rpy`` [rad]: ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``."""
    qx = (math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0)
    qy = (math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0)
    qz = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
    return quat_normalize(quat_multiply(qz, quat_multiply(qy, qx)), "rpy")


def quat_to_matrix(q: Quaternion) -> Matrix3:
    """The rotation matrix of a unit quaternion (rows)."""
    w, x, y, z = q
    return (
        (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )


def quat_from_matrix(m: Sequence[Sequence[float]]) -> Quaternion:
    """The unit quaternion of a proper rotation matrix (Shepperd's method: the largest pivot)."""
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > max(m[0][0], m[1][1], m[2][2]):
        s = 2.0 * math.sqrt(1.0 + trace)
        q = (s / 4, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s)
    elif m[0][0] >= m[1][1] and m[0][0] >= m[2][2]:
        s = 2.0 * math.sqrt(max(1e-300, 1.0 + m[0][0] - m[1][1] - m[2][2]))
        q = ((m[2][1] - m[1][2]) / s, s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s)
    elif m[1][1] >= m[2][2]:
        s = 2.0 * math.sqrt(max(1e-300, 1.0 + m[1][1] - m[0][0] - m[2][2]))
        q = ((m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s)
    else:
        s = 2.0 * math.sqrt(max(1e-300, 1.0 + m[2][2] - m[0][0] - m[1][1]))
        q = ((m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4)
    return quat_normalize(q, "rotation matrix")


def rotate(q: Quaternion, v: Sequence[float]) -> tuple[float, float, float]:
    """``R(q) @ v``."""
    m = quat_to_matrix(q)
    return (
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    )


def quat_taking_x_to(axis: Sequence[float]) -> Quaternion:
    """The shortest rotation taking +X onto the unit vector ``axis`` (PhysX's joint axis is X).

    For ``axis = -X`` the half turn about Z.
    """
    x, y, z = axis
    w = 1.0 + x  # the half-angle quaternion (1 + x.a, x cross a), normalized
    if w < 1e-12:
        return (0.0, 0.0, 0.0, 1.0)
    return quat_normalize((w, 0.0, -z, y), "axis")


def full_inertia(moments: Sequence[float], axes: Quaternion) -> Matrix3:
    """The inertia tensor ``R @ diag(moments) @ R.T`` in the link frame [kg*m^2]."""
    return turn_tensor(axes, [[moments[i] if i == j else 0.0 for j in range(3)] for i in range(3)])


def turn_tensor(q: Quaternion, tensor: Sequence[Sequence[float]]) -> Matrix3:
    """``R(q) @ tensor @ R(q).T``: a tensor given in a frame turned by ``q``, in the parent frame."""
    r = quat_to_matrix(q)
    rows = [tuple(sum(r[i][a] * tensor[a][b] * r[j][b] for a in range(3) for b in range(3)) for j in range(3))
            for i in range(3)]  # fmt: skip
    return rows[0], rows[1], rows[2]  # type: ignore[return-value]


def principal_inertia(
    tensor: Sequence[Sequence[float]], name: str
) -> tuple[tuple[float, float, float], Quaternion]:
    """Principal moments [kg*m^2] and the principal axes' rotation of a symmetric inertia tensor.

    Raises:
        InputError: the tensor is not positive definite; ``name`` says where.
    """
    import numpy as np

    matrix = np.asarray(tensor, dtype=np.float64)
    values, vectors = np.linalg.eigh(0.5 * (matrix + matrix.T))
    if np.linalg.det(vectors) < 0.0:
        vectors[:, 2] = -vectors[:, 2]  # a proper rotation: the axes stay right-handed
    a, b, c = (float(v) for v in values)
    if not a > 0.0:
        raise InputError(
            f"{name}: expected a positive-definite inertia tensor [kg*m^2], got principal moments {[a, b, c]}"
        )
    return (a, b, c), quat_from_matrix(vectors.tolist())

"""Shared input vectors of the kernel backend tests (``tests/test_kernels_*.py``, ``tests/test_clamp_*.py``).

Arguments are in PhysX ``clampDriveImpulse`` order:
``(joint_vel0, drive_impulse0, drive_impulse, response, max_joint_vel, max_impulse,
speed_impulse_gradient, velocity_dependent_resistance)``.
"""

from __future__ import annotations

import ctypes
import itertools
from pathlib import Path

import numpy as np

from drive_envelope._src.envelope.clamp import CLAMP_DRIVE_IMPULSE_ARGS as IMPULSE_ARGS

GOLDEN = Path(__file__).parent / "golden" / "physx_clamp_drive_impulse.npz"


def random_impulse_args(n: int = 20_000, seed: int = 7) -> list[np.ndarray]:
    """Random float32 arguments covering all quadrants, both curves binding, and R = 0."""
    rng = np.random.default_rng(seed)
    args = [
        rng.normal(0.0, 3.0, n),
        rng.normal(0.0, 1.0, n),
        rng.normal(0.0, 2.0, n),
        rng.uniform(0.0, 5.0, n),
        rng.uniform(0.0, 4.0, n),
        rng.uniform(0.0, 2.0, n),
        rng.uniform(0.0, 6.0, n),
        rng.choice([0.0, 0.1, 0.5, 2.0], n),
    ]
    return [a.astype(np.float32) for a in args]


def edge_impulse_args(with_nan: bool = True) -> list[np.ndarray]:
    """Grid of special values: r == gradient and r == 1/R (flat curves), r + gradient == 0 (ignored
    curve), |dev| == max (the epsilon tests), zero request, inf speed limit, zero caps, NaN."""
    nan = [np.nan] if with_nan else []
    grid = itertools.product(
        [-3.0, -1.0, 0.0, 0.5, 3.0, *nan],
        [0.0, 0.5],
        [-2.0, -0.5, 0.0, 0.5, 2.0, *nan],
        [0.0, 0.5, 2.0],
        [0.0, 1.0, 3.0, np.inf],
        [0.0, 1.0],
        [0.0, 0.5, 2.0],
        [0.0, 0.5, 2.0],
    )
    table = np.array(list(grid), dtype=np.float32)
    return [np.ascontiguousarray(table[:, k]) for k in range(8)]


def physx_golden() -> tuple[list[np.ndarray], np.ndarray] | None:
    """The real-PhysX vectors of tests/golden (8 float32 argument arrays, expected result), if present.

    The file (see tests/golden/ATTRIBUTION.md) holds ``inputs`` ``(K, 8)`` with ``columns`` naming
    them in PhysX order, and ``expected`` ``(K,)``, PhysX's float32 results.
    """
    if not GOLDEN.exists():
        return None
    data = np.load(GOLDEN, allow_pickle=False)
    columns = [str(c) for c in data["columns"]]
    inputs = np.asarray(data["inputs"], dtype=np.float32)
    args = [np.ascontiguousarray(inputs[:, columns.index(name)]) for name in IMPULSE_ARGS]
    return args, np.asarray(data["expected"], dtype=np.float32)


def envelope_cases() -> list[dict[str, float]]:
    """Envelopes covering: box only, speed line only, both lines, resistance only, a tiny one."""
    return [
        {"max_effort": 2.0},
        {"max_effort": 5.0, "max_actuator_velocity": 4.0, "speed_effort_gradient": 0.5},
        {
            "max_effort": 5.0,
            "max_actuator_velocity": 4.0,
            "speed_effort_gradient": 0.5,
            "velocity_dependent_resistance": 0.8,
        },
        {"max_effort": 3.0, "velocity_dependent_resistance": 0.4},
        {"max_effort": 0.1, "max_actuator_velocity": 0.5, "speed_effort_gradient": 2.0},
    ]


CPP_MODES = {(np.float32, False): "f32", (np.float64, False): "f64"}
CPP_MODES.update({(np.float32, True): "physx_f32", (np.float64, True): "physx_f64"})
"""Suffix of the C entry point ``drive_envelope_clamp_drive_impulse_<suffix>`` per (dtype, physx_exact)."""


def cpp_clamp_library() -> ctypes.CDLL:
    """The MuJoCo plugin library (built if missing) with its clamp entry points typed for ctypes.

    Skips the calling test when MuJoCo is not installed.
    """
    from _mujoco_plugin import mujoco_with_plugin
    from drive_envelope._src.adapters.mujoco import loader

    mujoco_with_plugin()
    handle = loader.plugin_library()
    for (dtype, _), suffix in CPP_MODES.items():
        kind = ctypes.c_float if dtype is np.float32 else ctypes.c_double
        function = getattr(handle, f"drive_envelope_clamp_drive_impulse_{suffix}")
        function.argtypes = [kind] * 8
        function.restype = kind
    return handle


def cpp_clamp(lib: ctypes.CDLL, rows: np.ndarray, dtype: type, physx_exact: bool = False) -> np.ndarray:
    """The C++ clamp row by row: ``rows`` ``(K, 8)`` in PhysX order, results of ``dtype``."""
    function = getattr(lib, f"drive_envelope_clamp_drive_impulse_{CPP_MODES[(dtype, physx_exact)]}")
    return np.array([function(*map(float, row)) for row in np.asarray(rows, dtype=dtype)], dtype=dtype)

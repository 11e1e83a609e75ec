"""The plugin's C++ drive math against the Python core, through the library's C entry points.

``drive_envelope_clamp_drive_impulse_physx_f32`` (``ClampDriveImpulsePhysx``) must reproduce PhysX
(the golden file) bit for bit; the guarded ``_f32``/``_f64`` entry points (``ClampDriveImpulse``, what
the plugin runs) and the exact ones must equal the Python modes; the implicit drive must equal
``implicit_drive_effort``. Vectors: ``golden/physx_clamp_drive_impulse.npz`` (PhysX's
own outputs, see ``golden/ATTRIBUTION.md``) plus random and edge vectors drawn here.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _kernel_vectors import cpp_clamp, cpp_clamp_library
from drive_envelope import clamp_drive_impulse, implicit_drive_effort

pytestmark = pytest.mark.mujoco

GOLDEN = Path(__file__).parent / "golden" / "physx_clamp_drive_impulse.npz"


@pytest.fixture(scope="module")
def lib() -> ctypes.CDLL:
    handle = cpp_clamp_library()
    effort = handle.drive_envelope_implicit_drive_effort
    effort.argtypes = [ctypes.c_double] * 7 + [ctypes.c_int]
    effort.restype = ctypes.c_double
    return handle  # type: ignore[no-any-return]


def _cpp(lib: ctypes.CDLL, rows: npt.NDArray[Any], name: str, physx_exact: bool = False) -> npt.NDArray[Any]:
    return cpp_clamp(lib, rows, np.float32 if name == "f32" else np.float64, physx_exact)  # type: ignore[no-any-return]


def _bits_equal(a: npt.NDArray[Any], b: npt.NDArray[Any]) -> npt.NDArray[np.bool_]:
    # equal bit patterns, any NaN equal to any NaN, and +0.0 == -0.0 as PhysX's compares treat them
    return (a == b) | (np.isnan(a) & np.isnan(b))


def _random_rows(count: int, seed: int) -> npt.NDArray[np.float64]:
    rng = np.random.default_rng(seed)
    dt = rng.choice([1e-3, 1 / 240, 1 / 60], count)
    response = rng.choice([0.0, 1e-3, 1.0, 20.0, 1e4], count) * rng.uniform(0.5, 2.0, count)
    rows = np.column_stack(
        [
            rng.normal(0.0, 5.0, count),  # joint_vel0
            rng.normal(0.0, 0.05, count) * (rng.random(count) < 0.5),  # drive_impulse0
            rng.normal(0.0, 0.2, count),  # drive_impulse
            response,
            np.where(rng.random(count) < 0.2, np.inf, rng.uniform(0.0, 10.0, count)),  # max_joint_vel
            rng.uniform(0.0, 20.0, count) * dt,  # max_impulse
            np.where(rng.random(count) < 0.3, 0.0, rng.uniform(0.0, 1.0, count)) / dt,  # gradient/dt
            np.where(rng.random(count) < 0.3, 0.0, rng.uniform(0.0, 2.0, count)) * dt,  # resistance*dt
        ]
    )
    # a few rows that land exactly on PhysX's near-zero denominators
    rows[:50, 6] = rows[:50, 3]
    rows[50:100, 7] = 1.0 / np.where(rows[50:100, 3] > 0, rows[50:100, 3], 1.0)
    return rows


def test_float32_matches_physx_golden_bit_for_bit(lib: ctypes.CDLL) -> None:
    """Reproduce every PhysX golden row bit for bit with the C++ float32 clamp."""
    if not GOLDEN.is_file():
        pytest.skip(f"{GOLDEN.name} not present")
    golden = np.load(GOLDEN)
    inputs, expected = golden["inputs"], golden["expected"]
    result = _cpp(lib, inputs, "f32", physx_exact=True)
    mismatch = ~_bits_equal(result, expected)
    assert not mismatch.any(), f"{mismatch.sum()} rows differ, first: {inputs[mismatch][:3]}"
    assert np.array_equal(result.view(np.uint32), expected.view(np.uint32))  # zeros' signs, NaN bits
    # the guarded default (what the plugin runs) equals the Python default on the same rows
    for name, dtype in (("f32", np.float32), ("f64", np.float64)):
        guarded = _cpp(lib, inputs, name)
        assert _bits_equal(guarded, clamp_drive_impulse(*inputs.T, dtype=dtype)).all()
        exact = _cpp(lib, inputs, name, physx_exact=True)
        assert _bits_equal(exact, clamp_drive_impulse(*inputs.T, dtype=dtype, physx_exact=True)).all()


def test_float32_matches_python_float32_mode(lib: ctypes.CDLL) -> None:
    """Match the Python float32 clamp exactly on random and edge vectors."""
    rows = _random_rows(4000, seed=1).astype(np.float32)
    for exact in (False, True):
        python = clamp_drive_impulse(*rows.T, dtype=np.float32, physx_exact=exact)
        cpp = _cpp(lib, rows, "f32", physx_exact=exact)
        assert _bits_equal(cpp, python).all()


def test_float64_matches_python_float64_mode(lib: ctypes.CDLL) -> None:
    """Match the Python float64 clamp exactly on random and edge vectors."""
    rows = _random_rows(4000, seed=2)
    for exact in (False, True):
        python = clamp_drive_impulse(*rows.T, physx_exact=exact)
        cpp = _cpp(lib, rows, "f64", physx_exact=exact)
        assert _bits_equal(cpp, python).all()


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.floats(allow_nan=True, allow_infinity=True, width=32), min_size=8, max_size=8),
    st.booleans(),
)
def test_float32_matches_python_on_arbitrary_floats(
    lib: ctypes.CDLL, values: list[float], exact: bool
) -> None:
    """Agree with the Python float32 clamp on any eight float32 inputs, NaN and inf included."""
    row = np.asarray(values, dtype=np.float32)
    python = clamp_drive_impulse(*row, dtype=np.float32, physx_exact=exact)
    cpp = _cpp(lib, row[None, :], "f32", physx_exact=exact)
    assert _bits_equal(cpp, np.atleast_1d(python)).all()


@pytest.mark.parametrize("drive_type", ["force", "acceleration"])
def test_implicit_drive_matches_python(lib: ctypes.CDLL, drive_type: str) -> None:
    """Compute the same unclamped implicit PD effort as implicit_drive_effort."""
    rng = np.random.default_rng(3)
    for _ in range(500):
        k, c = rng.uniform(0, 1e4), rng.uniform(0, 100)
        err, v, vt = rng.normal(0, 1), rng.normal(0, 10), rng.normal(0, 5)
        r, dt = rng.uniform(0.01, 100), rng.choice([1e-3, 1 / 120])
        python = implicit_drive_effort(
            stiffness=k, damping=c, position_error=err, velocity=v, target_velocity=vt,
            response=r, dt=dt, drive_type=drive_type,  # type: ignore[arg-type]
        )  # fmt: skip
        cpp = lib.drive_envelope_implicit_drive_effort(
            k, c, err, v, vt, r, dt, int(drive_type == "acceleration")
        )
        assert cpp == pytest.approx(float(python), rel=1e-12, abs=1e-9)

"""The default clamp keeps the effort cap for every finite input, in every backend.

PhysX's own arithmetic (``physx_exact=True``) loses the cap in two corners: a resistance ``R*dt``
whose reciprocal overflows (a subnormal, 1e-310 in float64) drops eq. 1 and returns the bare
request, and a resistance so large that ``r -+ 1/(R*dt)`` rounds to ``r`` (float32 from
``R*dt*r`` of about 1e7) turns eq. 1 into ``v(x) ~ 0`` whatever the effort. The sweep below crosses
R from 1e-320 to 1e30 with time steps, responses, velocities and requests across their ranges and
checks ``|result| <= max_impulse`` (and ``<= max_effort`` at the effort level) in NumPy float64 and
float32, Warp on the CPU, torch on the CPU and the C++ plugin.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest

import drive_envelope as de
from _kernel_vectors import cpp_clamp, cpp_clamp_library
from drive_envelope._src.envelope.clamp import PX_MAX_F32 as FLT_MAX

Array = npt.NDArray[Any]
MAX_EFFORT = 10.0
RESISTANCES = np.concatenate([[0.0, 5e-324], 10.0 ** np.arange(-320.0, 31.0, 10.0), [3e-39, 1e-45]])
DTS = np.array([1e-5, 1e-3, 1.0 / 240.0, 0.1, 1.0])
RESPONSES = np.array([1e-6, 1e-2, 1.0, 1e2, 1e4, 1e8])
VELOCITIES = np.array([0.0, 0.5, -5.0, 50.0, -1e4, 1e6])
REQUESTS = np.array([1e3, -1e3, 1.0, -7.5]) * MAX_EFFORT / 10.0


def _sweep() -> tuple[Array, Array]:
    """Rows in PhysX order (impulse level) and their time steps, every combination once."""
    grid = np.array(
        list(itertools.product(RESISTANCES, DTS, RESPONSES, VELOCITIES, REQUESTS, [np.inf, 20.0], [0.0, 0.5]))
    )
    resist, dt, response, velocity, request, max_v, grad = grid.T
    applied = np.where(np.arange(len(dt)) % 3 == 0, 3.0, 0.0)
    rows = np.column_stack(
        [velocity, applied * dt, request * dt, response, max_v, MAX_EFFORT * dt, grad / dt, resist * dt]
    )
    return rows, dt


ROWS, STEPS = _sweep()


def _check_impulses(result: Array, rows: Array, dtype: type) -> None:
    """No NaN, the request's sign, not above it, and ``|result| <= max_impulse`` in ``dtype``."""
    typed = rows.astype(dtype)
    request, cap = typed[:, 2], typed[:, 5]
    result = np.asarray(result, dtype=dtype).reshape(-1)
    assert not np.isnan(result).any()
    assert (np.abs(result) <= cap).all(), typed[np.abs(result) > cap][:3]
    assert (np.abs(result) <= np.abs(request)).all()
    assert (result * request >= 0.0).all()


def test_sweep_covers_physx_losing_the_cap() -> None:
    """Find rows where PhysX's arithmetic exceeds the cap, in float64 and in float32 (the sweep bites)."""
    for dtype in (np.float64, np.float32):
        exact = de.clamp_drive_impulse(*ROWS.T, dtype=dtype, physx_exact=True)
        over = np.abs(exact) > ROWS[:, 5].astype(dtype)
        assert over.sum() > 100, dtype


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_numpy_keeps_the_cap(dtype: type) -> None:
    """Keep |impulse| <= max_impulse in NumPy for every R, dt, response and state of the sweep."""
    _check_impulses(de.clamp_drive_impulse(*ROWS.T, dtype=dtype), ROWS, dtype)


def test_numpy_effort_level_keeps_max_effort() -> None:
    """Keep |effort| <= max_effort through clamp_effort_implicit for every R and dt of the sweep."""
    for dt in DTS:
        at = STEPS == dt
        rows = ROWS[at]
        for resist in RESISTANCES:
            env = de.PerformanceEnvelope(
                max_effort=MAX_EFFORT, velocity_dependent_resistance=resist, speed_effort_gradient=0.5
            )
            effort = de.clamp_effort_implicit(
                env, rows[:, 2] / dt, rows[:, 0], rows[:, 3], dt, rows[:, 1] / dt
            )
            assert not np.isnan(effort).any()
            assert (np.abs(effort) <= MAX_EFFORT).all()


def test_subnormal_resistance_keeps_the_cap() -> None:
    """Cap a 12.86 N*m request at max_effort 10 with R*dt = 1e-310 (PhysX returns the request)."""
    dt = 0.01
    args = (0.0, 0.0, 12.86 * dt, 2.0, np.inf, 10.0 * dt, 0.0, 1e-310)
    assert float(de.clamp_drive_impulse(*args, physx_exact=True)) / dt == pytest.approx(12.86)
    assert float(de.clamp_drive_impulse(*args)) / dt == pytest.approx(10.0)
    env = de.PerformanceEnvelope(max_effort=10.0, velocity_dependent_resistance=1e-308)
    assert float(de.clamp_effort_implicit(env, 12.86, 0.0, 2.0, dt)) == pytest.approx(10.0)


def test_large_resistance_keeps_the_cap_in_float32() -> None:
    """Let go (0) instead of braking with 5x max_effort when R*dt*r = 1e8 in float32, as float64 does."""
    row = np.array([-50.0, 0.0, 10.0, 100.0, np.inf, 0.1, 0.0, 1e6], dtype=np.float32)
    assert float(de.clamp_drive_impulse(*row, dtype=np.float32, physx_exact=True)) == pytest.approx(0.5)
    assert float(de.clamp_drive_impulse(*row, dtype=np.float32)) == 0.0
    assert float(de.clamp_drive_impulse(*row.astype(np.float64), physx_exact=True)) == 0.0


@pytest.mark.parametrize(
    ("args", "exact", "guarded"),
    [
        # flat speed curve (r == G), joint far past the limit, FLT_MAX cap: PhysX returns FLT_MAX
        ((-1e39, 0.0, 1.0, 1.0, 1.0, FLT_MAX, 1.0, 0.0), FLT_MAX, 0.0),
        # the same with an infinite request and cap: PhysX returns the flat curve's bound
        ((-1e39, 0.0, np.inf, 1.0, 1.0, np.inf, 1.0, 0.0), 5e38, 0.0),
        # a NaN velocity: PhysX drops every bound and returns the bare request
        ((np.nan, 0.0, 0.5, 1.0, 2.0, 0.1, 0.0, 0.05), 0.5, 0.0),
        # a NaN request: PhysX returns NaN, the default lets go
        ((0.0, 0.0, np.nan, 1.0, 2.0, 0.1, 0.0, 0.0), np.nan, 0.0),
        # an ignored speed curve (r + G = 0) above FLT_MAX in float64: no FLT_MAX cap by default
        ((0.0, 0.0, 1e300, 0.0, 1.0, 1e301, 0.0, 0.0), FLT_MAX, 1e300),
    ],
    ids=["flat-overflow", "flat-inf", "nan-velocity", "nan-request", "ignored-curve"],
)
def test_guard_rules(args: tuple[float, ...], exact: float, guarded: float) -> None:
    """Show each rule of the default mode on one row, beside PhysX's answer."""
    np.testing.assert_equal(float(de.clamp_drive_impulse(*args, physx_exact=True)), exact)
    np.testing.assert_equal(float(de.clamp_drive_impulse(*args)), guarded)


@pytest.mark.warp
def test_warp_keeps_the_cap() -> None:
    """Keep the cap in Warp's impulse launch and its effort-level implicit clamp (CPU)."""
    import drive_envelope.warp as dw

    rows = ROWS.astype(np.float32)
    _check_impulses(dw.clamp_drive_impulse(*rows.T).numpy(), ROWS, np.float32)
    for dt in DTS:
        r = rows[STEPS == dt]
        params = dw.EnvelopeArrays.from_values(
            max_effort=MAX_EFFORT,
            velocity_dependent_resistance=(r[:, 7].astype(np.float64) / dt).astype(np.float32),
            speed_effort_gradient=0.5,
            count=len(r),
            device="cpu",
        )
        effort = dw.clamp_effort_implicit(params, r[:, 2] / dt, r[:, 0], r[:, 3], float(dt), r[:, 1] / dt)
        effort = effort.numpy()
        assert not np.isnan(effort).any() and (np.abs(effort) <= np.float32(MAX_EFFORT)).all()


@pytest.mark.torch
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_torch_keeps_the_cap(dtype: type) -> None:
    """Keep the cap in torch's impulse clamp and its effort-level implicit clamp (CPU)."""
    import torch

    import drive_envelope.torch as dt_

    rows = torch.from_numpy(ROWS.astype(dtype))
    _check_impulses(dt_.clamp_drive_impulse(*rows.T).numpy(), ROWS, dtype)
    for dt in DTS:
        r = rows[torch.from_numpy(STEPS == dt)]
        params = dt_.EnvelopeTensors.from_values(
            max_effort=MAX_EFFORT,
            velocity_dependent_resistance=r[:, 7] / dt,
            speed_effort_gradient=0.5,
            dtype=rows.dtype,
        )
        effort = dt_.clamp_effort_implicit(params, r[:, 2] / dt, r[:, 0], r[:, 3], float(dt), r[:, 1] / dt)
        assert not effort.isnan().any() and (effort.abs() <= MAX_EFFORT).all()


@pytest.mark.mujoco
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_cpp_keeps_the_cap(dtype: type) -> None:
    """Keep the cap in the plugin's C++ ClampDriveImpulse (what envelope.cc calls), through ctypes."""
    lib = cpp_clamp_library()
    _check_impulses(cpp_clamp(lib, ROWS, dtype), ROWS, dtype)

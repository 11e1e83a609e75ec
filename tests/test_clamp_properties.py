"""Properties of the default ``clamp_drive_impulse``, one hypothesis test per backend, whole float range.

For any finite inputs, in NumPy float64 and float32, Warp (CPU), torch (CPU) and the C++ plugin:

* no NaN, the request's sign (never flipped), never above the request, ``|result| <= max_impulse``;
* for a valid envelope (response, limits and slopes ``>= 0``): a non-zero result lies inside the
  envelope at its end-of-step velocity ``v(x) = v0 + r*(x - x0)`` (so the result is inside whenever
  the envelope admits any effort: zero effort is itself inside then), and a request strictly
  inside the envelope comes back unchanged.

Inside the envelope is checked in exact rational arithmetic, with the rounding a float
computation of PhysX's bounds may make: ``16 u`` times the magnitudes that enter each curve
(``u = 2^-53`` or ``2^-24``) plus as many smallest subnormals. A curve PhysX treats with its
absolute ``2^-23`` epsilon (``|r -+ k| < 2^-23``: ignored, or a yes/no test) is not a curve of the
exact model, and a resistance whose reciprocal overflows acts as ``R = 0`` (the default's guard);
both are checked as the clamp defines them.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drive_envelope as de
from _kernel_vectors import cpp_clamp, cpp_clamp_library
from drive_envelope._src.envelope.clamp import PX_EPS_F32

Array = npt.NDArray[Any]
EXAMPLES = 250


def _magnitudes(width: int) -> st.SearchStrategy[float]:
    """Non-negative floats over the whole range, with physical ones and zeros drawn often."""
    return st.one_of(
        st.floats(min_value=0.0, allow_infinity=False, width=width),
        st.floats(min_value=0.0, max_value=100.0, width=width),
        st.just(0.0),
    )


def _signed(width: int) -> st.SearchStrategy[float]:
    return st.one_of(
        st.floats(allow_nan=False, allow_infinity=False, width=width),
        st.floats(min_value=-100.0, max_value=100.0, width=width),
        st.just(0.0),
    )


@st.composite
def _rows(draw: st.DrawFn, width: int) -> Array:
    """``(K, 8)`` finite rows in PhysX order; the envelope valid in most, any signs in the rest."""
    real = np.float32 if width == 32 else np.float64
    rows = []
    for _ in range(draw(st.integers(1, 12))):
        v0, x0, x = (draw(_signed(width)) for _ in range(3))
        part = _signed(width) if draw(st.integers(0, 9)) == 0 else _magnitudes(width)
        r, max_v, max_x, grad, resist = (draw(part) for _ in range(5))
        tie = draw(st.integers(0, 5))
        if tie == 1:
            grad = r  # a flat speed curve
        elif tie == 2 and r > 0.0:
            with np.errstate(over="ignore"):
                resist = float(real(1.0) / real(r))  # a flat resistance curve (inf: dropped below)
            resist = resist if math.isfinite(resist) else 0.0
        rows.append([v0, x0, x, r, max_v, max_x, grad, resist])
    return np.array(rows, dtype=real)


def _rational(value: float) -> Fraction:
    return Fraction(float(value))


def _short(value: Fraction) -> str:
    return f"{float(value):.3g}" if abs(value) < Fraction(10) ** 300 else ("+big" if value > 0 else "-big")


def _curve_is_exact(response: Any, slope: Any) -> bool:
    """Whether PhysX treats the curve of ``slope`` as the exact model does (no 2^-23 denominator)."""
    return bool(abs(response - slope) >= PX_EPS_F32 and abs(response + slope) >= PX_EPS_F32)


class _Verdict(NamedTuple):
    """Where an impulse lies against the curves the exact model shares with the clamp."""

    outside: bool
    """Some checked curve is exceeded by more than its rounding tolerance."""
    strictly_inside: bool
    """Every checked curve holds with a margin larger than its tolerance."""
    every_curve: bool
    """Both curves were checked (none is one PhysX treats with its 2^-23 epsilon)."""
    detail: list[str]
    """``excess/tolerance`` per checked curve, for messages."""


def _verdict(row: Array, x: Fraction, real: type) -> _Verdict:
    """Check impulse ``x`` of ``row`` against the exact curves, each with its rounding tolerance."""
    with np.errstate(all="ignore"):
        v0, x0, _, r, max_v, max_x, grad, resist = row
        inv, limit = real(1.0) / resist, max_x / resist
        flat_r = resist == 0.0 or not (np.isfinite(inv) and np.isfinite(limit))
        speed_exact = _curve_is_exact(r, grad)
        resist_exact = flat_r or _curve_is_exact(r, inv)
    u = Fraction(1, 2**53) if real is np.float64 else Fraction(1, 2**24)
    tiny = Fraction(float(np.finfo(real).smallest_subnormal))
    fv0, fx0, fr, fv, fm, fg, fR = (_rational(a) for a in (v0, x0, r, max_v, max_x, grad, resist))
    velocity = fv0 + fr * (x - fx0)
    scale = abs(fx0 * fr) + abs(fv0)
    checks = []
    if speed_exact:  # |v(x)| <= max_v - G|x|, in velocity units
        excess = abs(velocity) + fg * abs(x) - fv
        checks.append((excess, 16 * u * (scale + fv + (fr + fg) * abs(x)) + 16 * tiny * (1 + fr + fg)))
    if flat_r:  # the guard's R = 0: the box
        checks.append((abs(x) - fm, Fraction(0)))
    elif resist_exact:  # |x| <= max_x - R|v(x)|, in impulse units
        excess = abs(x) + fR * abs(velocity) - fm
        tol = 16 * u * (fR * scale + fm + (fR * fr + 1) * abs(x)) + 16 * tiny * (fR + fR * fr + 1)
        checks.append((excess, tol))
    return _Verdict(
        outside=any(excess > tol for excess, tol in checks),
        strictly_inside=bool(checks) and all(excess < -tol for excess, tol in checks),
        every_curve=bool(speed_exact and resist_exact),
        detail=[f"{_short(excess)}/{_short(tol)}" for excess, tol in checks],
    )


def _check(rows: Array, results: Array, real: type) -> None:
    results = np.asarray(results, dtype=real).reshape(-1)
    for row, result in zip(rows, results, strict=True):
        request, cap = row[2], row[5]
        assert not math.isnan(result), row
        assert abs(result) <= abs(request) and np.sign(result) * np.sign(request) >= 0.0, (row, result)
        assert abs(result) <= cap or (cap < 0.0 and result == 0.0), (row, result)
        if (row[[3, 4, 5, 6, 7]] < 0.0).any():
            continue  # an invalid envelope: no model to be inside of
        if result != 0.0:
            verdict = _verdict(row, _rational(result), real)
            assert not verdict.outside, (row.tolist(), result, verdict.detail)
        # a request strictly inside every curve (all of them exact ones) is returned as it is
        at_request = _verdict(row, _rational(request), real)
        if at_request.every_curve and at_request.strictly_inside and abs(request) <= cap:
            assert result == request, (row.tolist(), result, at_request.detail)


@settings(max_examples=EXAMPLES, deadline=None)
@given(rows=_rows(64))
def test_numpy_float64(rows: Array) -> None:
    """Hold the properties in NumPy float64."""
    _check(rows, de.clamp_drive_impulse(*rows.T), np.float64)


@settings(max_examples=EXAMPLES, deadline=None)
@given(rows=_rows(32))
def test_numpy_float32(rows: Array) -> None:
    """Hold the properties in NumPy float32."""
    _check(rows, de.clamp_drive_impulse(*rows.T, dtype=np.float32), np.float32)


@pytest.mark.warp
@settings(max_examples=EXAMPLES, deadline=None)
@given(rows=_rows(32))
def test_warp_cpu(rows: Array) -> None:
    """Hold the properties in Warp (float32, CPU), and equal NumPy float32 there."""
    import drive_envelope.warp as dw

    result = dw.clamp_drive_impulse(*rows.T).numpy()
    _check(rows, result, np.float32)
    np.testing.assert_array_equal(result, de.clamp_drive_impulse(*rows.T, dtype=np.float32))


@pytest.mark.torch
@settings(max_examples=EXAMPLES, deadline=None)
@given(rows=_rows(32))
def test_torch_cpu(rows: Array) -> None:
    """Hold the properties in torch (float32, CPU), and equal NumPy float32 there."""
    import torch

    import drive_envelope.torch as dt

    result = dt.clamp_drive_impulse(*torch.from_numpy(rows).T).numpy()
    _check(rows, result, np.float32)
    np.testing.assert_array_equal(result, de.clamp_drive_impulse(*rows.T, dtype=np.float32))


@pytest.fixture(scope="module")
def lib() -> Any:
    return cpp_clamp_library()


@pytest.mark.mujoco
@settings(max_examples=EXAMPLES, deadline=None)
@given(rows=_rows(64), single=st.booleans())
def test_cpp(lib: Any, rows: Array, single: bool) -> None:
    """Hold the properties in the C++ ClampDriveImpulse (float64, or float32), as the plugin runs it."""
    real = np.float32 if single else np.float64
    rows = rows.astype(real)
    rows[~np.isfinite(rows)] = 0.0  # float64 draws beyond float32's range
    result = cpp_clamp(lib, rows, real)
    _check(rows, result, real)
    np.testing.assert_array_equal(result, de.clamp_drive_impulse(*rows.T, dtype=real))

"""The one NumPy ``clamp_drive_impulse`` against a literal two-branch port of PhysX (the oracle).

``clamp.py`` evaluates PhysX's negative-request branch as the positive branch on sign-normalized
inputs. This file holds the literal port it replaced (both ``computeBoundsFor...Impulse`` branches,
select for select) and the default mode's guard written the same literal way, and checks that the
implementation gives their numbers on the PhysX vectors and on hypothesis draws over the whole
float range (NaN, inf, subnormals, exact ties on the ``2^-23`` denominator guards), in float32 and
float64. Values must be equal and NaN where the oracle is NaN; with ``physx_exact=True`` the sign of
a zero must be PhysX's too (the default mode leaves a zero's sign unspecified).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from drive_envelope import clamp_drive_impulse
from drive_envelope._src.envelope.clamp import PX_EPS_F32, PX_MAX_F32

Array = npt.NDArray[Any]
GOLDEN = Path(__file__).parent / "golden" / "physx_clamp_drive_impulse.npz"


def _pmax(a: Any, b: Any) -> Array:
    """PhysX ``PxMax(float)``: ``a > b ? a : b``."""
    return np.where(a > b, a, b)


def _pmin(a: Any, b: Any) -> Array:
    """PhysX ``PxMin(float)``: ``a < b ? a : b``."""
    return np.where(a < b, a, b)


def _positive(dev: Array, m: Array, d1: Array, d2: Array, x: Array, guard: bool) -> tuple[Array, ...]:
    """``computeBoundsForPositiveImpulse``; returns (lower, upper, no) with ``no`` a flat curve's no."""
    eps, big = PX_EPS_F32, (np.inf if guard else PX_MAX_F32)
    b1, b2, gap = (dev - m) / d1, (dev + m) / d2, dev - m
    zero = np.zeros_like(dev)
    if guard:  # NaN-propagating minima and maxima: any NaN bound empties the interval
        flat_no = ~((np.abs(gap) < eps) | (gap <= 0.0))
        lower = np.where(d1 >= 0.0, np.maximum(zero, b1), zero)
        upper = np.where(d1 >= 0.0, np.minimum(b2, x), np.minimum(np.minimum(b1, b2), x))
        flat_lower = zero
    else:
        flat_no = np.zeros(dev.shape, dtype=bool)
        flat = np.where(np.abs(gap) < eps, -big, np.where(gap > 0.0, big, -big))
        lower = np.where(d1 >= 0.0, _pmax(zero, b1), zero)
        upper = np.where(d1 >= 0.0, _pmin(b2, x), _pmin(_pmin(b1, b2), x))
        flat_lower = _pmax(zero, flat)
    is_flat, ignored = np.abs(d1) < eps, np.abs(d2) < eps
    lower = np.where(ignored, -big, np.where(is_flat, flat_lower, lower))
    upper = np.where(ignored, big, np.where(is_flat, b2, upper))
    return lower, upper, ~ignored & is_flat & flat_no


def _negative(dev: Array, m: Array, d1: Array, d2: Array, x: Array, guard: bool) -> tuple[Array, ...]:
    """``computeBoundsForNegativeImpulse`` (a negative or zero request)."""
    eps, big = PX_EPS_F32, (np.inf if guard else PX_MAX_F32)
    b1, b2, gap = (dev - m) / d1, (dev + m) / d2, dev + m
    zero = np.zeros_like(dev)
    if guard:
        flat_no = ~((np.abs(gap) < eps) | (gap >= 0.0))
        lower = np.where(d2 >= 0.0, np.maximum(b1, x), np.maximum(np.maximum(b1, b2), x))
        upper = np.where(d2 >= 0.0, np.minimum(zero, b2), zero)
        flat_upper = zero
    else:
        flat_no = np.zeros(dev.shape, dtype=bool)
        flat = np.where(np.abs(gap) < eps, big, np.where(gap > 0.0, big, -big))
        lower = np.where(d2 >= 0.0, _pmax(b1, x), _pmax(_pmax(b1, b2), x))
        upper = np.where(d2 >= 0.0, _pmin(zero, b2), zero)
        flat_upper = _pmin(zero, flat)
    is_flat, ignored = np.abs(d2) < eps, np.abs(d1) < eps
    lower = np.where(ignored, -big, np.where(is_flat, b1, lower))
    upper = np.where(ignored, big, np.where(is_flat, flat_upper, upper))
    return lower, upper, ~ignored & is_flat & flat_no


def oracle(*args: Any, dtype: Any = np.float64, physx_exact: bool = False) -> Array:
    """``clampDriveImpulse`` literally, both branches; ``physx_exact=False`` adds the documented guard.

    The guard (the library's default): a resistance whose ``1/R`` or ``max_impulse/R`` is not finite
    acts as ``R = 0``; ``|x| <= max_impulse`` bounds the interval; absent bounds are ``inf``; a flat
    curve that says no, or a NaN bound or request, gives 0.
    """
    real = np.dtype(dtype).type
    v0, x0, x, r, max_v, max_x, grad, resist = np.broadcast_arrays(*(np.asarray(a, dtype=real) for a in args))
    guard = not physx_exact
    with np.errstate(all="ignore"):
        dev = x0 * r - v0
        positive = x > 0.0
        pos1 = _positive(dev, max_v, r - grad, r + grad, x, guard)
        neg1 = _negative(dev, max_v, r + grad, r - grad, x, guard)
        plain = resist == 0.0
        safe = np.where(plain, real(1.0), resist)
        inv, limit = real(1.0) / safe, max_x / safe
        if guard:
            plain |= ~(np.isfinite(inv) & np.isfinite(limit))
        pos2 = _positive(dev, limit, r - inv, r + inv, x, guard)
        neg2 = _negative(dev, limit, r + inv, r - inv, x, guard)
        lo1, hi1, no1 = (np.where(positive, p, n) for p, n in zip(pos1, neg1, strict=True))
        lo2, hi2, no2 = (np.where(positive, p, n) for p, n in zip(pos2, neg2, strict=True))
        if guard:
            lo2 = np.where(plain, -np.inf, lo2)
            hi2 = np.where(plain, np.inf, hi2)
            no2 = no2 & ~plain
            lower = np.maximum(np.maximum(lo1, lo2), -max_x)
            upper = np.minimum(np.minimum(hi1, hi2), max_x)
            clamped = np.minimum(upper, np.maximum(lower, x))
            bad = no1 | no2 | np.isnan(lower) | np.isnan(upper) | np.isnan(clamped) | (lower > upper)
            return np.where(bad, real(0.0), clamped).astype(real)
        lower = _pmax(lo1, np.where(plain, -max_x, lo2))
        upper = _pmin(hi1, np.where(plain, max_x, hi2))
        return np.where(lower > upper, real(0.0), _pmin(upper, _pmax(lower, x))).astype(real)


def _same_value(a: Array, b: Array) -> Array:
    """Equal values (+0.0 == -0.0, as PhysX's compares treat them), NaN where the other is NaN."""
    return (a == b) | (np.isnan(a) & np.isnan(b))


def _check(args: list[Array], dtype: Any, physx_exact: bool) -> None:
    """Equal values, NaN where the oracle is NaN; in exact mode the sign of a zero too."""
    ours = clamp_drive_impulse(*args, dtype=dtype, physx_exact=physx_exact)
    expected = oracle(*args, dtype=dtype, physx_exact=physx_exact)
    assert ours.dtype == np.dtype(dtype) and ours.shape == expected.shape
    same = _same_value(ours, expected)
    if physx_exact:
        same &= np.signbit(ours) == np.signbit(expected)
        same |= np.isnan(ours) & np.isnan(expected)
    if not same.all():
        i = int(np.flatnonzero(~same.ravel())[0])
        row = [float(np.broadcast_to(a, ours.shape).ravel()[i]) for a in args]
        raise AssertionError(f"row {i}: args {row}: ours {ours.ravel()[i]!r}, oracle {expected.ravel()[i]!r}")


@pytest.mark.parametrize("physx_exact", [True, False], ids=["exact", "guarded"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_equals_the_literal_port_on_physx_vectors(dtype: Any, physx_exact: bool) -> None:
    """Give the literal port's numbers on all 34,100 PhysX vectors, in both modes and precisions."""
    with np.load(GOLDEN) as data:
        inputs = data["inputs"]
    _check(list(inputs.T), dtype, physx_exact)


# full float range, with the values that steer the branches drawn often
_SPECIAL = st.sampled_from(
    [0.0, -0.0, np.nan, np.inf, -np.inf, PX_EPS_F32, PX_EPS_F32 / 2, PX_MAX_F32, 5e-324, 1e-310, 1e-45, 1.0]
)


def _floats(width: int, finite: bool) -> st.SearchStrategy[float]:
    if finite:
        return st.one_of(
            st.floats(width=width, allow_nan=False, allow_infinity=False), st.floats(-10, 10, width=width)
        )
    return st.one_of(_SPECIAL, st.floats(width=width), st.floats(-10.0, 10.0, width=width))


@st.composite
def _rows(draw: st.DrawFn, width: int) -> list[Array]:
    """Eight argument arrays; some elements tie r with the gradient or 1/R, or dev with max_v.

    Half the draws are finite but for a few special values planted in single elements, so that a
    lone NaN or inf meets otherwise clean rows (the implementation checks for NaN per call).
    """
    real = np.float32 if width == 32 else np.float64
    n = draw(st.integers(1, 24))
    finite = draw(st.booleans())
    args = [draw(hnp.arrays(real, n, elements=_floats(width, finite))) for _ in range(8)]
    if finite:
        for _ in range(draw(st.integers(0, 3))):
            args[draw(st.integers(0, 7))][draw(st.integers(0, n - 1))] = draw(_SPECIAL)
    v0, x0, _, r, max_v, _, grad, resist = args
    with np.errstate(all="ignore"):
        ties = draw(hnp.arrays(np.int8, n, elements=st.integers(0, 5)))
        grad[ties == 1] = r[ties == 1]  # r - g = 0: flat speed curve
        grad[ties == 2] = -r[ties == 2]  # r + g = 0: ignored curve
        resist[ties == 3] = real(1.0) / r[ties == 3]  # r - 1/R ~ 0: flat resistance curve
        v0[ties == 4] = x0[ties == 4] * r[ties == 4] - max_v[ties == 4]  # dev = max_v
        v0[ties == 5] = x0[ties == 5] * r[ties == 5] + max_v[ties == 5]  # dev = -max_v
    return args


@settings(max_examples=400, deadline=None)
@given(args=_rows(32), physx_exact=st.booleans())
def test_equals_the_literal_port_float32(args: list[Array], physx_exact: bool) -> None:
    """Match the literal port in float32 on any inputs, NaN, inf and subnormals included."""
    _check(args, np.float32, physx_exact)


@settings(max_examples=400, deadline=None)
@given(args=_rows(64), physx_exact=st.booleans())
def test_equals_the_literal_port_float64(args: list[Array], physx_exact: bool) -> None:
    """Match the literal port in float64 on any inputs, NaN, inf and subnormals included."""
    _check(args, np.float64, physx_exact)


# edge-heavy physical inputs (moved from the former test_envelope_fast_clamp.py)
_EDGY = st.sampled_from([0.0, PX_EPS_F32 / 2, PX_EPS_F32, 1e-30, 0.5, 1.0, 2.0, 1e30, np.inf])
_VALUE = st.one_of(_EDGY, st.floats(min_value=-1e6, max_value=1e6, allow_subnormal=False))
_NONNEG = st.one_of(_EDGY, st.floats(min_value=0, max_value=1e6, allow_subnormal=False))


@settings(max_examples=300, deadline=None)
@given(data=st.data(), n=st.integers(min_value=1, max_value=30))
def test_equals_the_literal_port_on_edge_heavy_inputs(data: st.DataObject, n: int) -> None:
    """Match the literal port on mixed, edge-heavy float64 inputs, in both modes."""
    signed = [data.draw(hnp.arrays(np.float64, n, elements=_VALUE)) for _ in range(3)]
    nonneg = [data.draw(hnp.arrays(np.float64, n, elements=_NONNEG)) for _ in range(5)]
    v0, x0, x = signed
    r, max_v, max_x, grad, resist = nonneg
    # make denominators collide exactly sometimes: response == gradient
    if data.draw(st.booleans()):
        grad = r.copy()
    for physx_exact in (True, False):
        _check([v0, x0, x, r, max_v, max_x, grad, resist], np.float64, physx_exact)


def test_scalar_and_broadcast_arguments() -> None:
    """Broadcast scalar envelope parameters against array states, and keep a scalar call 0-d."""
    rng = np.random.default_rng(0)
    v0, x, r = rng.normal(0, 4, 1000), rng.normal(0, 0.2, 1000), rng.uniform(0.2, 3, 1000)
    for physx_exact in (True, False):
        ours = clamp_drive_impulse(v0, 0.0, x, r, 3.0, 0.1, 2.0, 0.01, physx_exact=physx_exact)
        expected = oracle(v0, 0.0, x, r, 3.0, 0.1, 2.0, 0.01, physx_exact=physx_exact)
        assert _same_value(ours, expected).all()
        assert (
            clamp_drive_impulse(1.0, 0.0, 5.0, 1.0, 3.0, 0.1, 2.0, 0.01, physx_exact=physx_exact).shape == ()
        )
    # the result has the broadcast shape of all arguments and is a writable array
    wide = clamp_drive_impulse(0.0, 0.0, 1.0, 0.0, np.arange(4.0), 2.0, 0.0, 0.0)
    assert wide.shape == (4,) and wide.flags.writeable


def test_each_mirror_fix_matters() -> None:
    """Give PhysX's answer where its negative branch is not the mirror of the positive one."""
    inf = np.inf
    # falling curve, one NaN bound (inf - inf): PhysX takes PxMax(PxMax(b1, b2), x) = x -> -1
    falling = (inf, 0.0, -1.0, -1.0, inf, 10.0, 0.5, 0.0)
    # flat curve (r == G) on a NaN gap: the negative branch says no, the interval is empty -> 0
    flat_nan = (inf, 0.0, -1.0, 1.0, inf, 10.0, 1.0, 0.0)
    for args, expected in ((falling, -1.0), (flat_nan, 0.0)):
        assert float(oracle(*args, physx_exact=True)) == expected
        for dtype in (np.float32, np.float64):
            assert float(clamp_drive_impulse(*args, dtype=dtype, physx_exact=True)) == expected
        assert float(clamp_drive_impulse(*args)) == 0.0  # the default lets go on a NaN bound

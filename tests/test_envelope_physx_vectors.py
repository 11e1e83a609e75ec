"""Differential test of ``clamp_drive_impulse`` against PhysX's own ``Dy::clampDriveImpulse``.

``golden/physx_clamp_drive_impulse.npz`` holds float32 inputs drawn per edge category and the
results of the unmodified PhysX function on them (provenance: ``golden/ATTRIBUTION.md``). PhysX's
arithmetic is the opt-out ``physx_exact=True``: its float32 mode must reproduce every row bit for
bit (the sign of a zero and NaN included). Its float64 mode is the same algorithm without float32
rounding: it agrees within relative 1e-6, except on a counted set of rows where PhysX's own float32
arithmetic changes the outcome (an overflow, a zero/empty-interval flip, or cancellation that a
per-row float32 error bound accounts for). The default mode (the effort cap kept, never NaN)
changes a counted set of rows. Every count is asserted exactly so any change shows up.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drive_envelope import clamp_drive_impulse
from drive_envelope._src.envelope.clamp import CLAMP_DRIVE_IMPULSE_ARGS

GOLDEN = Path(__file__).parent / "golden" / "physx_clamp_drive_impulse.npz"
PHYSX_COMMIT = "a3d8a641de4c3014fd56704af0f50b8be7e9778b"
COLUMNS = CLAMP_DRIVE_IMPULSE_ARGS
# every edge category the issue asks for, with the fewest rows we accept
MIN_ROWS = {
    "physical": 2000,
    "resistance_zero": 1500,
    "gradient_zero": 1500,
    "max_vel_inf": 1500,
    "max_vel_zero": 1500,
    "max_effort_zero": 1000,
    "far_outside": 1500,
    "applied_impulse": 2000,
    "zero_request": 800,
    "tiny": 1500,
    "huge": 1500,
    "near_denom_gradient": 2000,
    "near_denom_resistance": 2000,
    "near_dev_max": 2000,
    "negative_request": 1000,
    "response_zero": 1000,
    "special_values": 2000,
    "nan_input": 500,
    "flat_overflow": 200,
}

RTOL = 1e-6
# FLT_TRUE_MIN = 2^-149: PhysX returns a float32, which cannot resolve a smaller difference
ATOL = 2.0**-149
U32 = 2.0**-24  # unit roundoff of float32 arithmetic
EPS32 = 2.0**-23  # PhysX's PX_EPS_F32 guard on denominators
FLT_MAX = float(np.finfo(np.float32).max)

# Rows where float64 mode differs from PhysX by more than RTOL/ATOL, per cause and category.
# overflow: a float32 intermediate (x0*r, 1/R, max_impulse/R, a bound, ...) is inf, finite in float64.
# flip: one result is zero and the other is not (a bound or the empty-interval test flips).
# rounding: both non-zero and equal within twice the first-order float32 error bound of the
#   bound formula that produced them (cancellation in dev -+ max or in the denominator).
EXPECTED_EXCEPTIONS: dict[str, dict[str, int]] = {
    "overflow": {"huge": 10, "special_values": 24},
    "flip": {"huge": 25, "near_dev_max": 6, "special_values": 2},
    "rounding": {
        "applied_impulse": 202,
        "gradient_zero": 2,
        "huge": 1,
        "max_vel_inf": 2,
        "nan_input": 1,
        "near_denom_gradient": 17,
        "near_dev_max": 57,
        "negative_request": 3,
        "physical": 8,
        "response_zero": 11,
        "special_values": 2,
    },
}

# Rows the default mode changes, per category: against PhysX itself in float32, against
# physx_exact=True in float64. PhysX returned NaN (78 rows, NaN inputs), more than max_impulse (249
# in float32: 104 by one or two ulps of max_impulse/R, the rest through a NaN or overflowing bound
# it dropped), FLT_MAX for a request of a few N*m*s (178, flat_overflow), or a number after
# dropping a NaN bound (320); the default gives 0 or stays within the cap.
GUARD_CHANGES: dict[str, dict[str, int]] = {
    "float32": {"flat_overflow": 178, "huge": 8, "nan_input": 491, "special_values": 46, "tiny": 102},
    "float64": {"flat_overflow": 178, "huge": 7, "nan_input": 491, "special_values": 30, "tiny": 58},
}

Array = npt.NDArray[Any]


class Vectors(NamedTuple):
    """The golden table, loaded once."""

    inputs: Array
    """``(N, 8)`` float32 arguments in :data:`COLUMNS` order."""
    expected: Array
    """``(N,)`` float32 results of PhysX ``clampDriveImpulse``."""
    category: Array
    """``(N,)`` category name of each row."""
    columns: tuple[str, ...]
    """Column names stored with the table."""
    commit: str
    """PhysX commit the results came from."""


@pytest.fixture(scope="module")
def vectors() -> Vectors:
    with np.load(GOLDEN, allow_pickle=False) as data:
        names = data["category_names"]
        return Vectors(
            inputs=data["inputs"],
            expected=data["expected"],
            category=names[data["category"]],
            columns=tuple(str(c) for c in data["columns"]),
            commit=str(data["physx_commit"]),
        )


def _per_category(mask: Array, vectors: Vectors) -> dict[str, int]:
    return dict(sorted(Counter(str(c) for c in vectors.category[mask]).items()))


def _show(mask: Array, vectors: Vectors, got: Array, limit: int = 5) -> str:
    rows = np.flatnonzero(mask)[:limit]
    return "\n".join(
        f"  row {i} [{vectors.category[i]}] in={vectors.inputs[i].tolist()} "
        f"physx={vectors.expected[i]!r} ours={got[i]!r}"
        for i in rows
    )


def _ours(vectors: Vectors, dtype: type) -> Array:
    return clamp_drive_impulse(*vectors.inputs.T, dtype=dtype, physx_exact=True)


def test_vectors_come_from_the_recorded_physx_commit(vectors: Vectors) -> None:
    """Check the table's provenance, column order, dtype and size."""
    assert vectors.commit == PHYSX_COMMIT
    assert vectors.columns == COLUMNS
    assert vectors.inputs.dtype == np.float32 and vectors.expected.dtype == np.float32
    assert vectors.inputs.shape == (len(vectors.expected), len(COLUMNS))
    assert len(vectors.expected) >= 30_000


def test_every_edge_category_is_present(vectors: Vectors) -> None:
    """Cover each required edge category with at least its minimum number of rows."""
    counts = Counter(str(c) for c in vectors.category)
    short = {name: counts.get(name, 0) for name, need in MIN_ROWS.items() if counts.get(name, 0) < need}
    assert not short, f"categories below their minimum row count: {short}"


def test_float32_mode_matches_physx_exactly(vectors: Vectors) -> None:
    """Reproduce PhysX bit for bit in float32 mode (-0.0 == 0.0, NaN rows stay NaN)."""
    got = _ours(vectors, np.float32)
    assert got.dtype == np.float32
    expected = vectors.expected
    same = (got == expected) | (np.isnan(got) & np.isnan(expected))
    assert same.all(), (
        f"{int((~same).sum())} rows differ from PhysX, per category {_per_category(~same, vectors)}:\n"
        + _show(~same, vectors, got)
    )
    # and the bits themselves: the sign of every zero, the pattern of every NaN
    bits = got.view(np.uint32) == expected.view(np.uint32)
    assert bits.all(), f"{int((~bits).sum())} rows differ in their bits:\n" + _show(~bits, vectors, got)


def test_default_mode_changes_only_the_counted_rows(vectors: Vectors) -> None:
    """Change only the counted rows by default, each to a number within the cap and the request."""
    request = vectors.inputs[:, 2].astype(np.float64)
    cap = vectors.inputs[:, 5].astype(np.float64)
    for dtype, reference in ((np.float32, vectors.expected), (np.float64, _ours(vectors, np.float64))):
        guarded = clamp_drive_impulse(*vectors.inputs.T, dtype=dtype)
        changed = ~((guarded == reference) | (np.isnan(guarded) & np.isnan(reference)))
        assert _per_category(changed, vectors) == GUARD_CHANGES[np.dtype(dtype).name]
        result = guarded.astype(np.float64)
        assert not np.isnan(result).any()
        zero = result == 0.0  # also where the cap or the request is NaN or the cap negative
        assert ((np.abs(result) <= cap) | zero).all() and ((np.abs(result) <= np.abs(request)) | zero).all()
        assert ((np.sign(result) * np.sign(request) >= 0.0) | zero).all()


def _curves(cols: list[Array]) -> list[tuple[Array, Array]]:
    """The (max, slope) pair of each curve as PhysX forms it: (maxJointVel, G) and (maxImpulse/R, 1/R)."""
    _, _, _, _, max_v, max_x, grad, resist = cols
    has_r = resist != 0.0
    safe = np.where(has_r, resist, 1.0)
    return [(max_v, grad), (np.where(has_r, max_x / safe, np.nan), np.where(has_r, 1.0 / safe, np.nan))]


def _intermediates(cols: list[Array]) -> list[Array]:
    """Every quantity PhysX computes before selecting bounds, in the dtype of ``cols``."""
    v0, x0, _, r = cols[:4]
    product = x0 * r
    dev = product - v0
    out = [product, dev]
    for max_, slope in _curves(cols):
        out += [max_, slope]
        for num in (dev - max_, dev + max_):
            for den in (r - slope, r + slope):
                used = np.abs(den) >= EPS32  # PhysX never divides by a guarded denominator
                out += [num, den, np.where(used, num / np.where(used, den, 1.0), 0.0)]
    return out


def _float32_overflow(inputs: Array) -> Array:
    """Rows where a float32 intermediate is +-inf while the float64 one is finite."""
    cols32 = list(inputs.T)
    cols64 = list(inputs.T.astype(np.float64))
    flags = [
        np.isinf(a32) & np.isfinite(a64)
        for a32, a64 in zip(_intermediates(cols32), _intermediates(cols64), strict=True)
    ]
    return np.logical_or.reduce(flags)


def _rounding_bound(inputs: Array, result64: Array) -> Array:
    """First-order bound on PhysX's float32 error for the bound formula that produced ``result64``.

    A bound is ``(dev -+ M) / (r -+ G)`` with ``dev = x0*r - v0``; each float32 operation adds a
    relative error of at most 2^-24 (plus 2^-149 once results are subnormal). The clamp takes
    minima and maxima of bounds, which never amplify an error, so the error of the result is that
    of a bound near it; we take the largest such bound error, doubled for second-order terms.
    """
    cols = list(inputs.T.astype(np.float64))
    v0, x0, _, r = cols[:4]

    def rnd(value: Array) -> Array:
        return U32 * np.abs(value) + ATOL

    dev = x0 * r - v0
    err_dev = rnd(x0 * r) + rnd(dev)
    tol = np.zeros_like(result64)
    for (max_, slope), formed in zip(_curves(cols), (False, True), strict=True):
        err_max, err_slope = (rnd(max_), rnd(slope)) if formed else (0.0, 0.0)
        for num in (dev - max_, dev + max_):
            for den in (r - slope, r + slope):
                bound = num / den
                err = 2.0 * ((err_dev + err_max + rnd(num)) + np.abs(bound) * (err_slope + rnd(den)))
                err = err / np.abs(den) + rnd(bound)
                near = np.isfinite(bound) & np.isfinite(err) & (np.abs(bound - result64) <= err)
                tol = np.where(near, np.maximum(tol, err), tol)
    return 2.0 * tol


def _classify(vectors: Vectors, result64: Array) -> dict[str, Array]:
    """Split the rows where float64 mode misses RTOL/ATOL by cause (see EXPECTED_EXCEPTIONS)."""
    expected = vectors.expected.astype(np.float64)
    with np.errstate(all="ignore"):
        agree = (
            (result64 == expected)  # includes +-inf
            | (np.isnan(expected) & np.isnan(result64))
            | (np.abs(result64 - expected) <= RTOL * np.abs(expected) + ATOL)
        )
        overflow = ~agree & _float32_overflow(vectors.inputs)
        flip = ~agree & ~overflow & ((expected == 0.0) != (result64 == 0.0))
        rest = ~agree & ~overflow & ~flip
        rounding = rest & (np.abs(result64 - expected) <= _rounding_bound(vectors.inputs, result64))
    return {"overflow": overflow, "flip": flip, "rounding": rounding, "unexplained": rest & ~rounding}


def test_float64_mode_agrees_with_physx_up_to_float32_rounding(vectors: Vectors) -> None:
    """Agree within relative 1e-6 in float64 mode except on the counted float32-rounding rows."""
    result64 = _ours(vectors, np.float64)
    assert result64.dtype == np.float64
    classes = _classify(vectors, result64)
    unexplained = classes.pop("unexplained")
    assert not unexplained.any(), (
        f"{int(unexplained.sum())} float64 rows differ beyond float32 rounding, per category "
        f"{_per_category(unexplained, vectors)}:\n" + _show(unexplained, vectors, result64)
    )
    opposite = np.sign(vectors.expected) * np.sign(result64) < 0
    assert not opposite.any(), "float64 mode and PhysX chose opposite signs:\n" + _show(
        opposite, vectors, result64
    )
    counts = {name: _per_category(mask, vectors) for name, mask in classes.items()}
    assert counts == EXPECTED_EXCEPTIONS, f"exception rows per cause and category changed: {counts}"


def test_physx_never_grows_or_flips_a_request_outside_the_overflow_corner(vectors: Vectors) -> None:
    """Keep PhysX, and both our modes, NaN-free, no larger than the request and of its sign."""
    x = vectors.inputs[:, 2].astype(np.float64)
    sane = ~np.isnan(vectors.inputs).any(axis=1) & (vectors.category != "flat_overflow")
    for name, result in (
        ("physx", vectors.expected),
        ("float32", _ours(vectors, np.float32)),
        ("float64", _ours(vectors, np.float64)),
    ):
        res = result.astype(np.float64)
        bad = sane & (np.isnan(res) | (np.abs(res) > np.abs(x)) | (np.sign(res) * np.sign(x) < 0.0))
        assert not bad.any(), f"{name}: {_per_category(bad, vectors)}\n" + _show(bad, vectors, result)


def test_physx_grows_a_request_only_with_a_flat_curve_at_overflowing_speed(vectors: Vectors) -> None:
    """Return FLT_MAX, not the request, when the flat speed curve's bound overflows (PhysX quirk)."""
    x = vectors.inputs[:, 2]
    grows = np.abs(vectors.expected) > np.abs(x)
    assert set(vectors.category[grows]) == {"flat_overflow"}
    assert np.all(np.abs(vectors.expected[grows]) == np.float32(FLT_MAX))
    assert np.all(vectors.inputs[grows, 5] == np.float32(FLT_MAX))  # only with max_impulse = FLT_MAX


# -- properties on inputs where no float32 intermediate can overflow ---------------------------

_MAGNITUDE = st.one_of(
    st.just(0.0),
    st.floats(min_value=float(np.float32(1e-15)), max_value=float(np.float32(1e15)), width=32),
)
_SIGNED = st.tuples(st.sampled_from([-1.0, 1.0]), _MAGNITUDE).map(lambda p: p[0] * p[1])


@st.composite
def _clamp_args(draw: st.DrawFn) -> tuple[float, ...]:
    """Arguments within 1e-15..1e15, sometimes with response == gradient or == 1/R (flat curves)."""
    response = draw(_MAGNITUDE)
    tie = draw(st.sampled_from(["none", "gradient", "resistance"]))
    gradient = response if tie == "gradient" else draw(_MAGNITUDE)
    resistance = draw(_MAGNITUDE)
    if tie == "resistance" and response > 0.0:
        resistance = float(np.float32(1.0) / np.float32(response))
    max_vel = draw(st.one_of(st.just(math.inf), _MAGNITUDE))
    v0, x0, x = draw(_SIGNED), draw(_SIGNED), draw(_SIGNED)
    return (v0, x0, x, response, max_vel, draw(_MAGNITUDE), gradient, resistance)


@settings(max_examples=300, deadline=None)
@given(args=_clamp_args(), dtype=st.sampled_from([np.float32, np.float64]))
def test_clamp_never_nan_grown_or_flipped(args: tuple[float, ...], dtype: type) -> None:
    """Never return NaN, more than the request, or the opposite sign for bounded finite inputs."""
    result = float(clamp_drive_impulse(*args, dtype=dtype))
    request = float(np.asarray(args[2], dtype=dtype))
    assert not math.isnan(result)
    assert abs(result) <= abs(request)
    assert result * request >= 0.0

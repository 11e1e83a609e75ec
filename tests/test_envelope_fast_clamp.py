"""The float64 fast path of ``clamp_drive_impulse`` gives the literal port's numbers."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from drive_envelope import clamp_drive_impulse
from drive_envelope._src.envelope.clamp import PX_EPS_F32

_EDGY = st.sampled_from([0.0, PX_EPS_F32 / 2, PX_EPS_F32, 1e-30, 0.5, 1.0, 2.0, 1e30, np.inf])
_VALUE = st.one_of(_EDGY, st.floats(min_value=-1e6, max_value=1e6, allow_subnormal=False))
_NONNEG = st.one_of(_EDGY, st.floats(min_value=0, max_value=1e6, allow_subnormal=False))


def _literal(*args: np.ndarray) -> np.ndarray:
    """Force the literal port: a trailing NaN row routes the call around the fast path."""
    padded = [
        np.append(np.broadcast_to(a, np.broadcast_shapes(*(b.shape for b in args))), np.nan) for a in args
    ]
    return clamp_drive_impulse(*padded)[:-1]


@settings(max_examples=300, deadline=None)
@given(
    data=st.data(),
    n=st.integers(min_value=1, max_value=30),
)
def test_fast_path_equals_literal_port(data: st.DataObject, n: int) -> None:
    """Match the literal port on mixed, edge-heavy inputs (zeros compared by value)."""
    signed = [data.draw(hnp.arrays(np.float64, n, elements=_VALUE)) for _ in range(3)]
    nonneg = [data.draw(hnp.arrays(np.float64, n, elements=_NONNEG)) for _ in range(5)]
    v0, x0, x = signed
    r, max_v, max_x, grad, resist = nonneg
    # make denominators collide exactly sometimes: response == gradient or 1/R
    if data.draw(st.booleans()):
        grad = r.copy()
    fast = clamp_drive_impulse(v0, x0, x, r, max_v, max_x, grad, resist)
    literal = _literal(v0, x0, x, r, max_v, max_x, grad, resist)
    np.testing.assert_array_equal(fast, literal)


def test_scalar_parameters_broadcast() -> None:
    """Accept scalar envelope parameters with array states, as engines call it."""
    rng = np.random.default_rng(0)
    v0, x, r = rng.normal(0, 4, 1000), rng.normal(0, 0.2, 1000), rng.uniform(0.2, 3, 1000)
    fast = clamp_drive_impulse(v0, 0.0, x, r, 3.0, 0.1, 2.0, 0.01)
    literal = _literal(v0, np.zeros(1000), x, r, *(np.full(1000, c) for c in (3.0, 0.1, 2.0, 0.01)))
    np.testing.assert_array_equal(fast, literal)
    assert clamp_drive_impulse(1.0, 0.0, 5.0, 1.0, 3.0, 0.1, 2.0, 0.01).shape == ()

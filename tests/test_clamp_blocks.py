"""A large clamp runs in cache-sized blocks: the blocks give the bits of one whole-array call."""

from __future__ import annotations

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope._src.envelope import clamp


def _arguments(n: int, dtype: type, seed: int) -> list[np.ndarray]:
    """Random PhysX arguments with every special value sprinkled in (both slope signs, NaN, inf)."""
    rng = np.random.default_rng(seed)
    args = [
        rng.normal(0.0, 6.0, n),
        rng.normal(0.0, 0.02, n),
        rng.normal(0.0, 0.1, n),
        rng.uniform(5.0, 50.0, n),
        rng.uniform(5.0, 15.0, n),
        rng.uniform(0.02, 0.1, n),
        rng.uniform(0.0, 100.0, n),
        rng.uniform(0.0, 1e-3, n),
    ]
    specials = np.array([np.nan, np.inf, -np.inf, 0.0, -0.0, 1e-310, 1e300, -1.0])
    for a in args:
        where = rng.integers(0, n, n // 50)
        a[where] = rng.choice(specials, where.size)
    return [a.astype(dtype) for a in args]


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("exact", [False, True])
def test_blocks_give_the_bits_of_one_call(dtype: type, exact: bool) -> None:
    n = 2 * clamp._BLOCK + 12_345  # blocks and a ragged last block
    args = _arguments(n, dtype, seed=3)
    blocked = de.clamp_drive_impulse(*args, dtype=dtype, physx_exact=exact)
    with np.errstate(all="ignore"):
        whole = clamp._clamp(*args, exact=exact)
    ints = np.int64 if dtype is np.float64 else np.int32
    assert blocked.shape == (n,)
    assert np.array_equal(blocked.view(ints), np.asarray(whole, dtype=dtype).view(ints))


def test_blocks_broadcast_scalars_and_two_dimensions() -> None:
    n = 2 * clamp._BLOCK
    args = _arguments(n, np.float64, seed=4)
    grid = [a.reshape(512, -1) for a in args]
    grid[4] = np.float64(8.0)  # one envelope number for every DOF
    grid[5] = np.full((512, 1), 0.05)  # broadcast along a column
    blocked = de.clamp_drive_impulse(*grid)
    with np.errstate(all="ignore"):
        whole = clamp._clamp(*(np.asarray(a, dtype=np.float64) for a in grid), exact=False)
    assert blocked.shape == (512, n // 512)
    assert np.array_equal(blocked, whole, equal_nan=True)
    # and each element is the scalar clamp of its own arguments
    for i, j in [(0, 0), (17, n // 1024 + 8), (511, n // 512 - 1)]:
        one = de.clamp_drive_impulse(*(np.broadcast_to(a, blocked.shape)[i, j] for a in grid))
        assert float(one) == float(blocked[i, j]) or (np.isnan(one) and np.isnan(blocked[i, j]))

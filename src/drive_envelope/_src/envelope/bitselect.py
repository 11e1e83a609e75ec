"""Array passes the NumPy clamp is built from: in-place binary ufuncs and selects on bit patterns.

numpy.where branches per element: under a mask that flips at random (the sign of the requests) it
costs 3.6 ms per million float64, against 0.2 ms per integer pass; a select as ``(a ^ b) & mask ^
b`` takes three. Bit operations are exact for every value, NaN payloads and signed zeros included.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[Any]


def into(ufunc: np.ufunc, a: Array, b: Any) -> Array:
    """``ufunc(a, b)``, written into ``a`` (a temporary of ours) when it already has the result's shape."""
    fits = isinstance(a, np.ndarray) and (np.ndim(b) == 0 or a.shape == np.shape(b))
    return ufunc(a, b, out=a if fits else None)  # type: ignore[no-any-return]


_INT = {np.dtype(np.float32): np.int32, np.dtype(np.float64): np.int64}


def bits(a: Any, real: Any) -> Array:
    """The bit pattern of ``a`` as signed integers of ``real``'s width (a view, no copy of an array)."""
    return np.asarray(a, dtype=real).view(_INT[np.dtype(real)])


def int_mask(condition: Any, real: Any) -> Array:
    """``condition`` as an integer mask of ``real``'s width: all ones where true, 0 where false."""
    flags = np.asarray(condition)
    mask = np.empty(flags.shape, dtype=_INT[np.dtype(real)])
    return np.negative(flags.view(np.int8), out=mask, casting="unsafe")  # type: ignore[no-any-return]


def sign_bit_pattern(real: Any) -> Any:
    """The sign bit of ``real`` as an integer (the bit pattern of ``-0.0``)."""
    return bits(-0.0, real)


def select(mask: Array, a: Any, b: Any, real: Any) -> Array:
    """``numpy.where(mask, a, b)`` for an integer ``mask`` of :func:`int_mask`, bit for bit."""
    other = bits(b, real)
    picked = into(np.bitwise_and, np.bitwise_xor(bits(a, real), other), mask)
    return into(np.bitwise_xor, picked, other).view(real)

"""Validation of a fit's inputs: sample arrays and counts, each refused in one line naming it."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError

FloatArray = npt.NDArray[np.float64]

MAX_BOOTSTRAP = 10_000
"""Most bootstrap resamples: each refits the whole model, and more add nothing to a 95 % interval."""
MAX_SAMPLE = 1e100
"""Largest |velocity| or |effort| a fit accepts [SI]: the fit squares and sums samples, which must
stay far from float64's limit (real actuators are below 1e6)."""
MIN_SCALE = 1e-100
"""Smallest largest-|velocity| or largest-|effort| a fit accepts, unless all are 0 [SI]: slopes are
ratios of ranges, and ranges near float64's smallest numbers overflow them."""
RESOLUTION = 1e-150
"""Magnitudes below this fraction of the largest sample of their column are read as 0: they are
130 orders of magnitude below float64's resolution next to it, change no fitted digit, and would
overflow the slope search (ratios of a range to a range of subnormal numbers)."""


def check_count(name: str, value: object, high: int | None) -> None:
    """Refuse anything but an integer in ``0 .. high`` (``high`` None: no upper bound)."""
    if (
        isinstance(value, bool)
        or not isinstance(value, int)
        or value < 0
        or (high is not None and value > high)
    ):
        span = f"in 0..{high}" if high is not None else ">= 0"
        raise InputError(f"{name}: expected an integer {span}, got {value!r}")


def fit_samples_input(
    velocity: npt.ArrayLike, effort: npt.ArrayLike
) -> tuple[FloatArray, FloatArray, npt.NDArray[np.int8]]:
    """``|velocity|``, ``|effort|`` and their quadrant pair as flat arrays, validated for a fit.

    The pair is ``sign(velocity) * sign(effort)``: 1 driving (quadrants I and III), -1 braking (II
    and IV), 0 when either is 0.
    """
    try:
        v = np.asarray(velocity, dtype=np.float64).ravel()
        e = np.asarray(effort, dtype=np.float64).ravel()
    except (TypeError, ValueError) as exc:
        raise InputError(f"fit: expected arrays of numbers for velocity and effort ({exc})") from None
    x, y = np.abs(v), np.abs(e)
    if x.shape != y.shape:
        raise InputError(
            f"fit: velocity and effort must have the same number of samples, got {x.size} and {y.size}"
        )
    if x.size < 3:
        raise InputError(f"fit: {x.size} sample(s); expected at least 3 samples")
    for name, values in (("velocity", x), ("effort", y)):
        if not np.isfinite(values).all():
            index = int(np.flatnonzero(~np.isfinite(values))[0])
            raise InputError(
                f"fit: {name} sample {index} is {float(values[index])!r}; expected finite numbers"
            )
        largest = float(values.max())
        if largest > MAX_SAMPLE:
            raise InputError(
                f"fit: |{name}| up to {largest:.6g} [SI]; expected at most {MAX_SAMPLE:g} "
                "(values this large overflow the fit; check the log's units)"
            )
        if 0.0 < largest < MIN_SCALE:
            raise InputError(
                f"fit: |{name}| at most {largest:.6g} [SI]; expected all 0 or a largest value of at least "
                f"{MIN_SCALE:g} (check the log's units)"
            )
        values[values < RESOLUTION * largest] = 0.0  # x, y are fresh arrays: the caller's data is kept
    pair = (np.sign(v) * np.sign(e)).astype(np.int8)
    pair[(x == 0.0) | (y == 0.0)] = 0
    return x, y, pair

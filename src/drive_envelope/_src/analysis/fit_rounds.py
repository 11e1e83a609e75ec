"""The rounds of a fit: select the frontier, fit it, and widen the band to the noise the fit sees.

A containing fit (no outlier allowance) takes one round: on the hull's own samples when they are
clean (:func:`.clean_hull`), within :data:`DEFAULT_BAND` when they are noisy. A central fit starts
from :data:`DEFAULT_BAND`, which holds only the top of a noisy frontier, and widens the band round
by round (at most doubling it) to six standard deviations of the noise its outside samples show,
until the band stops growing; spikes are set aside from the hull in every round
(:func:`.select_frontier`).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.fit_frontier import (
    DEFAULT_BAND,
    ON_HULL,
    Frontier,
    clean_hull,
    select_frontier,
)
from drive_envelope._src.envelope.line_choice import choose_model
from drive_envelope._src.envelope.line_model import Model, line_residuals

FloatArray = npt.NDArray[np.float64]

_ROUNDS = 8  # frontier rounds: a central fit widens the band to its noise (it settles in 2 to 4)
_MAX_BAND = 0.5  # the band never widens beyond half the hull's radius, however noisy the samples
_NOISE_SAMPLES = 5  # fewest samples outside a fit that estimate its noise
_GROWTH = 2.0  # the band at most doubles per round, so one misfit cannot widen it at once
_FEW = 20  # a central fit's frontier smaller than this widens even without a noise estimate


def _noise_band(model: Model, x: FloatArray, y: FloatArray, q: float, base: float) -> float:
    """The band a fit's noise calls for: six standard deviations of its scatter, at least ``base``.

    The samples outside a fit are the upper tail of the noise beyond the fit's ``1 - q`` quantile
    (interior samples cannot be outside), so their median excess over their line is
    ``(z(1 - q/2) - z(1 - q)) * sigma`` for Gaussian noise: 0.674 sigma at q = 0.5. The excess is
    taken as a fraction of the data's range along the line's axis, close to the radial fraction
    the band is measured in.
    """
    if q == 0.0:
        return base
    excess = line_residuals(model, x, y)
    outside = excess[excess > 0.0]
    if outside.size < _NOISE_SAMPLES:  # too few to tell: a frontier this small is the top of the noise
        return _GROWTH * base if x.size < _FEW else base
    normal = statistics.NormalDist()
    sigma = float(np.median(outside)) / (normal.inv_cdf(1.0 - q / 2.0) - normal.inv_cdf(1.0 - q))
    return min(max(base, 6.0 * sigma), max(base, _MAX_BAND))


def frontier_fit(
    x: FloatArray,
    y: FloatArray,
    q: float,
    fixed: Mapping[str, float],
    least: int | None,
    given: float | None,
) -> tuple[Frontier, Model, str]:
    """Select the frontier and fit it.

    The band is ``given`` (the user's); else for a containing fit the hull samples when they are
    clean and :data:`DEFAULT_BAND` when they are noisy; with an outlier allowance it grows from
    :data:`DEFAULT_BAND` to six times the noise the central fit sees, round by round.

    Args:
        x: ``|velocity|`` of every sample [rad/s or m/s].
        y: ``|effort|`` of every sample [N*m or N].
        q: Outlier allowance per line.
        fixed: Parameters held by the user [SI].
        least: Fewest samples that identify a line; None: ``max(5, 2 %)`` of the frontier.
        given: The frontier band the user chose, or None.

    Returns:
        The frontier, the model fitted to it and a note on the model's structure.
    """
    if given is not None or q == 0.0:
        band = given if given is not None else (ON_HULL if clean_hull(x, y) else DEFAULT_BAND)
        return _fit_band(x, y, q, fixed, least, band)[:3]
    band = DEFAULT_BAND
    for _ in range(_ROUNDS):
        frontier, model, note, two = _fit_band(x, y, q, fixed, least, band)
        # the richer model misfits less, so its outside samples are closer to pure noise
        noise = _noise_band(two or model, x[frontier.mask], y[frontier.mask], q, band)
        wider = min(noise, _GROWTH * band)
        if wider <= band:
            break
        band = wider
    return frontier, model, note


def _fit_band(
    x: FloatArray, y: FloatArray, q: float, fixed: Mapping[str, float], least: int | None, band: float
) -> tuple[Frontier, Model, str, Model | None]:
    """The frontier within ``band`` and the model it supports (see :func:`choose_model`)."""
    frontier = select_frontier(x, y, band, q)
    xf, yf = x[frontier.mask], y[frontier.mask]
    model, note, two = choose_model(xf, yf, q, fixed, least or max(5, math.ceil(0.02 * xf.size)), band)
    return frontier, model, note, two

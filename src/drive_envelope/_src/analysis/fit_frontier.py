"""The frontier of a fit: the samples near the upper hull of ``|effort|`` over ``|velocity|``.

A log of real operation is mostly samples inside the envelope (the drive was not saturated); only
the samples on its boundary say where the lines are. Averaging a fit's cost over every sample lets
the interior swamp the few saturated samples, so the lines are fitted to the frontier only:

* the **hull** is the upper boundary of the samples' downward closure (the smallest region of the
  envelope's shape, convex and containing every point below and left of a sample): a concave chain
  from ``(0, max |tau|)`` to ``(max |v|, 0)``;
* a sample's **gap** is how far inside the hull it lies along its ray from the origin, as a fraction
  of the hull's radius there (0 on the hull, 1 at the origin, negative outside). Along a ray the
  ratio does not depend on the units of either axis, so one band serves every joint;
* the **frontier** is every sample with a gap of at most ``band``, plus every sample outside the hull.

With an outlier allowance (``q > 0``) a few wild samples (sensor spikes) would lift the hull far above
the saturated samples, so hull layers standing clear of the samples beneath (by more than half the
band) are peeled and set aside first, at most ``min(q, 10 %)`` of the frontier beneath them
(:func:`_peel`). Set-aside samples lie outside the hull and stay in the frontier, where the lines'
own allowance treats them as outliers.

The envelope is symmetric, so driving samples (effort along the velocity, quadrants I and III) and
braking samples (II and IV) bound the same lines; the hull is that of both pairs together, and the
report says which pair the deciding samples came from.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]
BoolArray = npt.NDArray[np.bool_]

DEFAULT_BAND = 0.01
"""Frontier band a fit with an outlier allowance starts from (1 % of the hull's radius, ``check``'s
on-limit band); it widens to six times the noise the fit sees."""
ON_HULL = 1e-4
"""Frontier band of a containing fit (no outlier allowance) of clean samples: the samples on the
hull, up to the rounding of a log printed to five or six digits. A containing envelope is decided by
the hull alone; samples inside it, however close, would only pull a line toward a neighbouring hull
edge. Noisy samples (see :func:`clean_hull`) get :data:`DEFAULT_BAND` instead."""
_MIN_FRONTIER = 3  # a fit needs at least this many samples
_PEEL_ROUNDS = 32  # hull layers peeled at most when looking for spikes
_SPIKE_SHARE = 0.1  # spikes are at most this fraction of the frontier, whatever the allowance


@dataclass(frozen=True, kw_only=True, slots=True)
class Frontier:
    """The samples a fit's lines are fitted to."""

    mask: BoolArray
    """True for frontier samples, one per input sample."""
    gap: FloatArray
    """Radial gap of each sample to the hull: fraction of the hull's radius, < 0 outside, 1 at 0."""
    band: float
    """Largest gap of a frontier sample (fraction of the hull's radius)."""
    set_aside: int
    """Samples set aside as spikes before the hull was drawn (outside it, kept in the frontier)."""
    hull_velocity: FloatArray
    """``|velocity|`` of the hull's vertices, from 0 to the largest [rad/s or m/s]."""
    hull_effort: FloatArray
    """``|effort|`` of the hull's vertices, from the largest to 0 [N*m or N]."""


def _pareto(x: FloatArray, y: FloatArray, index: IntArray) -> IntArray:
    """The samples of ``index`` no other sample of ``index`` dominates (>= in both, > in one).

    Only these can be hull vertices. Returned in ascending ``x`` (so descending ``y``).
    """
    if index.size == 0:
        return index
    order = index[np.lexsort((-y[index], -x[index]))]  # x descending, then y descending
    ys = y[order]
    before = np.maximum.accumulate(np.concatenate(([-np.inf], ys[:-1])))
    return order[ys > before][::-1]


def hull_chain(px: FloatArray, py: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Vertices of the upper hull of the downward closure of Pareto points (``px`` ascending).

    Args:
        px: ``|velocity|`` of Pareto-maximal samples, ascending [rad/s or m/s].
        py: ``|effort|`` of the same samples, descending [N*m or N].

    Returns:
        The concave chain from ``(0, max py)`` to ``(max px, 0)`` (collinear points dropped).
    """
    points = list(zip(px.tolist(), py.tolist(), strict=True))
    if points[0][0] > 0.0:
        points.insert(0, (0.0, points[0][1]))
    if points[-1][1] > 0.0:
        points.append((points[-1][0], 0.0))
    chain: list[tuple[float, float]] = []
    for p in points:
        while len(chain) >= 2:
            (ox, oy), (ax, ay) = chain[-2], chain[-1]
            if (ax - ox) * (p[1] - oy) - (ay - oy) * (p[0] - ox) < 0.0:
                break  # a right turn: chain[-1] stays a vertex
            chain.pop()
        chain.append(p)
    hx, hy = zip(*chain, strict=True)
    return np.array(hx), np.array(hy)


def gauge(hx: FloatArray, hy: FloatArray, x: FloatArray, y: FloatArray) -> FloatArray:
    """Each point's radius as a multiple of the hull's radius along the same ray (1 on the hull)."""
    nx, ny = hy[:-1] - hy[1:], hx[1:] - hx[:-1]  # outward normals of the edges (both >= 0)
    c = nx * hx[:-1] + ny * hy[:-1]
    # the edge a ray crosses brackets the ray's angle; its neighbours guard against rounding
    angles = np.arctan2(hy, hx)[::-1]  # ascending, from 0 at (max x, 0) to pi/2 at (0, max y)
    k = hx.size - 1 - np.searchsorted(angles, np.arctan2(y, x), side="left")
    k = np.clip(k, 0, c.size - 1)
    best = np.zeros(x.size)
    for shift in (-1, 0, 1):
        e = np.clip(k + shift, 0, c.size - 1)
        best = np.maximum(best, (nx[e] * x + ny[e] * y) / c[e])
    return best


def _hull_of(x: FloatArray, y: FloatArray, kept: IntArray) -> tuple[FloatArray, FloatArray] | None:
    """The hull of the ``kept`` samples; None when they have no extent on either axis."""
    if kept.size == 0 or not (float(x[kept].max()) > 0.0 and float(y[kept].max()) > 0.0):
        return None
    front = _pareto(x, y, kept)
    return hull_chain(x[front], y[front])


def _peel(x: FloatArray, y: FloatArray, q: float, band: float) -> BoolArray:
    """Samples set aside as spikes: those standing clear above the hull of the samples beneath.

    The hull's outer layers are peeled one after another while each layer holds a sample standing
    more than half the band above the hull of what is left (a layer with none is the frontier
    itself: a noisy frontier's layers stand out by about the noise, far less). Spikes shield one
    another, so at each depth the spikes are all peeled samples standing that far above the hull
    that remains; the largest such set that is at most a fraction ``min(q, 0.1)`` of the frontier
    beneath it is set aside. A clean log's true lines stand out above the interior too, but they
    are far more than a tenth of the interior near the hull beneath them, so they stay.
    """
    share = min(q, _SPIKE_SHARE)
    peeled = np.zeros(x.size, dtype=bool)
    best = np.zeros(x.size, dtype=bool)
    hull = _hull_of(x, y, np.arange(x.size))
    for _ in range(_PEEL_ROUNDS):
        kept = np.flatnonzero(~peeled)
        if hull is None:
            break
        layer = kept[1.0 - gauge(*hull, x[kept], y[kept]) <= band / 50.0]
        rest = _hull_of(x, y, np.setdiff1d(kept, layer, assume_unique=True))
        if rest is None or not np.any(gauge(*rest, x[layer], y[layer]) - 1.0 > band / 2.0):
            break
        peeled[layer], hull = True, rest
        candidates = np.flatnonzero(peeled)
        spikes = np.zeros(x.size, dtype=bool)
        spikes[candidates[gauge(*rest, x[candidates], y[candidates]) - 1.0 > band / 2.0]] = True
        beneath = _hull_of(x, y, np.flatnonzero(~spikes))
        count = int(spikes.sum())
        if beneath is None or count <= int(best.sum()):
            continue
        if count <= share * np.count_nonzero(1.0 - gauge(*beneath, x, y) <= band):
            best = spikes
    return best


def clean_hull(x: FloatArray, y: FloatArray) -> bool:
    """Whether the samples on the hull lie along its edges (clean) rather than at its vertices (noisy).

    Saturated samples without noise lie on their lines, so most of them sit inside the hull's
    edges; with noise only the outermost sample of each stretch touches the hull, at a vertex.
    Counts the samples within :data:`ON_HULL` of the hull: clean when those inside an edge are at
    least as many as those at a vertex.
    """
    hull = _hull_of(x, y, np.arange(x.size))
    if hull is None:
        return True
    on = np.flatnonzero(1.0 - gauge(*hull, x, y) <= ON_HULL)
    corners = set(zip(hull[0].tolist(), hull[1].tolist(), strict=True))
    at_vertex = sum((a, b) in corners for a, b in zip(x[on].tolist(), y[on].tolist(), strict=True))
    return on.size - at_vertex >= at_vertex


def select_frontier(x: FloatArray, y: FloatArray, band: float, q: float = 0.0) -> Frontier:
    """The frontier samples of ``(x, y) = (|v|, |tau|)``.

    Args:
        x: ``|velocity|`` of every sample [rad/s or m/s].
        y: ``|effort|`` of every sample [N*m or N].
        band: Largest radial gap of a frontier sample (fraction of the hull's radius).
        q: The fit's outlier allowance: with ``q > 0`` spikes standing clear of the hull are set
            aside first (outside the hull, they stay frontier samples).

    Returns:
        The :class:`Frontier`. When every velocity or every effort is 0 there is no hull to speak
        of and every sample is a frontier sample.
    """
    n = x.size
    aside = _peel(x, y, q, band) if q > 0.0 else np.zeros(n, dtype=bool)
    hull = _hull_of(x, y, np.flatnonzero(~aside))
    if hull is None:
        empty = np.zeros(0)
        return Frontier(
            mask=np.ones(n, dtype=bool),
            gap=np.zeros(n),
            band=band,
            set_aside=0,
            hull_velocity=empty,
            hull_effort=empty,
        )
    gap = 1.0 - gauge(*hull, x, y)
    mask = gap <= band
    if int(mask.sum()) < min(n, _MIN_FRONTIER):  # too few near the hull: take the nearest ones
        mask[np.argsort(gap, kind="stable")[: min(n, _MIN_FRONTIER)]] = True
    return Frontier(
        mask=mask, gap=gap, band=band, set_aside=int(aside.sum()), hull_velocity=hull[0], hull_effort=hull[1]
    )

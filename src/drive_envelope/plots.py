"""Envelope plots, python-control style: compute the curve data, then draw it.

``envelope_curve(envelope) -> EnvelopeCurve`` holds the arrays (feasible polygon, boundary lines
with their equations, corner points) and needs no matplotlib. ``plot_envelope(curve_or_envelope,
points=OperatingPoints(velocity=..., effort=..., time=...), ax=..., highlight=...) -> EnvelopePlot``
draws it over plain arrays (matplotlib is imported inside the
call) and ``save_figure(plot, "fig.png")`` writes the figure atomically.
"""

from __future__ import annotations

from drive_envelope._src.plots.curve import (
    BoundaryLine,
    CornerPoint,
    EnvelopeCurve,
    OperatingPoints,
    envelope_curve,
)
from drive_envelope._src.plots.figure import FIGURE_SUFFIXES, EnvelopePlot, plot_envelope, save_figure

__all__ = [
    "FIGURE_SUFFIXES",
    "BoundaryLine",
    "CornerPoint",
    "EnvelopeCurve",
    "EnvelopePlot",
    "OperatingPoints",
    "envelope_curve",
    "plot_envelope",
    "save_figure",
]

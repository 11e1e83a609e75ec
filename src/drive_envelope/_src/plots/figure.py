"""Drawing an envelope (and trajectories over it) with matplotlib, imported lazily.

:func:`plot_envelope` draws an :class:`~drive_envelope._src.plots.curve.EnvelopeCurve` and returns
an :class:`EnvelopePlot` handle (``.figure``, ``.axes``, ``.lines``); :func:`save_figure` writes it
atomically. Figures are built with ``matplotlib.figure.Figure`` (Agg canvas), never pyplot, so no
GUI backend or global figure state is touched.

Text: a title or label given to :func:`plot_envelope` may use matplotlib mathtext (``$x_1$``);
mathtext that does not parse (``$x^$``) is an :class:`InputError` naming the text, raised before
anything is drawn. Names that come from data files (an envelope's name, a trajectory's, a joint's)
are drawn as they are written: pass them through :func:`plain_text`. Raster output is limited to
:data:`MAX_PIXELS_PER_SIDE` pixels per side and :data:`MAX_PIXELS` in all.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.atomic import atomic_path
from drive_envelope._src.plots.curve import (
    MAX_EXTENT,
    EnvelopeCurve,
    OperatingPoints,
    effort_limit_at,
    envelope_curve,
)

FIGURE_SUFFIXES = (".png", ".svg", ".pdf")
"""File types :func:`save_figure` writes."""
MAX_PIXELS_PER_SIDE = 65535
"""Widest and tallest raster figure [pixels]: the limit of matplotlib's Agg canvas."""
MAX_PIXELS = 1 << 27
"""Most pixels of a raster figure (512 MiB of RGBA) [pixels]."""

_REGION_COLOUR = "#9ecae1"
_LINE_COLOURS = {"eq1": "#d62728", "eq2": "#1f77b4"}
_MARKERS = ("o", "s", "^", "D", "v", "P")
_POINT_MARGIN = 1.15  # the window reaches this far beyond the outermost operating point


@dataclass(frozen=True, kw_only=True, slots=True)
class EnvelopePlot:
    """Handle of a drawn envelope plot."""

    figure: Any
    """The ``matplotlib.figure.Figure``."""
    axes: tuple[Any, ...]
    """``(plane,)`` or ``(plane, time, time_effort)``: the (velocity, effort) axes, then the time
    panel's velocity axes and its twin effort axes."""
    lines: dict[str, list[Any]] = field(default_factory=dict)
    """Artists by role: ``region``, ``eq1``, ``eq2``, ``corners``, ``points:<name>``,
    ``highlight``, ``velocity:<name>``, ``effort:<name>``, ``limit``."""
    curve: EnvelopeCurve | None = None
    """The curve data drawn."""


def figure_class(what: str = "plotting") -> Any:
    """``matplotlib.figure.Figure``; without matplotlib an error saying that ``what`` needs it."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise InputError(f"{what} needs matplotlib: pip install 'drive-envelope[plot]'") from None
    return Figure


def plain_text(text: str) -> str:
    """``text`` drawn literally: its dollar signs escaped, so mathtext never reads a name from a file."""
    return text.replace("\\$", "$").replace("$", "\\$")


def check_text(text: str, where: str) -> str:
    """``text`` when matplotlib can draw it (valid mathtext, if any); else an error naming ``where``.

    Raises:
        InputError: mathtext between unescaped dollar signs that does not parse (e.g. ``$x^$``).
    """
    if text.count("$") - text.count("\\$") < 2:
        return text  # no math: drawn as written
    from matplotlib.mathtext import MathTextParser

    try:
        MathTextParser("path").parse(text)
    except ValueError:
        raise InputError(
            f"{where} {text!r}: not valid matplotlib mathtext between the dollar signs; "
            "write \\$ for a dollar sign"
        ) from None
    return text


def check_figure_path(path: str | os.PathLike[str], flag: str = "--output") -> Path:
    """``path`` as a Path when its suffix is one :func:`save_figure` writes.

    Raises:
        InputError: a suffix other than ``.png``, ``.svg`` or ``.pdf``.
    """
    target = Path(path)
    if target.suffix.lower() not in FIGURE_SUFFIXES:
        raise InputError(f"{flag} {str(target)!r}: expected a .png, .svg or .pdf file name")
    return target


def _as_list(points: OperatingPoints | Sequence[OperatingPoints] | None) -> list[OperatingPoints]:
    if points is None:
        return []
    if isinstance(points, OperatingPoints):
        return [points]
    items = list(points)
    for item in items:
        if not isinstance(item, OperatingPoints):
            raise InputError(f"points: expected OperatingPoints, got {type(item).__name__}")
    return items


def _window(
    curve_or_envelope: EnvelopeCurve | PerformanceEnvelope, trajectories: list[OperatingPoints]
) -> EnvelopeCurve:
    """Curve data with a window that also holds every operating point."""
    if isinstance(curve_or_envelope, EnvelopeCurve):
        return curve_or_envelope
    env = curve_or_envelope
    base = envelope_curve(env)
    if not trajectories:
        return base
    v_ext, e_ext = base.velocity_extent, base.effort_extent
    for index, traj in enumerate(trajectories):
        speed = float(np.max(np.abs(traj.velocity), initial=0.0))
        effort = float(np.max(np.abs(traj.effort), initial=0.0))
        if max(speed, effort) * _POINT_MARGIN > MAX_EXTENT:
            raise InputError(
                f"operating points {traj.label or index + 1!r}: |velocity| up to {speed:.6g} and |effort| "
                f"up to {effort:.6g} [SI]; expected values below {MAX_EXTENT / _POINT_MARGIN:.6g} to plot"
            )
        v_ext, e_ext = max(v_ext, _POINT_MARGIN * speed), max(e_ext, _POINT_MARGIN * effort)
    return envelope_curve(env, velocity_extent=v_ext, effort_extent=e_ext)


def plot_envelope(
    curve_or_envelope: EnvelopeCurve | PerformanceEnvelope,
    *,
    points: OperatingPoints | Sequence[OperatingPoints] | None = None,
    ax: Any = None,
    highlight: npt.ArrayLike | None = None,
    title: str | None = None,
) -> EnvelopePlot:
    """Draw the envelope's feasible region and, optionally, trajectories over it.

    Args:
        curve_or_envelope: Curve data from :func:`envelope_curve`, or an envelope (its window then
            grows to hold every operating point).
        points: One or more sets of operating points (plain arrays); they are drawn coloured by
            time, and, when ``ax`` is None, a second panel shows velocity and effort against time.
        ax: A matplotlib axes to draw the (velocity, effort) plane into; None creates a figure.
        highlight: Boolean mask over the first set of points; True points are marked
            in red (e.g. samples that violate the envelope).
        title: Figure title; default the envelope's name.

    Returns:
        The :class:`EnvelopePlot` handle.

    Raises:
        InputError: matplotlib is missing, ``highlight`` does not match the points, a title or label
            is mathtext that does not parse, or the window cannot be drawn to scale.
    """
    figure_cls = figure_class()
    trajectories = _as_list(points)
    if title is not None:
        check_text(title, "title")
    for index, traj in enumerate(trajectories):
        check_text(traj.label, f"points {index + 1} label")
    curve = _window(curve_or_envelope, trajectories)
    if ax is None:
        figure = figure_cls(figsize=(12.0, 6.2) if trajectories else (7.0, 6.4), layout="constrained")
        grid = figure.add_gridspec(1, 2, width_ratios=(1.15, 1.0)) if trajectories else None
        plane = figure.add_subplot(grid[0, 0] if grid is not None else 111)
    else:
        figure, plane, grid = ax.figure, ax, None
    lines: dict[str, list[Any]] = {}
    _draw_region(plane, curve, lines)
    colour_map = None
    for index, traj in enumerate(trajectories):
        colour_map = _draw_points(plane, traj, index, lines)
    if highlight is not None:
        _draw_highlight(plane, trajectories, highlight, lines)
    if colour_map is not None:
        clock = "time [s]" if trajectories[-1].time is not None else "sample"
        figure.colorbar(colour_map, ax=plane, label=clock, pad=0.01, fraction=0.04, aspect=30)
    # below the axes: inside it would hide operating points in the lower quadrants
    plane.legend(loc="upper center", bbox_to_anchor=(0.5, -0.11), fontsize=7, framealpha=0.9, ncols=1)
    axes: tuple[Any, ...] = (plane,)
    if grid is not None:
        axes = (plane, *_draw_time_panel(figure.add_subplot(grid[0, 1]), curve, trajectories, lines))
    name = title if title is not None else plain_text(curve.envelope.name)
    if name and ax is None:
        figure.suptitle(name)
    return EnvelopePlot(figure=figure, axes=axes, lines=lines, curve=curve)


def _draw_region(plane: Any, curve: EnvelopeCurve, lines: dict[str, list[Any]]) -> None:
    polygon = curve.boundary
    lines["region"] = plane.fill(
        polygon[:, 0], polygon[:, 1], color=_REGION_COLOUR, alpha=0.45, label="feasible region"
    )
    closed = np.vstack([polygon, polygon[:1]])
    lines["region"] += plane.plot(closed[:, 0], closed[:, 1], color="#08519c", linewidth=1.6)
    for line in curve.lines:
        artists = []
        for quadrant, segment in enumerate(line.segments):
            artists += plane.plot(
                segment[:, 0],
                segment[:, 1],
                linestyle="--",
                linewidth=1.0,
                color=_LINE_COLOURS.get(line.name, "k"),
                label=line.label if quadrant == 0 else None,
            )
        lines[line.name] = artists
    lines["corners"] = []
    for point in curve.corners:
        lines["corners"] += plane.plot([point.velocity], [point.effort], "ko", markersize=4)
        where = f"({point.velocity:.4g} {curve.velocity_unit}, {point.effort:.4g} {curve.effort_unit})"
        text = f"{point.name}\n{where}"
        # the label goes toward the inside of the region so the window never clips it
        right = point.velocity > 0.5 * curve.velocity_extent or point.velocity == 0.0  # stall: to the left
        high = point.effort > 0.5 * curve.effort_extent
        lines["corners"].append(
            plane.annotate(
                text,
                (point.velocity, point.effort),
                textcoords="offset points",
                xytext=(-6 if right else 6, -6 if high else 6),
                ha="right" if right else "left",
                va="top" if high else "bottom",
                fontsize=7,
            )
        )
    for x, y, text in (
        (0.75, 0.75, "driving"),
        (0.25, 0.75, "braking"),
        (0.25, 0.25, "driving"),
        (0.75, 0.25, "braking"),
    ):
        plane.text(x, y, text, transform=plane.transAxes, fontsize=11, color="0.55", alpha=0.6,
                   ha="center", va="center", zorder=0)  # fmt: skip
    plane.axhline(0.0, color="0.6", linewidth=0.6)
    plane.axvline(0.0, color="0.6", linewidth=0.6)
    plane.set_xlim(-curve.velocity_extent, curve.velocity_extent)
    plane.set_ylim(-curve.effort_extent, curve.effort_extent)
    plane.set_xlabel(f"joint velocity [{curve.velocity_unit}]")
    plane.set_ylabel(f"actuator effort [{curve.effort_unit}]")
    plane.grid(True, linewidth=0.3, alpha=0.5)


def _draw_points(plane: Any, traj: OperatingPoints, index: int, lines: dict[str, list[Any]]) -> Any:
    label = traj.label or f"points {index + 1}"
    points = plane.scatter(
        traj.velocity,
        traj.effort,
        c=traj.clock,
        cmap="viridis",
        s=12,
        marker=_MARKERS[index % len(_MARKERS)],
        linewidths=0.0,
        label=label,
        zorder=3,
    )
    lines[f"points:{label}"] = [points]
    return points


def _draw_highlight(
    plane: Any, trajectories: list[OperatingPoints], highlight: npt.ArrayLike, lines: dict[str, list[Any]]
) -> None:
    mask = np.asarray(highlight, dtype=bool)
    if not trajectories:
        raise InputError("highlight needs points to mark")
    first = trajectories[0]
    if mask.shape != (len(first),):
        raise InputError(f"highlight must be a boolean mask of shape ({len(first)},), got shape {mask.shape}")
    lines["highlight"] = plane.plot(
        first.velocity[mask],
        first.effort[mask],
        "x",
        color="red",
        markersize=6,
        label="outside envelope",
        zorder=4,
    )


def _draw_time_panel(
    axis: Any, curve: EnvelopeCurve, trajectories: list[OperatingPoints], lines: dict[str, list[Any]]
) -> tuple[Any, Any]:
    twin = axis.twinx()
    for index, traj in enumerate(trajectories):
        label = traj.label or f"points {index + 1}"
        style = ("-", "--", ":", "-.")[index % 4]
        lines[f"velocity:{label}"] = axis.plot(
            traj.clock, traj.velocity, style, color="#1f77b4", label=f"velocity {label}"
        )
        lines[f"effort:{label}"] = twin.plot(
            traj.clock, traj.effort, style, color="#d62728", label=f"effort {label}"
        )
    first = trajectories[0]
    limit = effort_limit_at(curve.envelope, first.velocity)
    lines["limit"] = twin.plot(
        first.clock, limit, color="#d62728", linewidth=0.6, alpha=0.5, label="effort limit at v(t)"
    )
    lines["limit"] += twin.plot(first.clock, -limit, color="#d62728", linewidth=0.6, alpha=0.5)
    axis.set_xlabel("time [s]" if all(t.time is not None for t in trajectories) else "sample")
    axis.set_ylabel(f"velocity [{curve.velocity_unit}]", color="#1f77b4")
    twin.set_ylabel(f"effort [{curve.effort_unit}]", color="#d62728")
    axis.grid(True, linewidth=0.3, alpha=0.5)
    handles = axis.get_legend_handles_labels()
    twin_handles = twin.get_legend_handles_labels()
    axis.legend(handles[0] + twin_handles[0], handles[1] + twin_handles[1], loc="lower right", fontsize=7)
    return axis, twin


def save_figure(
    plot: EnvelopePlot | Any, path: str | os.PathLike[str], *, dpi: int = 120, force: bool = False
) -> None:
    """Write the figure of ``plot`` (or a matplotlib figure) to ``path`` atomically.

    Args:
        plot: An :class:`EnvelopePlot` or a ``matplotlib.figure.Figure``.
        path: Output file; its suffix picks the format (``.png``, ``.svg``, ``.pdf``).
        dpi: Resolution of raster output [dots per inch]; a PNG stays within
            :data:`MAX_PIXELS_PER_SIDE` per side and :data:`MAX_PIXELS` in all.
        force: Replace ``path`` even when it is read-only.

    Raises:
        InputError: an unsupported suffix, a ``dpi`` that is not a positive integer or makes the
            image too large, or a file that cannot be written.
    """
    target = check_figure_path(path)
    suffix = target.suffix.lower()
    figure = plot.figure if isinstance(plot, EnvelopePlot) else plot
    _check_dpi(figure, dpi, raster=suffix == ".png")
    try:
        with atomic_path(target, force=force) as tmp:
            figure.savefig(tmp, format=suffix[1:], dpi=dpi, metadata=_metadata(suffix))
    except OSError as exc:  # a missing folder or no permission is the user's input, not a bug
        raise InputError(f"--output {str(target)!r}: cannot write: {exc.strerror or exc}") from None


def _check_dpi(figure: Any, dpi: int, *, raster: bool) -> None:
    """Refuse a ``dpi`` that is not a positive integer or would make a raster image too large."""
    if isinstance(dpi, bool) or not isinstance(dpi, int) or dpi <= 0:
        raise InputError(f"--dpi {dpi!r}: expected a positive integer")
    if not raster:
        return
    width, height = (float(size) for size in figure.get_size_inches())
    pixels_w, pixels_h = round(width * dpi), round(height * dpi)
    if max(pixels_w, pixels_h) > MAX_PIXELS_PER_SIDE or pixels_w * pixels_h > MAX_PIXELS:
        most = int(min(MAX_PIXELS_PER_SIDE / max(width, height), (MAX_PIXELS / (width * height)) ** 0.5))
        raise InputError(
            f"--dpi {dpi}: the {width:g} x {height:g} in figure would be {pixels_w} x {pixels_h} pixels; "
            f"expected at most {MAX_PIXELS_PER_SIDE} per side and {MAX_PIXELS} in all (--dpi {most} or less)"
        )


def _metadata(suffix: str) -> dict[str, Any]:
    # fixed metadata keeps SVG/PDF output reproducible (no creation date)
    if suffix == ".svg":
        return {"Date": None}
    if suffix == ".pdf":
        return {"CreationDate": None}
    return {}

"""The identification figure: measured against simulated motion, and the operating points.

Left, one row per shown log (the validation logs first, at most :data:`MAX_ROWS`): measured and
simulated position, and measured and simulated velocity, against time, with the unpowered spans
shaded. Right: the identified envelope with every replayed log's simulated operating points
(velocity, actuator effort) over it, and the measured ones when the logs have an effort column.
matplotlib is imported lazily (``plot`` extra); the file is written atomically.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from drive_envelope._src.identify.run import Identification, LogError
from drive_envelope._src.plots.curve import OperatingPoints
from drive_envelope._src.plots.figure import (
    check_figure_path,
    figure_class,
    plain_text,
    plot_envelope,
    save_figure,
)

MAX_ROWS = 4
"""Most logs drawn against time (the operating-point panel shows all)."""


def identification_figure(result: Identification) -> Any:
    """The figure (a ``matplotlib.figure.Figure``) of an identification."""
    figure_cls = figure_class("--plot")
    shown = [*result.validation, *result.train][:MAX_ROWS]
    rows = max(len(shown), 1)
    figure = figure_cls(figsize=(16.0, 2.4 * rows + 1.6), layout="constrained")
    grid = figure.add_gridspec(rows, 3, width_ratios=(1.0, 1.0, 1.15))
    revolute = result.scenario.joint.type == "revolute"
    units = ("rad", "rad/s") if revolute else ("m", "m/s")
    validation = {id(error) for error in result.validation}
    for row, error in enumerate(shown):
        kind = "validation" if id(error) in validation else "train"
        _time_panels(figure, grid, row, error, kind, units)
    plane = figure.add_subplot(grid[:, 2])
    points = [
        OperatingPoints(
            velocity=np.concatenate([e.velocity[1:] for e in errors]),
            effort=np.concatenate([e.effort[1:] for e in errors]),
            label=f"simulated, {label} logs",
        )
        for errors, label in ((result.train, "train"), (result.validation, "validation"))
        if errors
    ]
    replayed = (*result.train, *result.validation)
    measured = [e for e in replayed if e.log.effort is not None and e.log.velocity is not None]
    if measured:
        points.append(
            OperatingPoints(
                velocity=np.concatenate([e.log.velocity for e in measured]),  # type: ignore[misc]
                effort=np.concatenate([e.log.effort for e in measured]),  # type: ignore[misc]
                label="measured",
            )
        )
    plot_envelope(result.envelope, points=points, ax=plane, title="")
    plane.set_title("identified envelope and operating points", fontsize=9)
    name = plain_text(result.scenario.name or "identification")
    figure.suptitle(f"{name}: measured vs simulated (reference engine)")
    return figure


def _time_panels(
    figure: Any, grid: Any, row: int, error: LogError, kind: str, units: tuple[str, str]
) -> None:
    log = error.log
    time = log.time - log.time[0]
    off = ~log.enabled
    label = plain_text(log.name)
    position = figure.add_subplot(grid[row, 0])
    position.plot(time, log.position, color="black", lw=1.0, label="measured")
    position.plot(time, error.position, color="tab:orange", lw=1.0, ls="--", label="simulated")
    position.plot(time, log.target_position, color="tab:blue", lw=0.6, alpha=0.6, label="target")
    position.set_ylabel(f"position [{units[0]}]")
    position.set_title(f"{kind}: {label}, MAE {1e3 * error.mae_position:.1f} m{units[0]}", fontsize=8)
    velocity = figure.add_subplot(grid[row, 1], sharex=position)
    if log.velocity is not None:
        velocity.plot(time, log.velocity, color="black", lw=0.8, label="measured")
    velocity.plot(time, error.velocity, color="tab:orange", lw=0.8, ls="--", label="simulated")
    velocity.set_ylabel(f"velocity [{units[1]}]")
    for axes in (position, velocity):
        if off.any():
            span = axes.get_xaxis_transform()
            axes.fill_between(time, 0, 1, where=off, color="grey", alpha=0.15, transform=span, label="off")
        axes.grid(alpha=0.3)
        axes.tick_params(labelsize=7)
    if row == 0:
        position.legend(fontsize=7, loc="upper right")
    velocity.set_xlabel("time [s]", fontsize=8)
    position.set_xlabel("time [s]", fontsize=8)


def save_identification_figure(
    result: Identification, path: str | os.PathLike[str], *, force: bool = False
) -> None:
    """Draw the figure and write it atomically (``.png``, ``.svg`` or ``.pdf``)."""
    check_figure_path(path, "--plot")
    save_figure(identification_figure(result), path, force=force)

"""The violation plot of ``check --plot``: one envelope figure per joint, violations in red.

matplotlib is imported lazily (``plot`` extra); each file is written atomically.
"""

from __future__ import annotations

import os
from pathlib import Path

from drive_envelope._src.analysis.check import CheckReport
from drive_envelope._src.errors import InputError
from drive_envelope._src.plots.curve import OperatingPoints
from drive_envelope._src.plots.figure import figure_class, plain_text, plot_envelope, save_figure


def plot_check(report: CheckReport, path: str | os.PathLike[str], *, force: bool = False) -> list[Path]:
    """Write one envelope plot per joint with its violations in red; return the files written.

    With one joint the plot goes to ``path``; with several, to ``<stem>-<joint><suffix>`` beside it.
    ``force`` replaces read-only files.

    Raises:
        InputError: matplotlib is missing, no points were kept, or an unsupported suffix.
    """
    figure_cls = figure_class("--plot")
    target = Path(path)
    written = []
    for check in report.joints:
        points = check.points
        if points is None:
            raise InputError("plot: the check kept no points (CheckOptions.keep_points = 0)")
        name = plain_text(check.joint)  # a joint name from the log is text, never mathtext
        samples = OperatingPoints(
            velocity=points.velocity, effort=points.effort, time=points.time, label=name
        )
        figure = figure_cls(figsize=(7.0, 6.4), layout="constrained")
        axes = figure.add_subplot(111)
        plot = plot_envelope(check.envelope, points=samples, ax=axes, highlight=points.outside, title=name)
        safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in check.joint)
        out = target if len(report.joints) == 1 else target.with_name(f"{target.stem}-{safe}{target.suffix}")
        save_figure(plot, out, force=force)
        written.append(out)
    return written

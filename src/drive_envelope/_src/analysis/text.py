"""Plain-text reports of checks and fits for the command line (the violation plot: :mod:`..plots.check`)."""

from __future__ import annotations

import math

from drive_envelope._src.analysis.check import CheckReport, JointCheck, MarginSummary
from drive_envelope._src.analysis.fit import FitResult
from drive_envelope._src.analysis.fit_evidence import WARNING, sample_ranges
from drive_envelope._src.format import format_table, format_value
from drive_envelope._src.params.table import si_unit

_CURVE_TITLES = {"effort": "eq. 1 effort", "velocity": "eq. 2 velocity"}


def _percent(fraction: float) -> str:
    return f"{100.0 * fraction:.3g} %"


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.6g} s"


def _where(check: JointCheck) -> str:
    worst = check.worst
    if worst is None:
        return "no sample outside"
    unit = check.effort.unit if worst.curve == "effort" else (check.velocity.unit if check.velocity else "")
    at = f"t = {worst.time:.6g} s, " if worst.time is not None else ""
    return (
        f"worst: {_CURVE_TITLES[worst.curve]} exceeded by {format_value(worst.excess, unit)} "
        f"({_percent(worst.relative)} of the cap) at {at}row {worst.row}: "
        f"velocity {worst.velocity:.6g}, effort {worst.effort:.6g}"
    )


def _released(check: JointCheck) -> str:
    during = "" if check.time_released is None else f" ({check.time_released:.6g} s)"
    return (
        f"released: {check.samples_released} samples{during} above the speed line with zero effort: "
        "something else drove the joint past the no-load speed and the drive let go, as PhysX's does "
        "(not counted as outside)"
    )


def _margin_row(summary: MarginSummary) -> list[str]:
    quantiles = dict(summary.quantiles)
    return [
        f"{_CURVE_TITLES[summary.curve]} [{summary.unit}]",
        format_value(summary.minimum),
        format_value(quantiles[0.01]),
        format_value(quantiles[0.05]),
        format_value(quantiles[0.5]),
        str(summary.samples_on_limit),
        _seconds(summary.time_on_limit),
        str(summary.samples_outside),
    ]


def check_warnings(report: CheckReport) -> list[str]:
    """The check's warning lines (for stderr): one per mapping key no joint of the log took."""
    return [f"{unused.where}: {unused.reason}" for unused in report.unused_keys]


def format_check(report: CheckReport) -> str:
    """The check report as text: one block per joint, then the verdict."""
    options = report.options
    lines = [
        f"{report.source}: {len(report.joints)} joint(s); outside = margin < -{options.slack:g} of the cap, "
        f"on limit = |margin| <= {options.limit_band:g} of the cap"
    ]
    header = ["curve (margin)", "min", "p1", "p5", "median", "on limit", "time on limit", "outside"]
    for check in report.joints:
        status = "ok" if check.fraction_outside <= options.tolerance else "FAIL"
        duration = "" if check.duration is None else f" over {check.duration:.6g} s"
        if check.time_resets:
            duration += (
                f" in {check.time_resets + 1} episodes (time goes back {check.time_resets} time(s), "
                f"first at row {check.first_time_reset})"
            )
        lines.append("")
        lines.append(
            f"joint {check.joint!r}: {check.samples} samples{duration}, {check.samples_outside} outside "
            f"({_percent(check.fraction_outside)}), {check.samples_released} released -> {status}"
        )
        rows = [_margin_row(check.effort)]
        if check.velocity is not None:
            rows.append(_margin_row(check.velocity))
        lines.append(format_table(header, rows))
        if check.velocity is None:
            lines.append("eq. 2 not checked: max_actuator_velocity is inf")
        lines.append(_where(check))
        if check.samples_released:
            lines.append(_released(check))
    verdict = "PASSED" if report.passed else "FAILED"
    lines.append("")
    lines.append(f"{verdict}: tolerance {_percent(options.tolerance)} of samples outside per joint")
    return "\n".join(lines)


def format_fit(result: FitResult) -> str:
    """The fit as text: parameters, the samples that decided each line, residuals and notes."""
    rows = []
    for p in result.parameters:
        interval = "-" if p.interval is None else f"[{p.interval[0]:.6g}, {p.interval[1]:.6g}]"
        if p.interval is not None and f"{p.interval[0]:.6g}" == f"{p.interval[1]:.6g}" and p.std:
            # the middle 95 % of resamples agree to the digits shown; the std comes from the few
            # (under 5 %) that do not, so a zero-width interval beside it would read as a bug
            interval = f"{p.interval[0]:.6g} (>= 95 % of resamples; std from the rest)"
        rows.append(
            [
                p.name,
                format_value(p.value),
                "-" if p.std is None else f"{p.std:.3g}",
                interval,
                p.unit,
                p.status,
            ]
        )
    env = result.envelope
    lines = [
        f"fitted envelope ({env.joint}) from {result.samples} samples, {result.samples_outside} outside; "
        f"{result.frontier_samples} on the frontier (within {result.frontier_band:.3g} of the upper hull)",
        format_table(["parameter", "value", "std", "95 % interval", "unit", "status"], rows),
        "",
        "lines, decided by the samples on them (within 1 % of the cap)",
        _lines_table(result),
        "",
        "residuals of the frontier samples (positive: outside the fitted line)",
    ]
    residual_rows = []
    for label, values, unit in (
        ("eq. 1 effort", result.effort_residuals, si_unit("max_effort", env.joint)),
        ("eq. 2 velocity", result.velocity_residuals, si_unit("max_actuator_velocity", env.joint)),
    ):
        if values.size:
            rms = math.sqrt(float((values**2).mean()))
            residual_rows.append(
                [f"{label} [{unit}]", str(values.size), format_value(rms), format_value(float(values.max()))]
            )
        else:
            residual_rows.append([f"{label} [{unit}]", "0", "-", "-"])
    lines.append(format_table(["line", "samples", "rms", "max"], residual_rows))
    lines.extend(note if note.startswith(WARNING) else f"note: {note}" for note in result.notes)
    return "\n".join(lines)


_SHOWN_RUNS = 4  # runs of sample numbers a text report lists per line (JSON lists them all)


def _lines_table(result: FitResult) -> str:
    """One row per line: on-line samples by quadrant pair, their ranges and sample numbers."""
    joint = result.envelope.joint
    speed, effort = si_unit("max_actuator_velocity", joint), si_unit("max_effort", joint)
    rows = []
    for line in result.lines:
        runs = sample_ranges(line.on_line)
        numbers = ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs[:_SHOWN_RUNS])
        numbers += f", ... ({len(runs)} runs)" if len(runs) > _SHOWN_RUNS else ""
        rows.append(
            [
                _CURVE_TITLES[line.curve],
                "fitted" if line.identified else "not identified",
                str(line.bounded),
                str(line.on_line.size),
                str(line.driving),
                str(line.braking),
                _span(line.velocity_range),
                _span(line.effort_range),
                numbers or "-",
            ]
        )
    header = ["line", "status", "bounds", "on line", "driving", "braking"]
    header += [f"|velocity| [{speed}]", f"|effort| [{effort}]", "samples"]
    return format_table(header, rows)


def _span(extent: tuple[float, float] | None) -> str:
    return "-" if extent is None else f"{format_value(extent[0])} .. {format_value(extent[1])}"

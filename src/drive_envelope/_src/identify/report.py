"""An identification as one JSON object or as text.

The JSON object (``drive-envelope identify --json``), SI throughout:

``parameters``
    ``{name: {"value", "std", "spread", "fixed"}}`` for every parameter (``duty_effort`` only with
    a servo duty gain): ``std`` (Gauss-Newton) is null for a fixed parameter and ``"inf"`` for a
    fitted one the logs do not identify (an envelope line that never binds); ``spread`` is
    ``[lowest, highest]`` value the search's restarts ended at (null when fixed), the uncertainty
    to trust when the logs trade two parameters against each other; an infinite value is
    ``"inf"``, as in envelope files. A parameter that follows
    from others has a null value and ``"derived"`` saying how (stiffness with a servo duty gain:
    ``"duty_per_rad * max_effort, per log"``).
``train`` / ``validation``
    ``{"mae_position": {log file name: rad}, "mae_position_mean": rad}`` (reference engine);
    ``mae_velocity`` likewise when the logs have a velocity column. ``validation`` has an empty
    ``mae_position`` and a null mean without ``--validate``.
``engine``
    ``{"name", "train", "validation"}``: the same errors replayed in ``--engine`` (absent for the
    reference engine).
``wall_time_s``, ``search``, ``envelope``, ``units``, ``notes``
    Time taken; generations, candidate replays and whether the polish helped; the identified
    envelope; each parameter's unit; warnings (a parameter on a bound, a sidecar that disagrees
    with its log or the stand).
"""

from __future__ import annotations

import math
from typing import Any

from drive_envelope._src.format import format_table
from drive_envelope._src.identify.parameters import parameter_units
from drive_envelope._src.identify.run import Identification, LogError, mean_error
from drive_envelope._src.io.envelope_file import envelope_data


def _number(value: float | None) -> float | str | None:
    if value is None:
        return None
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return float(value)


def _errors(errors: tuple[LogError, ...]) -> dict[str, Any]:
    data: dict[str, Any] = {
        "mae_position": {e.log.name: e.mae_position for e in errors},
        "mae_position_mean": _number(mean_error(errors)) if errors else None,
    }
    if errors and all(e.mae_velocity is not None for e in errors):
        velocities = [float(e.mae_velocity) for e in errors if e.mae_velocity is not None]
        data["mae_velocity"] = {e.log.name: e.mae_velocity for e in errors}
        data["mae_velocity_mean"] = sum(velocities) / len(velocities)
    return data


def _engine_errors(values: dict[str, float]) -> dict[str, Any]:
    return {"mae_position": dict(values), "mae_position_mean": _mean(values) if values else None}


def _mean(values: dict[str, float]) -> float:  # of another engine's per-log errors
    return sum(values.values()) / len(values)


def identification_to_dict(result: Identification) -> dict[str, Any]:
    """The JSON-compatible object of an identification (see the module docstring)."""
    units = parameter_units(result.scenario.joint.type)
    data: dict[str, Any] = {
        "parameters": {
            name: {
                "value": None if estimate.derived else _number(estimate.value),
                "std": None if estimate.fixed else _number(estimate.std),
                "spread": None
                if estimate.fixed or estimate.spread is None
                else [_number(estimate.spread[0]), _number(estimate.spread[1])],
                "fixed": estimate.fixed,
                **({"derived": estimate.derived} if estimate.derived else {}),
            }
            for name, estimate in result.parameters.items()
        },
        "train": _errors(result.train),
        "validation": _errors(result.validation),
        "wall_time_s": result.wall_time_s,
        "search": {
            "generations": result.search.generations,
            "candidate_replays": result.search.replays,
            "polished": result.search.polished,
            "train_cost": result.search.cost,
            "restarts": len(result.search.restart_costs),
            "restart_costs": list(result.search.restart_costs),
        },
        "envelope": envelope_data(result.envelope),
        "units": units,
        "notes": list(result.notes),
    }
    if result.engine != "reference":
        data["engine"] = {
            "name": result.engine,
            "train": _engine_errors(result.engine_train),
            "validation": _engine_errors(result.engine_validation),
        }
    return data


def _fmt(value: float | None) -> str:
    if value is None:
        return "-"
    if math.isinf(value):
        return "inf"
    return f"{value:.6g}"


def identification_text(result: Identification) -> str:
    """A report for people: the parameters, then the errors per log (mrad or mm)."""
    units = parameter_units(result.scenario.joint.type)
    rows = []
    for name, estimate in result.parameters.items():
        if estimate.derived:
            rows.append([name, estimate.derived, "-", "-", units[name].replace("**", "^")])
            continue
        if estimate.fixed:
            std, spread = "fixed", "-"
        else:
            identified = estimate.std is not None and not math.isinf(estimate.std)
            std = _fmt(estimate.std) if identified else "not identified"
            low, high = estimate.spread if estimate.spread is not None else (math.nan, math.nan)
            spread = f"{low:.4g} .. {high:.4g}" if estimate.spread is not None else "-"
        rows.append([name, _fmt(estimate.value), std, spread, units[name].replace("**", "^")])
    header = ["parameter", "value", "std", f"restarts ({len(result.search.restart_costs)})", "unit (SI)"]
    lines = [format_table(header, rows), ""]
    scale, unit = (1e3, "mrad") if result.scenario.joint.type == "revolute" else (1e3, "mm")
    table = []
    engine = result.engine != "reference"
    for kind, errors, replays in (
        ("train", result.train, result.engine_train),
        ("validation", result.validation, result.engine_validation),
    ):
        for error in errors:
            row = [kind, error.log.name, f"{scale * error.mae_position:.2f}"]
            if engine:
                other = replays.get(error.log.name)
                row.append("-" if other is None else f"{scale * other:.2f}")
            table.append(row)
    if table:
        header = ["set", "log", f"MAE reference [{unit}]"]
        if engine:
            header.append(f"MAE {result.engine} [{unit}]")
        lines.append(format_table(header, table))
        summary = [f"mean position error: train {scale * mean_error(result.train):.2f} {unit}"]
        if result.validation:
            summary.append(f"validation {scale * mean_error(result.validation):.2f} {unit}")
        for kind, replays in (("train", result.engine_train), ("validation", result.engine_validation)):
            if replays:  # only another engine's run has them
                summary.append(f"{kind} in {result.engine} {scale * _mean(replays):.2f} {unit}")
        lines.append(", ".join(summary) + f"; {result.wall_time_s:.1f} s")
    return "\n".join(lines)

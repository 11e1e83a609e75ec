"""Convert BAM's JSON bench logs into drive-envelope bench logs (CSV + a JSON sidecar each).

BAM (Better Actuator Models, https://github.com/Rhoban/bam, Apache-2.0) records a servo swinging
a pendulum as one JSON file per run: the stand (``mass`` [kg], ``length`` [m], firmware ``kp``,
``vin`` [V], ``motor``) and ``entries``, one per bus cycle, with ``timestamp`` [s], ``position``
[rad], ``speed`` [rad/s], ``goal_position`` [rad], ``torque_enable`` and more. Processed logs
(``python -m bam.process``) are on a uniform grid (``dt``); raw ones are not and are resampled here
(``--dt``; positions and speeds linearly, goals and torque enable held from the last cycle).

For each log this writes ``OUT/NAME.csv`` with the columns ``drive-envelope identify`` reads
(``time, position, target_position, velocity, torque_enable`` and ``input_volts`` when present) and
``OUT/NAME.json`` beside it with the stand and the servo's duty gain ``kp_duty_per_rad``: the
firmware's position gain as PWM duty per radian of error, ``kp * error_gain``, with BAM's
``error_gain`` for its Dynamixel actuators (``bam/dynamixel/actuator.py``; XL330: 4096/(2*pi) counts
per radian over 256*885) and the Feetech STS3215 (``bam/feetech/actuator.py``). For another servo pass
``--duty-per-rad``. Then::

    python examples/bam/convert.py bam_logs/*.json -o logs/
    drive-envelope identify logs/run_1.csv logs/run_2.csv --stand examples/bam/xl330_pendulum.toml \\
        --validate logs/run_3.csv --fit max_effort,damping,static_friction,viscous_friction,armature

A stand file for another pendulum: copy ``xl330_pendulum.toml`` and change ``[pendulum]`` to the
sidecar's ``mass_kg`` and ``length_m``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

# BAM's duty gain per unit of firmware kp and radian, by its actuator names (bam/actuators.py);
# the XL330's (bam/dynamixel/actuator.py): encoder counts per radian / (kp divisor * PWM limit)
XL330 = (4096 / (2 * math.pi)) / (256 * 885)
ERROR_GAINS = {
    "xl330": XL330,
    "mx64": 0.158,
    "mx106": 0.158,
    "xl320": 0.05048199,
    "sts3215": 0.166,
}
"""BAM's ``error_gain`` [duty per (kp * rad)] of its voltage-controlled actuators."""


class ConvertError(Exception):
    """A log that cannot be converted (the message names the file and the key)."""


def _entries(log: dict[str, Any], source: str) -> dict[str, np.ndarray]:
    entries = log.get("entries")
    if not isinstance(entries, list) or len(entries) < 3:
        raise ConvertError(f"{source}: key 'entries': expected a list of at least 3 samples")
    columns: dict[str, np.ndarray] = {}
    for key in ("timestamp", "position", "goal_position", "speed", "torque_enable", "input_volts"):
        if key not in entries[0]:
            if key in ("timestamp", "position", "goal_position"):
                raise ConvertError(f"{source}: entries have no {key!r}; expected BAM's log format")
            continue
        try:
            values = np.array([float(entry[key]) for entry in entries])
        except (KeyError, TypeError, ValueError) as exc:
            detail = f"not a number in every entry ({exc})"
            raise ConvertError(f"{source}: entries[...][{key!r}]: {detail}") from None
        if not np.isfinite(values).all():
            row = int(np.flatnonzero(~np.isfinite(values))[0])
            raise ConvertError(f"{source}: entries[{row}][{key!r}] is not a finite number")
        columns[key] = values
    return columns


def _resample(columns: dict[str, np.ndarray], dt: float) -> dict[str, np.ndarray]:
    """Columns on a uniform grid from the first timestamp (measured values linear, commands held)."""
    stamps = columns["timestamp"]
    if np.any(np.diff(stamps) <= 0):
        raise ConvertError("timestamps do not increase")
    time = np.arange(0.0, stamps[-1] - stamps[0] + 1e-12, dt)
    grid = stamps[0] + time
    out = {"timestamp": time}
    held = np.clip(np.searchsorted(stamps, grid, side="right") - 1, 0, len(stamps) - 1)
    for key, values in columns.items():
        if key == "timestamp":
            continue
        if key in ("goal_position", "torque_enable"):
            out[key] = values[held]  # a command acts from its cycle until the next
        else:
            out[key] = np.interp(grid, stamps, values)
    return out


def _uniform(stamps: np.ndarray) -> bool:
    steps = np.diff(stamps)
    return bool(np.all(np.abs(steps - np.median(steps)) <= 0.01 * np.median(steps)))


def duty_per_rad(log: dict[str, Any], source: str, override: float | None) -> float:
    """The servo's PWM duty per radian of error for this log's firmware kp."""
    if override is not None:
        return override
    motor = str(log.get("motor", ""))
    gain = ERROR_GAINS.get(motor)
    if gain is None:
        raise ConvertError(
            f"{source}: key 'motor' = {motor!r}: no duty gain known (known: {', '.join(ERROR_GAINS)}); "
            "pass --duty-per-rad"
        )
    kp = log.get("kp")
    if isinstance(kp, bool) or not isinstance(kp, (int, float)) or not kp > 0:
        raise ConvertError(f"{source}: key 'kp': expected the firmware gain (a number > 0), got {kp!r}")
    return float(kp) * gain


def convert(path: Path, out: Path, *, dt: float | None, duty: float | None) -> tuple[Path, int]:
    """Convert one BAM log; returns the CSV written and its number of rows."""
    source = str(path)
    try:
        log = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConvertError(f"{source}: cannot read as JSON: {exc}") from None
    if not isinstance(log, dict):
        raise ConvertError(f"{source}: expected a JSON object (a BAM log)")
    columns = _entries(log, source)
    step = dt or log.get("dt")
    if _uniform(columns["timestamp"]) and dt is None:
        columns["timestamp"] = columns["timestamp"] - columns["timestamp"][0]
    else:
        if not isinstance(step, (int, float)) or not step > 0:
            raise ConvertError(f"{source}: timestamps are not on a uniform grid; pass --dt to resample")
        columns = _resample(columns, float(step))
    names = {"timestamp": "time", "position": "position", "goal_position": "target_position"}
    names.update({"speed": "velocity", "torque_enable": "torque_enable", "input_volts": "input_volts"})
    header = [names[key] for key in names if key in columns]
    table = np.column_stack([columns[key] for key in names if key in columns])
    lines = [",".join(header)] + [",".join(f"{value:.10g}" for value in row) for row in table]
    sidecar = {
        "source": source,
        "motor": log.get("motor"),
        "trajectory": log.get("trajectory"),
        "mass_kg": log.get("mass"),
        "length_m": log.get("length"),
        "arm_mass_kg": log.get("arm_mass", log.get("arm-mass", 0.0)),
        "kp_firmware": log.get("kp"),
        "kp_duty_per_rad": duty_per_rad(log, source, duty),
        "supply_voltage_v": log.get("vin"),
        "samples": len(table),
        "dt_s": float(np.median(np.diff(table[:, 0]))),
    }
    out.mkdir(parents=True, exist_ok=True)
    target = out / f"{path.stem}.csv"
    _write(target, "\n".join(lines) + "\n")
    _write(target.with_suffix(".json"), json.dumps(sidecar, indent=1) + "\n")
    return target, len(table)


def _write(path: Path, text: str) -> None:
    """Write beside the target and rename: a failed run never leaves half a file."""
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            stream.write(text)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def main(argv: list[str] | None = None) -> int:
    """Command line: convert each log; one line per log, or one error line and exit 2."""
    parser = argparse.ArgumentParser(description="Convert BAM JSON logs into drive-envelope bench logs.")
    parser.add_argument("logs", nargs="+", type=Path, help="BAM JSON logs (processed or raw)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="output folder")
    parser.add_argument("--dt", type=float, default=None, help="resample to this step [s] (raw logs)")
    parser.add_argument("--duty-per-rad", type=float, default=None, help="servo duty per radian (overrides)")
    args = parser.parse_args(argv)
    for value, flag in ((args.dt, "--dt"), (args.duty_per_rad, "--duty-per-rad")):
        if value is not None and not (math.isfinite(value) and value > 0):
            parser.error(f"{flag}: expected a number > 0, got {value!r}")
    try:
        for path in args.logs:
            target, rows = convert(path, args.output, dt=args.dt, duty=args.duty_per_rad)
            print(f"wrote {target} ({rows} rows) and {target.with_suffix('.json').name}", file=sys.stderr)
    except (ConvertError, OSError) as exc:
        print(f"convert.py: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

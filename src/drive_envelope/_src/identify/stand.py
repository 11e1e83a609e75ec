"""The stand file of ``identify``: a test-stand scenario plus what identification needs beside it.

The file is the scenario format (:mod:`drive_envelope._src.scenario.spec`; a ``[pendulum]`` table
for a gravity load) with two optional tables of its own:

``[servo]``
    ``duty_per_rad`` [1/rad]: the servo firmware's position gain as PWM duty per radian of
    error. A voltage-driven servo (Dynamixel, Feetech) at full duty gives its stall effort at rest,
    so its position loop is a drive of stiffness ``duty_per_rad * max_effort``: the stiffness follows
    the identified ``max_effort``. A log's JSON sidecar ``kp_duty_per_rad`` replaces it for that log
    (bench sets often sweep the gain). Without it the drive's ``stiffness`` is the stand's.
    ``duty_effort`` [N*m or N]: the effort the loop commands at full duty, so stiffness is
    ``duty_per_rad * duty_effort``; by default ``max_effort`` (and it follows a fitted
    ``max_effort``). An identified stand writes it when the envelope's canonical ``max_effort``
    differs from it (the speed line caps the effort at rest below it).
``[bounds]``
    ``name = [low, high]`` in SI for any parameter ``--fit`` may name: the search interval.

Values in ``[drive]``, ``[envelope]``, ``[friction]``, ``[joint] armature`` and ``[pendulum]
angle_offset`` are the starting values of the parameters ``--fit`` names and the fixed values of
the others. ``[simulation]`` gives the solver, position and velocity iterations and gravity; the time
step and duration come from each log (a stand ``dt`` or ``duration`` is ignored with a warning).
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from drive_envelope._src.errors import InputError
from drive_envelope._src.io.files import read_mapping
from drive_envelope._src.scenario.spec import Scenario, scenario_from_mapping
from drive_envelope._src.validation import check_keys
from drive_envelope._src.values import read_quantity

_OWN_TABLES = ("servo", "bounds")


class StandWarning(UserWarning):
    """A stand value identification does not use (the CLI prints it on stderr)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class IdentifyStand:
    """A stand for identification: the base scenario and the identification tables."""

    scenario: Scenario
    """The scenario: the stand's joint, loads, drive, envelope and solver settings (SI)."""
    duty_per_rad: float | None = None
    """``[servo] duty_per_rad`` [1/rad], or None: stiffness is then the drive's own."""
    duty_effort: float | None = None
    """``[servo] duty_effort`` [N*m or N], or None: ``max_effort`` (stiffness is ``duty_per_rad *
    duty_effort``)."""
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    """``[bounds]``: search interval per parameter name (SI)."""
    source: str = "stand"
    """The file name (for messages)."""


def read_stand(
    path: str | os.PathLike[str], parameter_units: Mapping[str, str] | None = None
) -> IdentifyStand:
    """Read a stand file.

    Args:
        path: The stand file (TOML, JSON or YAML).
        parameter_units: SI unit of each parameter name ``[bounds]`` may use (revolute units; a
            prismatic stand's bounds are read as bare SI numbers); default: every identify parameter.

    Raises:
        InputError: a scenario error, or a bad ``[servo]`` / ``[bounds]`` key or value (one line
            naming the file, the key and the value).
    """
    if parameter_units is None:
        from drive_envelope._src.identify.parameters import parameter_units as units_of

        parameter_units = units_of()
    file = Path(path)
    source = str(file)
    data = dict(read_mapping(file))
    own = {name: _table(data.pop(name, {}), name, source) for name in _OWN_TABLES}
    simulation = data.get("simulation")
    if isinstance(simulation, Mapping):
        ignored = [key for key in ("dt", "duration") if key in simulation]
        if ignored:
            warnings.warn(
                f"{source}: simulation.{' and simulation.'.join(ignored)} ignored: each log's sampling "
                "step and length set the replay",
                StandWarning,
                stacklevel=2,
            )
            data["simulation"] = {k: v for k, v in simulation.items() if k not in ("dt", "duration")}
    scenario = scenario_from_mapping(
        data, source=source, base_dir=file.parent, default_name=file.stem, other_tables=_OWN_TABLES
    )
    return IdentifyStand(
        scenario=scenario,
        duty_per_rad=_duty(own["servo"], source),
        duty_effort=_duty_effort(own["servo"], scenario.joint.type, source),
        bounds=_bounds(own["bounds"], parameter_units, scenario.joint.type, source),
        source=source,
    )


def _table(value: object, name: str, source: str) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        raise InputError(f"{source}: key {name!r}: expected a table [{name}], got {value!r}")
    return dict(value)


_SERVO_KEYS = ("duty_per_rad", "duty_effort")


def _duty(table: Mapping[str, Any], source: str) -> float | None:
    check_keys(table, _SERVO_KEYS, source, "servo")
    if "duty_per_rad" not in table:
        return None
    value = read_quantity(table["duty_per_rad"], "1/rad", f"{source}: key 'servo.duty_per_rad'")
    if not (math.isfinite(value) and value > 0.0):
        raise InputError(f"{source}: key 'servo.duty_per_rad': expected a number > 0 [1/rad], got {value!r}")
    return value


def _duty_effort(table: Mapping[str, Any], joint: str, source: str) -> float | None:
    if "duty_effort" not in table:
        return None
    unit = "N*m" if joint == "revolute" else "N"
    value = read_quantity(table["duty_effort"], unit, f"{source}: key 'servo.duty_effort'")
    if not (math.isfinite(value) and value > 0.0):
        raise InputError(f"{source}: key 'servo.duty_effort': expected a number > 0 [{unit}], got {value!r}")
    if "duty_per_rad" not in table:
        raise InputError(f"{source}: key 'servo.duty_effort' needs servo.duty_per_rad (the gain it scales)")
    return value


def _bounds(
    table: Mapping[str, Any], units: Mapping[str, str], joint: str, source: str
) -> dict[str, tuple[float, float]]:
    bounds = {}
    check_keys(table, tuple(units), source, "bounds")
    for key, value in table.items():
        where = f"{source}: key 'bounds.{key}'"
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise InputError(f"{where}: expected [low, high], got {value!r}")
        unit = units[key] if joint == "revolute" else ""
        low, high = (read_quantity(item, unit, where) if unit else _bare(item, where) for item in value)
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise InputError(f"{where}: expected finite low < high, got {value!r}")
        bounds[key] = (low, high)
    return bounds


def _bare(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{where}: expected SI numbers for a prismatic stand, got {value!r}")
    return float(value)

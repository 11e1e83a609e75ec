"""Writing an identified stand: a stand file with every identified and fixed parameter.

``identify -o STAND`` writes it; ``identify --stand STAND`` (a new search from the result) and
``replay LOG... --stand STAND`` read it back with :func:`~drive_envelope._src.identify.stand.read_stand`.
The text is the scenario format (``[joint]``, ``[drive]``, ``[envelope]``, ``[pendulum]``,
``[friction]``, ``[simulation]``) plus ``[servo]`` and ``[bounds]``, SI numbers written with every
digit (``repr``), so a replay of the file gives the identification's errors to the last bit. The
time step and duration are not written: each log gives its own.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path

from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.stand import IdentifyStand
from drive_envelope._src.io.atomic import atomic_write_text
from drive_envelope._src.io.files import format_toml_value

STAND_SUFFIXES = (".toml", ".json")
"""File name endings an identified stand can be written as."""


def stand_to_mapping(stand: IdentifyStand) -> dict[str, dict[str, object] | str]:
    """The stand as the tables of a stand file (SI floats)."""
    scenario = stand.scenario
    envelope = scenario.effective_envelope()
    data: dict[str, dict[str, object] | str] = {"name": scenario.name}
    data["joint"] = _fields(scenario.joint, "type", "inertia", "armature")
    drive: dict[str, object] = {"type": scenario.drive.type}
    if stand.duty_per_rad is None:
        drive["stiffness"] = scenario.drive.stiffness
    drive.update(_fields(scenario.drive, "damping", "max_effort", "target_velocity"))
    data["drive"] = drive
    if envelope is not None and scenario.envelope is not None:
        lines = ("max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")
        data["envelope"] = _fields(envelope, *lines)
    if stand.duty_per_rad is not None:
        servo: dict[str, object] = {"duty_per_rad": stand.duty_per_rad}
        if stand.duty_effort is not None:
            servo["duty_effort"] = stand.duty_effort
        data["servo"] = servo
    if scenario.load.external_effort or scenario.load.applied_effort:
        data["load"] = _fields(scenario.load, "external_effort", "applied_effort")
    if scenario.pendulum is not None:
        data["pendulum"] = _fields(scenario.pendulum, "mass", "distance", "angle_offset")
    data["friction"] = _fields(scenario.friction, "static_friction", "dynamic_friction", "viscous_friction")
    data["simulation"] = _fields(
        scenario.simulation, "solver", "position_iterations", "velocity_iterations", "gravity"
    )
    if stand.bounds:
        data["bounds"] = {name: [low, high] for name, (low, high) in stand.bounds.items()}
    return data


def _fields(record: object, *names: str) -> dict[str, object]:
    """The named attributes of ``record``, in that order: one table of the file."""
    return {name: getattr(record, name) for name in names}


def stand_to_toml(stand: IdentifyStand, comments: Sequence[str] = ()) -> str:
    """TOML text of the stand (``comments`` first, as ``#`` lines)."""
    data = stand_to_mapping(stand)
    lines = [f"# {line}" for line in comments]
    lines.append(f"name = {format_toml_value(data.pop('name'))}")
    for section, table in data.items():
        assert isinstance(table, dict)
        lines.append("")
        lines.append(f"[{section}]")
        for key, value in table.items():
            if isinstance(value, list):
                text = "[" + ", ".join(format_toml_value(float(item)) for item in value) + "]"
            else:
                text = format_toml_value(value)
            lines.append(f"{key} = {text}")
    return "\n".join(lines) + "\n"


def _json_value(value: object) -> object:
    if isinstance(value, float) and math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if isinstance(value, list):
        return [_json_value(item) for item in value]
    return value


def save_stand(
    stand: IdentifyStand,
    path: str | os.PathLike[str],
    *,
    comments: Sequence[str] = (),
    force: bool = False,
) -> None:
    """Write the stand file atomically (``.toml``, or ``.json`` without the comments).

    Raises:
        InputError: another suffix, or the file cannot be written.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in STAND_SUFFIXES:
        raise InputError(f"--output {str(path)!r}: expected a stand file name ending in .toml or .json")
    if suffix == ".json":
        data = {
            key: ({k: _json_value(v) for k, v in table.items()} if isinstance(table, dict) else table)
            for key, table in stand_to_mapping(stand).items()
        }
        text = json.dumps(data, indent=2) + "\n"
    else:
        text = stand_to_toml(stand, comments)
    atomic_write_text(path, text, force=force)

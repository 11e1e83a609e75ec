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
    data["joint"] = {
        "type": scenario.joint.type,
        "inertia": scenario.joint.inertia,
        "armature": scenario.joint.armature,
    }
    drive: dict[str, object] = {"type": scenario.drive.type}
    if stand.duty_per_rad is None:
        drive["stiffness"] = scenario.drive.stiffness
    drive.update(
        damping=scenario.drive.damping,
        max_effort=scenario.drive.max_effort,
        target_velocity=scenario.drive.target_velocity,
    )
    data["drive"] = drive
    if envelope is not None and scenario.envelope is not None:
        data["envelope"] = {
            "max_actuator_velocity": envelope.max_actuator_velocity,
            "velocity_dependent_resistance": envelope.velocity_dependent_resistance,
            "speed_effort_gradient": envelope.speed_effort_gradient,
        }
    if stand.duty_per_rad is not None:
        servo: dict[str, object] = {"duty_per_rad": stand.duty_per_rad}
        if stand.duty_effort is not None:
            servo["duty_effort"] = stand.duty_effort
        data["servo"] = servo
    if scenario.load.external_effort or scenario.load.applied_effort:
        data["load"] = {
            "external_effort": scenario.load.external_effort,
            "applied_effort": scenario.load.applied_effort,
        }
    if scenario.pendulum is not None:
        data["pendulum"] = {
            "mass": scenario.pendulum.mass,
            "distance": scenario.pendulum.distance,
            "angle_offset": scenario.pendulum.angle_offset,
        }
    friction = scenario.friction
    data["friction"] = {
        "static_friction": friction.static_friction,
        "dynamic_friction": friction.dynamic_friction,
        "viscous_friction": friction.viscous_friction,
    }
    simulation = scenario.simulation
    data["simulation"] = {
        "solver": simulation.solver,
        "position_iterations": simulation.position_iterations,
        "velocity_iterations": simulation.velocity_iterations,
        "gravity": simulation.gravity,
    }
    if stand.bounds:
        data["bounds"] = {name: [low, high] for name, (low, high) in stand.bounds.items()}
    return data


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

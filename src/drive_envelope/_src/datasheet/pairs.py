"""Keys that say the same thing twice, and pairs of keys that must agree (a point below its line's end).

Each is checked on the section values in SI, after every key has been read on its own.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from drive_envelope._src.errors import InputError


def check_pairs(sections: Mapping[str, dict[str, Any]], source: str) -> None:
    """Refuse keys that say the same thing twice, and inconsistent pairs."""
    motor, output = sections.get("motor", {}), sections.get("output", {})
    if "speed_constant" in motor and "back_emf_constant" in motor:
        raise InputError(
            f"{source}: keys 'motor.speed_constant' and 'motor.back_emf_constant' both given; "
            "they say the same thing (k_v = 1/k_e): keep one"
        )
    if "velocity_at_max_effort" in output and "speed_effort_gradient" in output:
        raise InputError(
            f"{source}: keys 'output.velocity_at_max_effort' and 'output.speed_effort_gradient' both given; "
            "they say the same thing: keep one"
        )
    if (
        "velocity_dependent_resistance" in sections.get("losses", {})
        and "velocity_dependent_resistance" in output
    ):
        raise InputError(
            f"{source}: 'velocity_dependent_resistance' given in both [losses] and [output]: keep one"
        )
    if "velocity_at_max_effort" in output:
        if "max_effort" not in output or "max_velocity" not in output:
            raise InputError(
                f"{source}: key 'output.velocity_at_max_effort' needs "
                "'output.max_effort' and 'output.max_velocity'"
            )
        if output["velocity_at_max_effort"] > output["max_velocity"]:
            raise InputError(
                f"{source}: key 'output.velocity_at_max_effort': "
                f"{output['velocity_at_max_effort']:g} exceeds "
                f"'output.max_velocity' {output['max_velocity']:g} (SI)"
            )
    _check_output_line(output, source)
    if (
        "no_load_speed" in motor
        and "nominal_speed" in motor
        and not motor["no_load_speed"] > motor["nominal_speed"]
    ):
        raise InputError(
            f"{source}: key 'motor.no_load_speed': {motor['no_load_speed']:g} must exceed "
            f"'motor.nominal_speed' {motor['nominal_speed']:g} (SI)"
        )


def _check_output_line(output: Mapping[str, Any], source: str) -> None:
    """The nominal point needs the no-load speed and its effort, and lies below the no-load speed."""
    if "nominal_velocity" not in output:
        return
    for needed in ("nominal_effort", "no_load_velocity"):
        if needed not in output:
            raise InputError(
                f"{source}: key 'output.nominal_velocity' needs 'output.{needed}' "
                "(a point on the speed-effort line through the no-load speed)"
            )
    if not output["nominal_velocity"] < output["no_load_velocity"]:
        raise InputError(
            f"{source}: key 'output.nominal_velocity': {output['nominal_velocity']:g} must be below "
            f"'output.no_load_velocity' {output['no_load_velocity']:g} (SI)"
        )

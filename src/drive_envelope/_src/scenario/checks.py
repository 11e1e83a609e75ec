"""Validation and reading helpers shared by the scenario tables (one-line errors naming the key).

Every helper raises :class:`~drive_envelope.errors.InputError`; the reading helpers take the file
name (``source``) so their messages start with it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from drive_envelope._src.datasheet.load import read_text as read_text  # re-exported for spec, chain
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import read_quantity

MAX_ITERATIONS = 255
"""Largest solver iteration count: PhysX stores solver iteration counts in 8 bits."""


def unit_for(joint: str, revolute: str, prismatic: str) -> str:
    """The unit string of a quantity for this joint type."""
    return revolute if joint == "revolute" else prismatic


def check_finite(name: str, value: float, *, positive: bool = False, nonnegative: bool = False) -> None:
    """Refuse a value that is not a finite number (or not ``> 0`` / ``>= 0`` when asked)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"{name} must be a finite number, got {value!r}")
    if positive and not value > 0.0:
        raise InputError(f"{name} must be > 0, got {value!r}")
    if nonnegative and value < 0.0:
        raise InputError(f"{name} must be >= 0, got {value!r}")


def check_int(name: str, value: int, low: int) -> None:
    """Refuse a value that is not an integer in ``low..MAX_ITERATIONS``."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= MAX_ITERATIONS:
        raise InputError(f"{name} must be an integer in {low}..{MAX_ITERATIONS}, got {value!r}")


def require(data: Mapping[str, Any], section: str, needs: Mapping[str, str], source: str) -> None:
    """Refuse a table without one of the keys of ``needs`` (key -> what it expects, for the message)."""
    for key, what in needs.items():
        if key not in data:
            raise InputError(f"{source}: missing required key '{section}.{key}' ({what})")


def table(data: Mapping[str, Any], name: str, source: str) -> dict[str, Any]:
    """The table ``[name]`` of a scenario mapping (empty when absent)."""
    value = data.get(name, {})
    if not isinstance(value, Mapping):
        raise InputError(f"{source}: key {name!r}: expected a table [{name}], got {value!r}")
    return dict(value)


def choice(data: Mapping[str, Any], section: str, key: str, choices: tuple[str, ...], source: str) -> str:
    """One of ``choices`` (the first when absent)."""
    value = data.get(key, choices[0])
    if value not in choices:
        raise InputError(
            f"{source}: key '{section}.{key}': expected one of {', '.join(map(repr, choices))}, got {value!r}"
        )
    return str(value)


def quantities(
    data: Mapping[str, Any], section: str, units: Mapping[str, str], source: str
) -> dict[str, float]:
    """Read every key of ``units`` present in ``data`` as an SI float (strings may carry units)."""
    values = {}
    for key, unit in units.items():
        if key in data:
            where = f"{source}: key '{section}.{key}'"
            value = read_quantity(data[key], unit, where)
            if math.isnan(value):
                raise InputError(f"{where}: expected a number in {unit}, got {data[key]!r}")
            values[key] = value
    return values


def one_solve_tgs_note(engine: str, solver: str) -> str | None:
    """What an engine that takes one drive solve per step says of a TGS scenario, or None.

    PhysX's TGS applies loads and clamps the envelope per substep; Newton's own actuator stack (the
    Newton stand's ``drive="actuator"``) solves the drive once per step, so its transients part
    from PhysX's while its steady states agree. The sizes were measured on the shipped TGS
    scenarios against the reference engine, which holds real PhysX to 4e-5 rad/s
    (``tests/test_newton_teststand.py``); the engines' default stands run PhysX's iteration.
    """
    if solver != "tgs":
        return None
    return (
        f"the {engine} engine solves the drive once per step, PhysX's TGS per substep: on the shipped "
        "TGS scenarios transients differ from PhysX by up to 4.0 rad/s and 8.7 N*m, steady states "
        "agree; the stands' default drive runs PhysX's TGS (docs/parity.md)"
    )

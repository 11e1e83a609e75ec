"""The one reader of user values: SI numbers, ``"inf"``, strings with units, and key suggestions.

Every place that takes a value from a file, a dict, a config or a command-line flag reads it with
:func:`read_quantity` (or :func:`read_joint_quantity` when the joint type is not known), so
``"inf"``, ``"300 rpm"`` and a bare SI number mean the same thing everywhere. A bare number is SI:
``12`` in a file, ``"12"`` quoted and ``--set key=12`` are all 12 in the key's SI unit.
"""

from __future__ import annotations

import math

from drive_envelope._src.errors import UnitsError
from drive_envelope._src.params.table import parameter
from drive_envelope._src.units import to_si

INFINITY_WORDS = ("inf", "+inf", "infinity", "+infinity")
"""Spellings of an unbounded value (case-insensitive), e.g. ``max_actuator_velocity = "inf"``."""


def read_quantity(value: object, unit: str, where: str) -> float:
    """Read a user value as an SI float.

    Args:
        value: A bare number (already in ``unit``), ``"inf"`` (or another of :data:`INFINITY_WORDS`),
            a string with units as datasheets print them, or a ``pint.Quantity``.
        unit: The SI unit of the result, as pint reads it (``"rad/s"``, ``"N*m"``).
        where: The file and key, or the argument, the value comes from; it starts every error.

    Returns:
        The value in ``unit`` [SI]; ``inf`` for an unbounded value.

    Raises:
        UnitsError: not a number, an unknown unit, the wrong dimension, or NaN.
    """
    if isinstance(value, str) and value.strip().lower() in INFINITY_WORDS:
        return math.inf
    return to_si(value, unit, where)


def read_joint_quantity(value: object, revolute_unit: str, prismatic_unit: str, where: str) -> float:
    """Read a value whose joint type is unknown: the unit's dimension decides (``"300 rpm"`` or ``"2 m/s"``).

    A bare number is SI for either joint type. The error for a string that fits neither explains
    the revolute (angle) rules, which is where users go wrong.
    """
    if not isinstance(value, str) or value.strip().lower() in INFINITY_WORDS:
        return read_quantity(value, revolute_unit, where)
    try:
        return to_si(value, revolute_unit, where)
    except UnitsError as revolute_error:
        try:
            return to_si(value, prismatic_unit, where)
        except UnitsError:
            raise revolute_error from None


def read_envelope_value(value: object, field: str, where: str) -> float:
    """Read one of the four envelope parameters, revolute or prismatic by the unit given (SI if bare)."""
    row = parameter(field)
    return read_joint_quantity(value, row.unit_revolute, row.unit_prismatic, where)

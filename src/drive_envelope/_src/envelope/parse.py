"""Reading envelopes from mappings (envelope files, dicts): SI numbers or strings with units."""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.params.table import si_unit
from drive_envelope._src.units import to_si
from drive_envelope.errors import InputError

__all__ = ["envelope_from_mapping", "nearest_key", "read_quantity"]

_KEYS = ("name", "joint", *ENVELOPE_FIELDS)


def nearest_key(key: str, valid: tuple[str, ...] | list[str]) -> str:
    """Return ``" (did you mean 'x'?)"`` for the closest valid key, or ``""``."""
    match = difflib.get_close_matches(key, list(valid), n=1, cutoff=0.5)
    return f" (did you mean {match[0]!r}?)" if match else ""


def read_quantity(value: object, unit: str, where: str) -> float:
    """Read an SI number, ``"inf"``, or a string with units, as ``unit`` [SI]."""
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "infinity"):
        return math.inf
    return to_si(value, unit, where)


def envelope_from_mapping(data: Mapping[str, object], *, source: str) -> PerformanceEnvelope:
    """Build a :class:`PerformanceEnvelope` from a mapping; every error names ``source`` and the key."""
    if not isinstance(data, Mapping):
        raise InputError(f"{source}: expected a table of envelope keys, got {type(data).__name__}")
    for key in data:
        if key not in _KEYS:
            raise InputError(
                f"{source}: unknown key {key!r}{nearest_key(str(key), _KEYS)}; valid keys: {', '.join(_KEYS)}"
            )
    joint = data.get("joint", "revolute")
    if joint not in ("revolute", "prismatic"):
        raise InputError(f"{source}: key 'joint': expected 'revolute' or 'prismatic', got {joint!r}")
    name = data.get("name", "")
    if not isinstance(name, str):
        raise InputError(f"{source}: key 'name': expected a string, got {name!r}")
    if "max_effort" not in data:
        raise InputError(
            f"{source}: missing required key 'max_effort' "
            f"(the drive's effort cap, {si_unit('max_effort', joint)})"
        )
    values: dict[str, float] = {}
    for field in ENVELOPE_FIELDS:
        if field in data:
            values[field] = read_quantity(data[field], si_unit(field, joint), f"{source}: key {field!r}")
    try:
        return PerformanceEnvelope(joint=joint, name=name, **values)  # type: ignore[arg-type]
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None

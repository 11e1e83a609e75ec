"""``--set section.key=value`` overrides of a scenario file, applied to its raw mapping before validation."""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from typing import Any

from drive_envelope._src.errors import InputError
from drive_envelope._src.validation import nearest_key

SECTIONS = ("joint", "drive", "envelope", "load", "pendulum", "friction", "simulation")
"""The tables of a scenario file."""


def parse_override(text: str) -> tuple[str, str, object]:
    """Split one ``--set section.key=value`` into ``(section, key, value)``.

    The value is read as a TOML literal (``12``, ``1.5``, ``"pgs"``, ``true``); anything else is
    kept as a plain string, so ``--set drive.target_velocity="30 rpm"`` and
    ``--set simulation.solver=pgs`` both work.

    Raises:
        InputError: no ``=``, or a key that is not ``section.key``.
    """
    import tomllib

    path, sep, raw = text.partition("=")
    section, dot, key = path.strip().partition(".")
    if not sep or not dot or not section or not key or "." in key:
        raise InputError(f"--set {text!r}: expected section.key=value, e.g. drive.target_velocity=12")
    raw = raw.strip()
    try:
        value: object = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return section, key, value


def apply_overrides(data: Mapping[str, Any], overrides: Sequence[str]) -> dict[str, Any]:
    """Return a copy of the raw scenario mapping with ``--set section.key=value`` overrides applied.

    Raises:
        InputError: a malformed override or an unknown section (the key is checked later, with the
            rest of the file).
    """
    result = copy.deepcopy(dict(data))
    for text in overrides:
        section, key, value = parse_override(text)
        if section not in SECTIONS:
            raise InputError(
                f"--set {text!r}: unknown section {section!r}{nearest_key(section, SECTIONS)}; "
                f"valid sections: {', '.join(SECTIONS)}"
            )
        table = result.setdefault(section, {})
        if not isinstance(table, dict):
            raise InputError(f"--set {text!r}: [{section}] is not a table in the scenario file")
        table[key] = value
    return result

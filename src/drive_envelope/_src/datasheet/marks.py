"""What a value's text says besides its SI number: an rms or peak mark, or no unit at all.

The reader turns every value into an SI float, which loses two facts the unit-slip checks need:
``"1.22 N.m/Arms"`` and ``"23Apk"`` are both read as plain amperes (the checks compare the marks),
and ``torque_constant = 91`` is read as 91 N*m/A like ``"91 N*m/A"`` (only the bare number may be
``91 mNm/A`` typed without its unit).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

_RMS = re.compile(r"A\s*\(?\s*(?:rms|RMS)\b")
_PEAK = re.compile(r"A\s*\(?\s*(?:pk|PK|peak)\b")


def current_conventions(merged: Mapping[str, Any]) -> dict[str, str]:
    """Which current-carrying values were marked rms or peak in their text (see ``Datasheet``)."""
    found = {}
    for section, key in (("motor", "torque_constant"), ("controller", "max_current")):
        table = merged.get(section)
        raw = table.get(key) if isinstance(table, Mapping) else None
        if isinstance(raw, str):
            if _RMS.search(raw):
                found[f"{section}.{key}"] = "rms"
            elif _PEAK.search(raw):
                found[f"{section}.{key}"] = "peak"
    return found


def bare_numbers(
    merged: Mapping[str, Any], sections: tuple[str, ...], aliases: Mapping[str, Mapping[str, str]]
) -> frozenset[str]:
    """``"section.key"`` (under the key's own name, not an alias) of each value written without a unit.

    A number (``91``) or a string holding only one (``"91"``, ``--set motor.torque_constant=91``) is
    bare; ``"91 mNm/A"`` is not. The values have been read already, so a string that ``float`` does
    not take has a unit (or a thousands separator, which no motor constant needs).
    """
    found = set()
    for section in sections:
        table = merged.get(section)
        if not isinstance(table, Mapping):
            continue
        for key, raw in table.items():
            if _is_bare(raw):
                found.add(f"{section}.{aliases.get(section, {}).get(str(key), str(key))}")
    return frozenset(found)


def _is_bare(raw: object) -> bool:
    if isinstance(raw, bool):
        return False
    if isinstance(raw, (int, float)):
        return True
    if not isinstance(raw, str):
        return False
    try:
        float(raw)
    except ValueError:
        return False
    return True

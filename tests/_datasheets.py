"""Datasheets for the derive tests: a base mapping with some sections changed."""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

from drive_envelope._src.datasheet.load import datasheet_from_mapping


def sheet_from(base: Mapping[str, Any], source: str, **sections: Any) -> Any:
    """``base`` with some sections updated (a key set to None is removed; ``name``/``joint`` replaced)."""
    data = copy.deepcopy(dict(base))
    for section, values in sections.items():
        if section in ("name", "joint"):
            data[section] = values
            continue
        table = data.setdefault(section, {})
        for key, value in values.items():
            if value is None:
                table.pop(key, None)
            else:
                table[key] = value
    return datasheet_from_mapping(data, source=source)

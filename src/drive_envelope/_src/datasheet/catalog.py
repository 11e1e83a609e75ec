"""The catalog: real actuators as datasheet files shipped in ``drive_envelope/catalog/*.toml``.

Each file is a datasheet (see :mod:`~drive_envelope._src.datasheet.load`) whose every number carries
its source (document URL, table or page) in a comment. A value the datasheet does not print is left
out, so the derivation reports that limit as missing.
"""

from __future__ import annotations

import difflib
import importlib.resources
from dataclasses import dataclass
from importlib.resources.abc import Traversable

from drive_envelope._src.datasheet.load import datasheet_from_mapping
from drive_envelope._src.datasheet.spec import Datasheet
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.files import read_mapping

__all__ = ["CatalogEntry", "catalog_entries", "catalog_entry", "catalog_text", "load_catalog_datasheet"]


@dataclass(frozen=True, kw_only=True, slots=True)
class CatalogEntry:
    """One catalog actuator."""

    key: str
    """Short name used on the command line (the file name without ``.toml``)."""
    name: str
    """Actuator name (the file's ``name``)."""
    joint: str
    """``"revolute"`` or ``"prismatic"``."""
    description: str
    """One line about the actuator."""


def _directory() -> Traversable:
    return importlib.resources.files("drive_envelope").joinpath("catalog")


def _files() -> dict[str, Traversable]:
    return {f.name[: -len(".toml")]: f for f in _directory().iterdir() if f.name.endswith(".toml")}


def catalog_entries() -> list[CatalogEntry]:
    """Every catalog actuator, sorted by key."""
    entries = []
    for key, _ in sorted(_files().items()):
        sheet = load_catalog_datasheet(key)
        entries.append(
            CatalogEntry(key=key, name=sheet.name, joint=sheet.joint, description=sheet.description)
        )
    return entries


def catalog_entry(name: str) -> str | None:
    """The catalog key for ``name`` (a key or an actuator name, case-insensitive), or None."""
    files = _files()
    wanted = name.strip().lower()
    for key in files:
        if key.lower() == wanted:
            return key
    for key, file in files.items():
        data = _read(file, key)
        if str(data.get("name", "")).strip().lower() == wanted:
            return key
    return None


def catalog_text(name: str) -> str:
    """The datasheet file of a catalog actuator, comments (sources) included."""
    return _files()[_key(name)].read_text(encoding="utf-8")


def load_catalog_datasheet(name: str) -> Datasheet:
    """Read a catalog actuator by key or name.

    Raises:
        InputError: no such catalog actuator (with the nearest key).
    """
    key = _key(name)
    return datasheet_from_mapping(_read(_files()[key], key), source=f"catalog:{key}")


def _key(name: str) -> str:
    key = catalog_entry(name)
    if key is None:
        keys = sorted(_files())
        match = difflib.get_close_matches(name, keys, n=1, cutoff=0.4)
        hint = f" (did you mean {match[0]!r}?)" if match else ""
        raise InputError(
            f"{name!r}: no such file or catalog actuator{hint}; `drive-envelope catalog` lists them"
        )
    return key


def _read(file: Traversable, key: str) -> dict[str, object]:
    with importlib.resources.as_file(file) as path:
        data = read_mapping(path)
    return data

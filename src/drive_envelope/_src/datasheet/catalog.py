"""The catalog: real actuators as datasheet files shipped in ``drive_envelope/catalog/*.toml``.

Each file is a datasheet (see :mod:`~drive_envelope._src.datasheet.load`) whose every number carries
its source (document and URL, table or page) in a comment on its line, typed in the vendor's units.
A value the vendor does not print is left out, so the derivation reports that limit as missing,
and the file's comments say what is missing.
"""

from __future__ import annotations

import difflib
import importlib.resources
import re
from collections.abc import Mapping
from dataclasses import dataclass
from importlib.resources.abc import Traversable

from drive_envelope._src.datasheet.load import datasheet_from_mapping
from drive_envelope._src.datasheet.spec import Datasheet
from drive_envelope._src.errors import InputError
from drive_envelope._src.format import first_few
from drive_envelope._src.io.files import read_mapping
from drive_envelope._src.validation import nearest_key

_JOINTS = ("revolute", "prismatic")


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
    sources: tuple[str, ...] = ()
    """Document URLs the numbers come from."""


@dataclass(frozen=True, kw_only=True, slots=True)
class SourcedValue:
    """One value of a catalog file with the source comment written beside it."""

    key: str
    """Dotted key, ``section.key``."""
    value: str
    """The value as written in the file (vendor units)."""
    source: str
    """The comment on its line: the document, table or page, and the printed text."""


def _directory() -> Traversable:
    return importlib.resources.files("drive_envelope").joinpath("catalog")


def _files() -> dict[str, Traversable]:
    return {f.name[: -len(".toml")]: f for f in _directory().iterdir() if f.name.endswith(".toml")}


def catalog_entries(*, joint: str | None = None, search: str | None = None) -> list[CatalogEntry]:
    """Catalog actuators sorted by key, optionally filtered.

    Args:
        joint: Only ``"revolute"`` or only ``"prismatic"`` actuators.
        search: Words that must all appear (case-insensitive) in the key, name, description or
            source URLs, each at the start of a word there (``"ec 45"`` is not in "FEETECH" or
            "2EC"), e.g. ``"unitree"`` or ``"dynamixel 12 v"``.

    Raises:
        InputError: ``joint`` is not ``revolute`` or ``prismatic``.
    """
    if joint is not None and joint not in _JOINTS:
        raise InputError(f"--joint {joint!r}: expected 'revolute' or 'prismatic'")
    words = search.lower().split() if search else []
    entries = []
    for key in sorted(_files()):
        sheet = load_catalog_datasheet(key)
        entry = CatalogEntry(
            key=key, name=sheet.name, joint=sheet.joint, description=sheet.description, sources=sheet.sources
        )
        if joint is not None and entry.joint != joint:
            continue
        text = " ".join([entry.key, entry.name, entry.description, *entry.sources]).lower()
        if all(_holds(text, word) for word in words):
            entries.append(entry)
    return entries


def _holds(text: str, word: str) -> bool:
    """Whether ``word`` starts somewhere in ``text`` after a character that is not a letter or digit."""
    return re.search(r"(?<![a-z0-9])" + re.escape(word), text) is not None


def no_match_error(search: str | None, joint: str | None = None) -> InputError:
    """The one line for ``catalog --search`` that matches nothing: the query and what to try instead.

    The nearest key to the whole query is suggested when it is close (``robstride-rs1`` ->
    ``robstride-rs01``); else a word no entry holds is replaced by the nearest word of the catalog's
    keys and names (``ak-80`` -> ``ak80``) when that search finds entries, or named. The line ends
    with the command that lists every actuator.
    """
    entries = catalog_entries(joint=joint)
    texts = [" ".join([e.key, e.name, e.description, *e.sources]).lower() for e in entries]
    words = search.lower().split() if search else []
    vocabulary = sorted(
        {w for e in entries for w in re.split(r"[^a-z0-9.]+", f"{e.key} {e.name}".lower()) if w}
    )
    absent = [word for word in words if not any(_holds(text, word) for text in texts)]
    corrected = [
        next(iter(difflib.get_close_matches(word, vocabulary, 1, 0.6)), "") if word in absent else word
        for word in words
    ]
    found = [e.key for e, text in zip(entries, texts, strict=True) if all(w and w in text for w in corrected)]
    hint = nearest_key(" ".join(words), [e.key for e in entries], cutoff=0.75)
    if not hint and found:
        hint = f" (did you mean --search {' '.join(corrected)!r}? it lists {first_few(found, 3, str)})"
    elif not hint and absent and len(absent) < len(words):
        hint = f" ({', '.join(map(repr, absent))} is in no entry)"
    flag = f" --joint {joint}" if joint else ""
    return InputError(
        f"catalog --search {search!r}{flag}: no catalog actuator matches{hint}; "
        f"`drive-envelope catalog{flag}` lists all {len(entries)}"
    )


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


_SECTION = re.compile(r"^\s*\[([A-Za-z_]+)\]")
_VALUE = re.compile(r"^\s*([A-Za-z_]+)\s*=\s*(.+?)\s*(?:#\s*(.*))?$")


def catalog_sources(name: str) -> list[SourcedValue]:
    """Every value of a catalog actuator's datasheet with the source comment on its line, in file order."""
    values: list[SourcedValue] = []
    section = ""
    for line in catalog_text(name).splitlines():
        header = _SECTION.match(line)
        if header is not None:
            section = header.group(1)
            continue
        match = _VALUE.match(line)
        if match is None or not section:
            continue
        value, comment = _split_comment(match.group(2), match.group(3))
        values.append(SourcedValue(key=f"{section}.{match.group(1)}", value=value, source=comment))
    return values


def _split_comment(value: str, comment: str | None) -> tuple[str, str]:
    """Keep a ``#`` inside a quoted value (``"0.14 s/60°"`` has none, but a URL could) with the value."""
    if value.count('"') % 2 == 1 and comment is not None:  # the '#' was inside the string
        head, _, tail = comment.partition('"')
        value, comment = f'{value}#{head}"', tail.lstrip(" #")
    return value.strip(), (comment or "").strip()


def load_catalog_datasheet(name: str, *, overrides: Mapping[str, object] | None = None) -> Datasheet:
    """Read a catalog actuator by key or name (``overrides``: ``section.key`` values, as ``derive --set``).

    Raises:
        InputError: no such catalog actuator (with the nearest key), or a bad override.
    """
    key = _key(name)
    return datasheet_from_mapping(_read(_files()[key], key), source=f"catalog:{key}", overrides=overrides)


def _key(name: str) -> str:
    key = catalog_entry(name)
    if key is None:
        from drive_envelope._src.datasheet.maps import robot_maps

        shipped = {robot.key: robot for robot in robot_maps()}
        if name in shipped:  # a robot map's name got the nearest actuator's as a suggestion
            raise InputError(
                f"{name!r} is a robot map, not an actuator: {shipped[name].path} "
                f"(`drive-envelope catalog --maps` lists them; usd and mujoco apply take --map {name})"
            )
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

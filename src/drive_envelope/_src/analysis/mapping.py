"""Which envelope applies to which joint of a long-format log.

A joint mapping file is TOML (or JSON/YAML) with one table ``joints``: each key is a joint name or a
glob pattern (``*``, ``?``, ``[...]``), each value an envelope file, a datasheet file, a catalog
actuator name, or an inline envelope table::

    # joints.toml
    [joints]
    shoulder_pan = "envelopes/shoulder.toml"     # path relative to this file
    "elbow_*" = "tmotor-ak80-6"                 # datasheet file or catalog name
    "wrist_*" = { max_effort = "12 N*m", max_actuator_velocity = "300 deg/s" }

An exact name wins over patterns; patterns are tried in file order. A log joint that nothing
matches is an error (no joint is silently left unchecked).
"""

from __future__ import annotations

import fnmatch
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.envelope.model import PerformanceEnvelope, envelope_from_mapping
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.files import read_mapping

__all__ = ["JointMapping", "is_mapping_file", "load_joint_mapping"]

_MAPPING_SUFFIXES = (".toml", ".json", ".yaml", ".yml")


@dataclass(frozen=True, kw_only=True, slots=True)
class JointMapping:
    """Envelopes per joint name (exact names and glob patterns), resolved eagerly."""

    entries: tuple[tuple[str, PerformanceEnvelope], ...]
    """``(name or pattern, envelope)`` in file order."""
    source: str = "<mapping>"
    """File the mapping came from, for messages."""

    def envelope_for(self, joint: str) -> PerformanceEnvelope:
        """The envelope of ``joint``: an exact key, else the first matching pattern.

        Raises:
            InputError: no key matches ``joint``.
        """
        exact = [envelope for key, envelope in self.entries if key == joint]
        matches = exact or [envelope for key, envelope in self.entries if fnmatch.fnmatchcase(joint, key)]
        if not matches:
            keys = ", ".join(key for key, _ in self.entries)
            raise InputError(f"{self.source}: no envelope for joint {joint!r} of the log (keys: {keys})")
        return matches[0]

    @classmethod
    def from_envelopes(
        cls, envelopes: Mapping[str, PerformanceEnvelope], *, source: str = "<mapping>"
    ) -> JointMapping:
        """A mapping from a dict of joint name (or pattern) -> envelope."""
        for key, envelope in envelopes.items():
            if not isinstance(envelope, PerformanceEnvelope):
                raise InputError(
                    f"{source}: joint {key!r}: expected a PerformanceEnvelope, got {type(envelope).__name__}"
                )
        return cls(entries=tuple(envelopes.items()), source=source)


def is_mapping_file(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a joint mapping file (a readable table file with a ``joints`` table)."""
    file = Path(path)
    if not file.is_file() or file.suffix.lower() not in _MAPPING_SUFFIXES:
        return False
    try:
        return isinstance(read_mapping(file).get("joints"), Mapping)
    except InputError:
        return False


def load_joint_mapping(path: str | os.PathLike[str]) -> JointMapping:
    """Read a joint mapping file; every envelope it names is resolved now, so errors come early.

    Raises:
        InputError: malformed file, missing ``joints`` table, an unknown key, or an envelope that
            cannot be resolved (the message names the file and the joint key).
    """
    file = Path(path)
    data = read_mapping(file)
    unknown = sorted(set(data) - {"joints"})
    if unknown:
        raise InputError(f"{file}: unknown key {unknown[0]!r}; a joint mapping has one table 'joints'")
    table = data.get("joints")
    if not isinstance(table, Mapping) or not table:
        raise InputError(f"{file}: key 'joints': expected a table of joint name -> envelope, got {table!r}")
    entries = []
    for key, value in table.items():
        where = f"{file}: joints.{key}"
        if isinstance(value, Mapping):
            envelope = envelope_from_mapping(value, source=where)
        elif isinstance(value, str) and value.strip():
            envelope = resolve_envelope(value, base=file.parent, where=where)
        else:
            raise InputError(
                f"{where}: expected an envelope file, datasheet, catalog name or inline table, got {value!r}"
            )
        entries.append((str(key), envelope))
    return JointMapping(entries=tuple(entries), source=str(file))

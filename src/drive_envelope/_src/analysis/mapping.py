"""Which envelope applies to which joint of a long-format log.

A joint mapping file is TOML (or JSON/YAML) with one table ``joints``: each key is a joint name or a
glob pattern (``*``, ``?``, ``[...]``; not a regular expression), each value an envelope file, a
datasheet file, a catalog actuator name, or a table (an inline envelope, or ``envelope`` /
``datasheet``)::

    # joints.toml
    [joints]
    shoulder_pan = "envelopes/shoulder.toml"     # path relative to this file
    "elbow_*" = "tmotor-ak80-6"                 # datasheet file or catalog name
    "wrist_*" = { max_effort = "12 N*m", max_actuator_velocity = "300 deg/s" }

The values are read by the map files' reader
(:func:`~drive_envelope._src.adapters.usd.joint_map.read_entry`, no USD), so a value means the same
in ``check`` as in ``usd apply --map`` and ``mujoco apply --map`` (``instance`` is read and not used
here). The matching differs: an exact name wins over patterns, then patterns are tried in file
order. A log joint that nothing matches is an error (no joint is silently left unchecked); a key
that matches no joint of the log, or whose joints all take an earlier key, is reported by
:meth:`JointMapping.unused_keys` (a warning: a log may cover part of a robot).
"""

from __future__ import annotations

import fnmatch
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from drive_envelope._src.adapters.usd.joint_map import case_hint, glob_hint, read_entry, read_map_table
from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.format import first_few
from drive_envelope._src.io.files import read_mapping

_MAPPING_SUFFIXES = (".toml", ".json", ".yaml", ".yml")
_SHOWN = 3  # joint names quoted in one message


@dataclass(frozen=True, kw_only=True, slots=True)
class UnusedKey:
    """A mapping key that gave no joint of the log its envelope."""

    key: str
    """The key (joint name or glob) as written."""
    reason: str
    """Why: ``"matches no joint of the log"`` (with hints), or the earlier keys that took its joints."""
    where: str
    """The mapping and key, for messages: ``"joints.toml: key 'joints.elbow_*'"``."""


@dataclass(frozen=True, kw_only=True, slots=True)
class JointMapping:
    """Envelopes per joint name (exact names and glob patterns), resolved eagerly."""

    entries: tuple[tuple[str, PerformanceEnvelope], ...]
    """``(name or pattern, envelope)`` in file order."""
    source: str = "<mapping>"
    """File the mapping came from, for messages."""

    def _winner(self, joint: str) -> int | None:
        """Index of the entry that gives ``joint`` its envelope: an exact key, else the first glob."""
        keys = [key for key, _ in self.entries]
        if joint in keys:
            return keys.index(joint)
        return next((i for i, key in enumerate(keys) if fnmatch.fnmatchcase(joint, key)), None)

    def envelope_for(self, joint: str) -> PerformanceEnvelope:
        """The envelope of ``joint``: an exact key, else the first matching pattern.

        Raises:
            InputError: no key matches ``joint``.
        """
        index = self._winner(joint)
        if index is None:
            keys = ", ".join(key for key, _ in self.entries)
            hint = next((glob_hint(key) for key, _ in self.entries if glob_hint(key)), "")
            hint = hint or case_hint(joint, [key for key, _ in self.entries])
            where = f"{self.source}: no envelope for joint {joint!r} of the log"
            raise InputError(f"{where} (keys: {keys}){hint}")
        return self.entries[index][1]

    def unused_keys(self, joints: Sequence[str]) -> tuple[UnusedKey, ...]:
        """The keys that give none of ``joints`` (the log's joint names) an envelope, in file order.

        A key matches no joint (the reason says so, with a hint when it is written as a regular
        expression or differs from a joint only in case), or every joint it matches takes an
        earlier key (exact names first, then globs in file order): it is never used.
        """
        winners = {joint: self._winner(joint) for joint in dict.fromkeys(joints)}
        unused = []
        for index, (key, _) in enumerate(self.entries):
            matched = [joint for joint in winners if joint == key or fnmatch.fnmatchcase(joint, key)]
            if not matched:
                reason = f"matches no joint of the log{case_hint(key, list(winners))}{glob_hint(key)}"
            elif all(winners[joint] != index for joint in matched):
                takers = dict.fromkeys(self.entries[i][0] for j in matched if (i := winners[j]) is not None)
                reason = (
                    f"never used: every joint of the log it matches ({first_few(matched, _SHOWN)}) takes "
                    f"{first_few(list(takers), _SHOWN)} first (exact names first, then globs in file order)"
                )
            else:
                continue
            unused.append(UnusedKey(key=key, reason=reason, where=f"{self.source}: key 'joints.{key}'"))
        return tuple(unused)

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
    entries = []
    resolved: dict[str, PerformanceEnvelope] = {}  # each source read once
    for key, value in read_map_table(file).items():
        entry = read_entry(key, value, file.parent, str(file))
        envelope = entry.envelope
        if envelope is None:
            if entry.source not in resolved:
                resolved[entry.source] = resolve_envelope(entry.source, base=file.parent, where=entry.where)
            envelope = resolved[entry.source]
        entries.append((key, envelope))
    return JointMapping(entries=tuple(entries), source=str(file))

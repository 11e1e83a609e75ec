"""Map files: which envelope goes on which joint, by glob on joint names or paths (no USD in here).

A map file is a TOML, JSON or YAML file with one ``[joints]`` table of pattern -> envelope source::

    # go2.toml
    [joints]
    "*_hip_joint" = "unitree-go2-hip"                      # a catalog name
    "*_thigh_joint" = "actuators/go2_thigh.toml"           # a file, relative to this map's folder
    "*_calf_joint" = { datasheet = "go2_calf.toml", instance = "angular" }
    "*_foot_joint" = { max_effort = "12 N*m", max_actuator_velocity = "2.6 rad/s" }   # inline

The format-independent part lives here, so ``usd apply --map`` and ``mujoco apply --map`` read the
same files the same way; an engine only supplies its list of joint names (MuJoCo) or prim paths
(USD)::

    joint_map = read_map("go2.toml")
    match = match_joints(joint_map, ["FL_hip_joint", "FL_thigh_joint", "FL_calf_joint"])
    for message in match.warnings:
        print(message)                                     # overlapping patterns, redundant entries
    for item in resolve_envelopes(match):
        item.joint, item.envelope, item.entry.instance     # each source resolved once

Rules:

* Patterns are :func:`fnmatch.fnmatchcase` globs (``*``, ``?``, ``[abc]``; case-sensitive; ``*``
  also crosses ``/``). A pattern with a ``/`` is matched against the whole name (a USD prim path
  such as ``/go2/joints/FL_hip_joint``); a pattern without one is matched against the part after
  the last ``/`` (the prim's own name), so a map written with bare MuJoCo joint names also works on
  a USD asset of the same robot.
* Patterns are tried in file order; the first one that matches a joint gives its envelope.
* Mistakes are errors naming the map file and key (``go2.toml: key 'joints.*_hip'``): a pattern
  that matches no joint (with the nearest names, a "did you mean" for a name that differs only in
  case, and a hint when it is written as a regular expression), a pattern every joint of which an
  earlier pattern with another source already took (it would silently do nothing), a source file
  that does not exist, an unknown key.
* :func:`read_entry` is the one reader of a map value; ``check``'s joint mappings
  (:mod:`drive_envelope._src.analysis.mapping`) read their values with it too, and
  :func:`glob_hint` is their hint for a key written as a regular expression.
* A joint that two patterns with different sources match gets a warning (first match wins).
"""

from __future__ import annotations

import difflib
import fnmatch
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope, envelope_from_mapping
from drive_envelope._src.errors import InputError
from drive_envelope._src.format import first_few
from drive_envelope._src.validation import nearest_key  # keyed_error: re-exported for apply

_FILE_SUFFIXES = (".toml", ".json", ".yaml", ".yml")
_SHOWN = 3  # joint names quoted in one message
_SOURCE_KEYS = ("envelope", "datasheet")
_ENVELOPE_KEYS = ("name", "joint", *ENVELOPE_FIELDS)  # an envelope file's keys (envelope_from_mapping)
_TABLE_KEYS = (*_SOURCE_KEYS, "instance", *_ENVELOPE_KEYS)
# what only a regular expression means: .* .+ \d ... + { } ^ $ | ( ); globs know * ? [...] only
_REGEX = re.compile(r"\.[*+]|\\|[+{}^$|()]")


@dataclass(frozen=True, kw_only=True, slots=True)
class MapEntry:
    """One line of a map file: the joints matching ``pattern`` get the envelope of ``source``."""

    pattern: str
    """Glob on joint names or prim paths (see the module docstring)."""
    source: str
    """Envelope file or datasheet file (absolute when found relative to the map), or catalog name;
    ``""`` for an inline envelope."""
    envelope: PerformanceEnvelope | None = None
    """The inline envelope (SI, joint side) of a table of envelope keys, else None."""
    instance: str | None = None
    """Drive instance (USD: ``angular``, ``linear``, ``rotX`` ...), or None for the joint's default."""
    where: str = ""
    """Where the entry is, for messages: ``"map.toml: key 'joints.<pattern>'"``."""


@dataclass(frozen=True, kw_only=True, slots=True)
class JointMap:
    """A parsed map file."""

    path: str
    """The map file as given."""
    entries: tuple[MapEntry, ...]
    """The entries in file order."""


@dataclass(frozen=True, kw_only=True, slots=True)
class MappedJoint:
    """One joint and the entry that won it (with the resolved envelope after :func:`resolve_envelopes`)."""

    joint: str
    """Joint name or prim path, as given to :func:`match_joints`."""
    entry: MapEntry
    """The first entry whose pattern matches the joint."""
    envelope: PerformanceEnvelope | None = None
    """The entry's envelope (SI, joint side); None until resolved."""


@dataclass(frozen=True, kw_only=True, slots=True)
class MapMatch:
    """The result of :func:`match_joints`."""

    joint_map: JointMap
    """The map that was matched."""
    joints: tuple[MappedJoint, ...]
    """Every matched joint, in the order of the joint list given."""
    warnings: tuple[str, ...] = ()
    """One line per overlap of patterns with different sources and per redundant entry."""


def read_map(path: str | os.PathLike[str]) -> JointMap:
    """Read a map file (TOML/JSON/YAML) with one ``[joints]`` table of pattern -> envelope source.

    ``path`` may also name a robot map shipped with the package (``"unitree-go2"``,
    ``"franka-fr3"``: ``drive_envelope/maps/``) when no such file exists. Each value is read by
    :func:`read_entry`.

    Example::

        joint_map = read_map("examples/usd/map.toml")
        [entry.pattern for entry in joint_map.entries]     # ['/Robot/joints/shoulder', ...]

    Raises:
        InputError: an unreadable file or unknown map name, a missing ``[joints]`` table, an
            unknown key, an empty pattern, a value of the wrong type or a source file that does not
            exist, naming the key.
    """
    path = _map_file(path)
    name = os.fspath(path)
    base = Path(path).parent
    entries = tuple(read_entry(pattern, value, base, name) for pattern, value in read_map_table(path).items())
    return JointMap(path=name, entries=entries)


def read_map_table(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The ``[joints]`` table of a map file, keys as strings, in file order (values unread).

    Raises:
        InputError: an unreadable file, a key other than ``joints``, or no (or an empty) table.
    """
    from drive_envelope._src.io.files import read_mapping

    name = os.fspath(path)
    data = read_mapping(path)
    unknown = [key for key in data if key != "joints"]
    if unknown:
        raise InputError(
            f"{name}: unknown key {unknown[0]!r}; expected one [joints] table of pattern -> envelope"
        )
    joints = data.get("joints")
    if not isinstance(joints, Mapping) or not joints:
        raise InputError(
            f"{name}: missing [joints] table of joint pattern -> envelope file, datasheet or catalog name"
        )
    return {str(key): value for key, value in joints.items()}


def _map_file(path: str | os.PathLike[str]) -> str | os.PathLike[str]:
    """A map file as given, or the shipped robot map of that name (``"unitree-go2"``)."""
    name = os.fspath(path)
    if Path(name).is_file() or "/" in name or os.sep in name or Path(name).suffix not in ("", ".toml"):
        return path
    from drive_envelope._src.datasheet.maps import robot_map_path

    try:
        return robot_map_path(name)
    except InputError as exc:
        raise InputError(f"{name}: no such map file, and {exc}") from None


def read_entry(pattern: str, value: Any, base: Path, name: str) -> MapEntry:
    """One value of a map's ``[joints]`` table: a source, or a table of a source or an inline envelope.

    A value is a string (an envelope file, a datasheet file or a catalog name), or a table holding
    either exactly one of ``envelope`` / ``datasheet``, or the keys of an envelope file
    (``max_effort``, ``max_actuator_velocity``, ``velocity_dependent_resistance``,
    ``speed_effort_gradient``, ``name``, ``joint``; SI numbers, ``"inf"`` or strings with units), and
    in both cases an optional ``instance``.

    Args:
        pattern: The key (joint name, path or glob).
        value: The value as read from the file.
        base: Folder a relative file name is looked up in first (the map's), then the current folder.
        name: The map file, for messages.

    Raises:
        InputError: an empty pattern, an unknown key, both a source and envelope keys, a bad
            instance, a bad inline value, a missing source file, naming ``name`` and the key.
    """
    where = f"{name}: key 'joints.{pattern}'"
    if not pattern.strip():
        raise InputError(f"{where}: expected a joint name or path pattern, got an empty key")
    instance = None
    if isinstance(value, Mapping):
        keys = [str(key) for key in value]
        for key in keys:
            if key not in _TABLE_KEYS:
                raise InputError(
                    f"{where}: unknown key {key!r}{nearest_key(key, _TABLE_KEYS)}; expected envelope, "
                    f"datasheet or an inline envelope ({', '.join(_ENVELOPE_KEYS)}), and optionally instance"
                )
        sources = [key for key in _SOURCE_KEYS if key in keys]
        inline = [key for key in keys if key in _ENVELOPE_KEYS]
        if sources and inline:
            raise InputError(
                f"{where}: key {sources[0]!r} with inline envelope key(s) {', '.join(map(repr, inline))}; "
                "expected either a source (envelope or datasheet) or an inline envelope"
            )
        if len(sources) > 1 or not (sources or inline):
            raise InputError(
                f"{where}: expected exactly one of 'envelope' or 'datasheet', or an inline envelope "
                f"(max_effort, ...), got {dict(value)!r}"
            )
        instance = value.get("instance")
        if instance is not None and (not isinstance(instance, str) or not instance.strip()):
            raise InputError(
                f"{where}: key 'instance': expected a string such as 'angular', got {instance!r}"
            )
        if inline:
            envelope = envelope_from_mapping({key: value[key] for key in inline}, source=where)
            return MapEntry(pattern=pattern, source="", envelope=envelope, instance=instance, where=where)
        value = value[sources[0]]
    if not isinstance(value, str) or not value.strip():
        raise InputError(
            f"{where}: expected an envelope file, datasheet file or catalog name, got {value!r} "
            "(or a table: an inline envelope such as { max_effort = '12 N*m' }, or envelope/datasheet)"
        )
    return MapEntry(pattern=pattern, source=_source(value, base, where), instance=instance, where=where)


def _source(value: str, base: Path, where: str) -> str:
    """A file named relative to the map's folder (else the current folder), or a catalog name."""
    for candidate in (base / value, Path(value)):
        if candidate.is_file():
            return str(candidate)
    if Path(value).suffix.lower() in _FILE_SUFFIXES or "/" in value or os.sep in value:
        raise InputError(
            f"{where}: no such file {value!r} (looked in {str(base) or '.'!r} and the current folder)"
        )
    return value  # a catalog name; resolve_envelopes says if there is no such actuator


def _subject(pattern: str, joint: str) -> str:
    """What ``pattern`` is matched against: the whole name, or its last ``/`` part."""
    return joint if "/" in pattern else joint.rpartition("/")[2]


def _names(joints: Sequence[str], show: Callable[[str], str] = repr) -> str:
    """The first few ``joints`` (each written by ``show``) and how many more there are."""
    return first_few(joints, _SHOWN, show)


def glob_hint(pattern: str) -> str:
    """``"; patterns are globs ..."`` when ``pattern`` holds regular-expression syntax, else ``""``.

    Regular-expression syntax is ``.*``, ``.+``, a backslash, ``+``, ``{``, ``}``, ``^``, ``$``,
    ``|``, ``(`` or ``)``: a glob has no such operators, so ``"elbow_.*"`` matches only a name with
    a literal ``.`` after ``elbow_``.
    """
    if not _REGEX.search(pattern):
        return ""
    return "; patterns are globs (*, ?, [...]), not regular expressions (write 'elbow_*', not 'elbow_.*')"


def case_hint(pattern: str, names: Sequence[str]) -> str:
    """``"; did you mean ..."`` naming the ``names`` that ``pattern`` matches only up to case, else ``""``.

    Matching is case-sensitive (:func:`fnmatch.fnmatchcase`); this says when case is what is wrong.
    """
    folded = pattern.casefold()
    close = [name for name in dict.fromkeys(names) if fnmatch.fnmatchcase(name.casefold(), folded)]
    if not close:
        return ""
    return f"; did you mean {_names(close)}? (names are case-sensitive)"


def _no_match(entry: MapEntry, joints: Sequence[str]) -> InputError:
    subjects = sorted({_subject(entry.pattern, joint) for joint in joints})
    hint = case_hint(entry.pattern, subjects)
    if not hint:
        close = difflib.get_close_matches(entry.pattern, subjects, n=_SHOWN, cutoff=0.5)
        hint = f"; close: {', '.join(repr(c) for c in close)}" if close else ""
    what = "joint path" if "/" in entry.pattern else "joint name"
    if "/" not in entry.pattern and any("/" in joint for joint in joints):
        what += " (the part after the last '/')"  # how a USD prim path is matched; MJCF names have no '/'
    return InputError(
        f"{entry.where}: matches no {what} of the {len(joints)} joints{hint}{glob_hint(entry.pattern)}"
    )


def _same_source(a: MapEntry, b: MapEntry) -> bool:
    return (a.source, a.envelope, a.instance) == (b.source, b.envelope, b.instance)


def match_joints(joint_map: JointMap, joints: Sequence[str]) -> MapMatch:
    """Give each joint the first entry whose pattern matches it.

    Example::

        match = match_joints(read_map("go2.toml"), ["FL_hip_joint", "FL_thigh_joint"])
        [(item.joint, item.entry.source) for item in match.joints]

    Args:
        joint_map: The map, from :func:`read_map`.
        joints: Joint names (MuJoCo) or prim paths (USD) that can take an envelope; duplicates are
            ignored.

    Returns:
        The matched joints in the order of ``joints`` (joints no pattern matches are left out) and
        the warnings.

    Raises:
        InputError: an entry that matches no joint, or one whose joints earlier entries with
            another source all took already, naming its key.
    """
    unique = list(dict.fromkeys(joints))
    winner: dict[str, MapEntry] = {}
    messages: list[str] = []
    for entry in joint_map.entries:
        matched = [
            joint for joint in unique if fnmatch.fnmatchcase(_subject(entry.pattern, joint), entry.pattern)
        ]
        if not matched:
            raise _no_match(entry, unique)
        taken = [joint for joint in matched if joint in winner]
        earlier = list(dict.fromkeys(winner[joint] for joint in taken))
        conflicting = [other for other in earlier if not _same_source(other, entry)]
        if len(taken) == len(matched):
            if conflicting:
                patterns = ", ".join(repr(other.pattern) for other in conflicting)
                raise InputError(
                    f"{entry.where}: never used: every joint it matches ({_names(matched)}) already takes "
                    f"an earlier pattern ({patterns}; the first match wins): move it above them or remove it"
                )
            messages.append(
                f"{entry.where}: redundant: earlier patterns with the same source match all its joints"
            )
        for other in conflicting:
            shared = [joint for joint in taken if winner[joint] is other]
            messages.append(
                f"{entry.where}: {len(shared)} joint(s) it matches keep the envelope of the earlier pattern "
                f"{other.pattern!r} (first match wins): {_names(shared)}"
            )
        for joint in matched:
            winner.setdefault(joint, entry)
    mapped = tuple(MappedJoint(joint=joint, entry=winner[joint]) for joint in unique if joint in winner)
    return MapMatch(joint_map=joint_map, joints=mapped, warnings=tuple(messages))


def resolve_envelopes(match: MapMatch) -> list[MappedJoint]:
    """Resolve each matched joint's source to its envelope (each source read once).

    Example::

        for item in resolve_envelopes(match_joints(read_map("go2.toml"), names)):
            print(item.joint, item.envelope.max_effort)

    Raises:
        InputError: a source that is not an envelope file, a datasheet or a catalog name, with the
            map key in front of the resolver's message. An inline envelope is used as read.
    """
    from drive_envelope._src.datasheet.resolve import resolve_envelope

    cache: dict[str, PerformanceEnvelope] = {}
    resolved = []
    for item in match.joints:
        if item.entry.envelope is not None:  # inline: read with the map
            resolved.append(replace(item, envelope=item.entry.envelope))
            continue
        source = item.entry.source
        if source not in cache:
            cache[source] = resolve_envelope(
                source, base=Path(match.joint_map.path).parent, where=item.entry.where
            )
        resolved.append(MappedJoint(joint=item.joint, entry=item.entry, envelope=cache[source]))
    return resolved

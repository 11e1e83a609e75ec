"""Apply envelopes to a whole robot asset: open, edit in memory, write atomically.

A map file assigns envelope sources to joints by glob on the joint's prim path::

    # map.toml: joint glob -> envelope file, datasheet file or catalog name
    [joints]
    "/Robot/*/hip_*" = "actuators/ak80-6.toml"
    "/Robot/*/knee" = { envelope = "knee.toml", instance = "angular" }

Relative file names are relative to the map file. Patterns are tried in file order and the first
that matches a joint wins; a pattern that matches no joint is an error (a typo must not pass
silently). Globs follow :func:`fnmatch.fnmatchcase` (``*`` also crosses ``/``).
"""

from __future__ import annotations

import fnmatch
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    from pxr import Usd

__all__ = ["AppliedDrive", "MapEntry", "apply_envelopes", "match_map", "read_map"]


@dataclass(frozen=True, kw_only=True, slots=True)
class MapEntry:
    """One line of a map file: joints matching ``pattern`` get the envelope of ``source``."""

    pattern: str
    """Glob on the joint's prim path."""
    source: str
    """Envelope file, datasheet file (resolved against the map's folder) or catalog name."""
    instance: str | None = None
    """Drive instance, or None for the joint type's default."""


@dataclass(frozen=True, kw_only=True, slots=True)
class AppliedDrive:
    """What one edit did, for the command's report."""

    joint_path: str
    """Prim path of the joint."""
    instance: str
    """Drive instance written."""
    envelope: PerformanceEnvelope
    """The envelope written (SI)."""
    warnings: tuple[str, ...] = ()
    """Authoring warnings for this joint."""


def read_map(path: str | os.PathLike[str]) -> list[MapEntry]:
    """Read a map file (TOML/JSON/YAML) with a ``[joints]`` table of glob -> source.

    Raises:
        InputError: a missing ``[joints]`` table, an entry that is neither a string nor a table with
            ``envelope`` / ``datasheet`` (and optional ``instance``), or an unknown key.
    """
    from drive_envelope._src.io.files import read_mapping

    data = read_mapping(path)
    base = Path(path).parent
    unknown = [key for key in data if key != "joints"]
    if unknown:
        raise InputError(
            f"{path}: unknown key {unknown[0]!r}; expected one [joints] table of glob -> envelope"
        )
    joints = data.get("joints")
    if not isinstance(joints, Mapping) or not joints:
        raise InputError(
            f"{path}: missing [joints] table of joint-path glob -> envelope file, datasheet or catalog name"
        )
    return [
        _map_entry(pattern, value, base, f"{path}: key 'joints.{pattern}'")
        for pattern, value in joints.items()
    ]


def _map_entry(pattern: str, value: Any, base: Path, where: str) -> MapEntry:
    instance = None
    if isinstance(value, Mapping):
        allowed = ("envelope", "datasheet", "instance")
        for key in value:
            if key not in allowed:
                raise InputError(f"{where}: unknown key {key!r}; expected envelope, datasheet or instance")
        sources = [value[k] for k in ("envelope", "datasheet") if k in value]
        if len(sources) != 1:
            raise InputError(
                f"{where}: expected exactly one of 'envelope' or 'datasheet', got {dict(value)!r}"
            )
        instance = value.get("instance")
        if instance is not None and not isinstance(instance, str):
            raise InputError(
                f"{where}: key 'instance': expected a string such as 'angular', got {instance!r}"
            )
        value = sources[0]
    if not isinstance(value, str) or not value.strip():
        raise InputError(f"{where}: expected an envelope file, datasheet file or catalog name, got {value!r}")
    candidate = base / value
    return MapEntry(
        pattern=pattern, source=str(candidate) if candidate.is_file() else value, instance=instance
    )


def _joint_paths(stage: Usd.Stage) -> list[str]:
    """Paths of the joints that can carry an envelope (revolute, prismatic, D6)."""
    from pxr import UsdPhysics

    from drive_envelope._src.adapters.usd.authoring import joint_kind

    paths = []
    for prim in stage.Traverse():
        if prim.IsA(UsdPhysics.Joint):
            try:
                joint_kind(prim)
            except InputError:
                continue  # fixed, spherical, distance joints have no drive envelope
            paths.append(str(prim.GetPath()))
    return paths


def apply_envelopes(
    stage: Usd.Stage, assignments: list[tuple[str, PerformanceEnvelope, str | None]]
) -> list[AppliedDrive]:
    """Write each ``(joint_path, envelope, instance)`` on the stage, collecting the warnings per joint.

    Raises:
        InputError: from :func:`~drive_envelope._src.adapters.usd.authoring.write_envelope`; the stage may
            then be partly edited in memory, so callers write nothing.
    """
    from drive_envelope._src.adapters.usd.authoring import write_envelope

    results = []
    for joint_path, envelope, instance in assignments:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            inst = write_envelope(stage, joint_path, envelope, instance)
        messages = tuple(str(w.message) for w in caught)
        results.append(
            AppliedDrive(joint_path=joint_path, instance=inst, envelope=envelope, warnings=messages)
        )
    return results


def match_map(
    stage: Usd.Stage, entries: list[MapEntry], map_name: str
) -> list[tuple[str, PerformanceEnvelope, str | None]]:
    """Assign each joint the first matching entry's envelope.

    Raises:
        InputError: an entry matching no joint, or a source that cannot be resolved.
    """
    joints = _joint_paths(stage)
    assignments: dict[str, tuple[str, PerformanceEnvelope, str | None]] = {}
    cache: dict[str, PerformanceEnvelope] = {}
    for entry in entries:
        matched = [path for path in joints if fnmatch.fnmatchcase(path, entry.pattern)]
        if not matched:
            raise InputError(f"{map_name}: key 'joints.{entry.pattern}': matches no joint of the stage")
        if entry.source not in cache:
            where = f"{map_name}: key 'joints.{entry.pattern}'"
            cache[entry.source] = resolve_envelope(entry.source, where=where)
        for path in matched:
            assignments.setdefault(path, (path, cache[entry.source], entry.instance))
    return list(assignments.values())

"""Robot maps shipped with the package: joint-name patterns of popular robots -> catalog actuators.

Each ``drive_envelope/maps/<robot>.toml`` is a map file in the format ``usd apply --map`` and
``mujoco apply --map`` read (one ``[joints]`` table of glob -> catalog name; see
:mod:`~drive_envelope._src.adapters.usd.joint_map`), written for the joint names of the robot's
published model and commented with where those names and the limits come from.
"""

from __future__ import annotations

import difflib
import importlib.resources
import re
from dataclasses import dataclass
from pathlib import Path

from drive_envelope._src.errors import InputError


@dataclass(frozen=True, kw_only=True, slots=True)
class RobotMap:
    """One shipped robot map."""

    key: str
    """Name of the map (the file name without ``.toml``), e.g. ``"unitree-go2"``."""
    title: str
    """The file's first comment line: the robot."""
    path: Path
    """Where the file is installed."""


def _directory() -> Path:
    return Path(str(importlib.resources.files("drive_envelope").joinpath("maps")))


def robot_maps() -> list[RobotMap]:
    """Every shipped robot map, sorted by key."""
    maps = []
    for path in sorted(_directory().glob("*.toml")):
        first = path.read_text(encoding="utf-8").splitlines()[0] if path.stat().st_size else ""
        title = re.sub(r"^#\s*", "", first).split(":")[0].strip()
        maps.append(RobotMap(key=path.stem, title=title, path=path))
    return maps


def robot_map_path(name: str) -> Path:
    """The installed file of the shipped map ``name`` (``"unitree-go2"`` or ``"unitree-go2.toml"``).

    Raises:
        InputError: no such shipped map (with the nearest name and the list).
    """
    key = name.strip().removesuffix(".toml")
    by_key = {m.key: m.path for m in robot_maps()}
    if key in by_key:
        return by_key[key]
    close = difflib.get_close_matches(key, list(by_key), n=1, cutoff=0.5)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise InputError(f"{name!r}: no such robot map{hint}; shipped maps: {', '.join(sorted(by_key))}")

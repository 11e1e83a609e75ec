"""Test-stand engines: each maps a :class:`Scenario` to a :class:`Trajectory`.

An engine is a module exposing ``simulate(scenario: Scenario) -> Trajectory``. Modules are
imported only when the engine is used, and each imports its simulator inside its functions, so the
registry itself is light. A missing optional package gives one :class:`InputError` line naming the
extra to install.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType
from typing import TYPE_CHECKING

from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    from drive_envelope._src.scenario.spec import Scenario
    from drive_envelope._src.scenario.trajectory import Trajectory

__all__ = ["ENGINES", "ENGINE_EXTRAS", "engine_module", "engine_names", "simulate"]

ENGINES: dict[str, str] = {
    "reference": "drive_envelope._src.teststand.engines.reference",
    "mujoco": "drive_envelope._src.teststand.engines.mujoco",
    "physx": "drive_envelope._src.teststand.engines.physx",
}
"""Engine name -> module path."""

ENGINE_EXTRAS: dict[str, tuple[str, tuple[str, ...]]] = {
    "reference": ("", ()),
    "mujoco": ("mujoco", ("mujoco",)),
    "physx": ("physx", ("ovphysx", "ovstage", "pxr", "physx_usd_schemas")),
}
"""Engine name -> (pip extra, top-level packages it needs)."""


def engine_names() -> tuple[str, ...]:
    """Names of every registered engine, ``reference`` first."""
    return tuple(ENGINES)


def _missing_extra(name: str, package: str) -> InputError:
    extra = ENGINE_EXTRAS.get(name, (name, ()))[0] or name
    return InputError(
        f"--engine {name}: needs the Python package {package!r} "
        f"(install the extra: pip install 'drive-envelope[{extra}]')"
    )


def engine_module(name: str) -> ModuleType:
    """Import and return the module of engine ``name``.

    Raises:
        InputError: unknown engine, an engine whose optional package is missing (naming the extra),
            or an engine not present in this build.
    """
    if name not in ENGINES:
        raise InputError(f"--engine {name!r}: unknown engine; valid engines: {', '.join(ENGINES)}")
    for package in ENGINE_EXTRAS.get(name, ("", ()))[1]:
        if importlib.util.find_spec(package) is None:
            raise _missing_extra(name, package)
    try:
        return importlib.import_module(ENGINES[name])
    except ModuleNotFoundError as exc:
        if exc.name == ENGINES[name]:
            raise InputError(f"--engine {name}: this engine is not available in this build") from None
        raise _missing_extra(name, (exc.name or "?").split(".")[0]) from None


def simulate(scenario: Scenario, engine: str = "reference") -> Trajectory:
    """Run ``scenario`` on ``engine`` and return its trajectory.

    Args:
        scenario: The validated scenario (SI).
        engine: A name from :data:`ENGINES`.

    Raises:
        InputError: unknown or unavailable engine (naming the extra to install), or a scenario the
            engine cannot represent.
    """
    module = engine_module(engine)
    try:
        result: Trajectory = module.simulate(scenario)
    except ModuleNotFoundError as exc:
        # engines import their simulator lazily: a missing package surfaces on the first call
        raise _missing_extra(engine, (exc.name or "?").split(".")[0]) from None
    return result

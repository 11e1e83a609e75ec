"""Test-stand engines: each maps a :class:`Scenario` to a :class:`Trajectory`.

An engine is a module exposing ``simulate(scenario: Scenario) -> Trajectory``; one that also takes
a keyword ``progress`` (a callable ``progress(done, total)`` it calls now and then with the steps
done) gets the command line's progress bar, and one that takes a keyword ``schedule`` (a
:class:`~drive_envelope._src.scenario.schedule.DriveSchedule`) can replay per-step drive
commands. Modules are imported only when the engine is used, and each imports its simulator inside
its functions, so the registry itself is light. A missing optional package gives one
:class:`InputError` line naming the extra to install.

The bench loads (a ``[pendulum]``, ``[friction]``, ``joint.armature``) are refused by an engine
whose module does not list them in ``LOADS`` (a tuple of ``"pendulum"``, ``"friction"``,
``"armature"``), so an engine that has not learnt one never silently drops it.

Every run is bounded: :func:`simulate` refuses a scenario of more than ``max_steps`` steps
(:data:`MAX_STEPS` unless raised) before any engine allocates its arrays (about 32 bytes a step).
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable
from types import ModuleType
from typing import TYPE_CHECKING, overload

from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    from drive_envelope._src.scenario.chain import ChainScenario
    from drive_envelope._src.scenario.chain_trajectory import ChainTrajectory
    from drive_envelope._src.scenario.schedule import DriveSchedule
    from drive_envelope._src.scenario.spec import Scenario
    from drive_envelope._src.scenario.trajectory import Trajectory

MAX_STEPS = 10**8
"""Most time steps one run takes unless ``max_steps`` (``--max-steps``) raises it: 3.2 GB of trajectory."""

LOADS = ("pendulum", "friction", "armature")
"""The bench loads an engine declares in its module's ``LOADS`` when it represents them."""

ProgressCallback = Callable[[int, int], None]
"""``progress(done, total)``: called by an engine with the number of steps done so far."""

ENGINES: dict[str, str] = {
    "reference": "drive_envelope._src.teststand.engines.reference",
    "mujoco": "drive_envelope._src.teststand.engines.mujoco",
    "physx": "drive_envelope._src.teststand.engines.physx",
    "newton": "drive_envelope._src.teststand.engines.newton",
}
"""Engine name -> module path."""

ENGINE_EXTRAS: dict[str, tuple[str, tuple[str, ...]]] = {
    "reference": ("", ()),
    "mujoco": ("mujoco", ("mujoco",)),
    "physx": ("physx", ("ovphysx", "ovstage", "pxr", "physx_usd_schemas")),
    "newton": ("newton", ("newton", "warp")),
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


def check_steps(scenario: Scenario | ChainScenario, max_steps: int = MAX_STEPS) -> int:
    """The number of steps of ``scenario``, refused above ``max_steps``.

    Raises:
        InputError: a dt longer than the duration, more than ``max_steps`` steps, or a
            ``max_steps`` that is not an integer >= 1.
    """
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1:
        raise InputError(f"--max-steps: expected an integer >= 1, got {max_steps!r}")
    sim = scenario.simulation
    steps = sim.steps
    if sim.dt > sim.duration:
        raise InputError(
            f"simulation.dt = {sim.dt:g} s is longer than simulation.duration = {sim.duration:g} s; "
            "expected a duration of at least one dt"
        )
    if steps > max_steps:
        raise InputError(
            f"simulation.duration / simulation.dt = {sim.duration:g} s / {sim.dt:g} s = {steps:.4g} steps; "
            f"expected at most {max_steps} (raise the limit with --max-steps; a run keeps about 32 bytes "
            "per step)"
        )
    return steps


def scenario_loads(scenario: Scenario) -> tuple[str, ...]:
    """The bench loads a scenario uses, among :data:`LOADS`."""
    used = {
        "pendulum": scenario.pendulum is not None,
        "friction": scenario.friction.active or scenario.friction.dynamic_friction != 0.0,
        "armature": scenario.joint.armature != 0.0,
    }
    return tuple(name for name in LOADS if used[name])


def check_loads(scenario: Scenario, engine: str, module: ModuleType) -> None:
    """Refuse a scenario whose bench loads the engine's module does not declare in ``LOADS``.

    Raises:
        InputError: naming the first load the engine does not represent.
    """
    supported = getattr(module, "LOADS", ())
    for name in scenario_loads(scenario):
        if name not in supported:
            table = f"[{name}]" if name != "armature" else "joint.armature"
            raise InputError(
                f"--engine {engine}: this engine does not represent {table} yet; "
                f"run the scenario on {', '.join(e for e in ('reference', 'physx', 'mujoco') if e != engine)}"
            )


@overload
def simulate(
    scenario: Scenario,
    engine: str = ...,
    *,
    max_steps: int = ...,
    progress: ProgressCallback | None = ...,
    schedule: DriveSchedule | None = ...,
) -> Trajectory: ...
@overload
def simulate(
    scenario: ChainScenario,
    engine: str = ...,
    *,
    max_steps: int = ...,
    progress: ProgressCallback | None = ...,
    schedule: DriveSchedule | None = ...,
) -> ChainTrajectory: ...
def simulate(
    scenario: Scenario | ChainScenario,
    engine: str = "reference",
    *,
    max_steps: int = MAX_STEPS,
    progress: ProgressCallback | None = None,
    schedule: DriveSchedule | None = None,
) -> Trajectory | ChainTrajectory:
    """Run ``scenario`` on ``engine`` and return its trajectory.

    A :class:`~drive_envelope._src.scenario.chain.ChainScenario` runs on the engines whose module
    has ``simulate_chain`` (reference, physx, mujoco) and gives a
    :class:`~drive_envelope._src.scenario.chain_trajectory.ChainTrajectory`.

    Args:
        scenario: The validated scenario (SI).
        engine: A name from :data:`ENGINES`.
        max_steps: Most steps allowed (the run is refused before it starts above it).
        progress: Called as ``progress(done, total)`` during the run by engines that support it.
        schedule: Per-step drive targets and power state (one per step), or None for the
            scenario's constant targets.

    Raises:
        InputError: more than ``max_steps`` steps, an unknown or unavailable engine (naming the
            extra to install), a scenario the engine cannot represent, or a schedule for an engine
            that cannot replay one.
    """
    check_steps(scenario, max_steps)
    module = engine_module(engine)
    import inspect  # here, not at the top: the registry is imported for --help

    from drive_envelope._src.scenario.chain import ChainScenario

    chain = isinstance(scenario, ChainScenario)  # a multi-DOF stand: the engine's chain runner
    if not isinstance(scenario, ChainScenario):
        check_loads(scenario, engine, module)
    elif not hasattr(module, "simulate_chain"):
        raise InputError(
            f"--engine {engine}: this engine does not run chain scenarios ([[joints]]) yet; "
            "run it on reference, physx or mujoco"
        )
    run = module.simulate_chain if chain else module.simulate
    parameters = inspect.signature(run).parameters
    options: dict[str, object] = {}
    if progress is not None and "progress" in parameters:
        options["progress"] = progress
    if schedule is not None and not chain:  # a chain's drives keep their scenario targets
        if "schedule" not in parameters:
            raise InputError(f"--engine {engine}: this engine cannot replay a drive schedule")
        options["schedule"] = schedule
    try:
        result: Trajectory | ChainTrajectory = run(scenario, **options)
    except ModuleNotFoundError as exc:
        # engines import their simulator lazily: a missing package surfaces on the first call
        raise _missing_extra(engine, (exc.name or "?").split(".")[0]) from None
    return result

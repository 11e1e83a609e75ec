"""Test-stand scenario files: one actuated joint (one DOF, fixed base) driving a rigid inertia.

A scenario file (TOML, JSON or YAML) has the sections ``[joint]``, ``[drive]``, ``[envelope]``
(optional), ``[load]``, ``[pendulum]`` and ``[friction]`` (optional, see
:mod:`~drive_envelope._src.scenario.loads`) and ``[simulation]``; quantities are bare SI numbers or
strings with units.
``load_scenario`` reads it, applies ``--set section.key=value`` overrides and validates every value;
every mistake raises one :class:`~drive_envelope.errors.InputError` line naming the file (or
``--set``), the key, the value and what was expected.

Envelope precedence: ``[envelope] datasheet = ...`` (a datasheet file, envelope file or catalog
name) gives the base envelope; explicit ``[envelope]`` keys beside it replace its values, and
``[drive] max_effort`` replaces its ``max_effort`` (PhysX's ``maxEffort`` is the drive's maxForce:
one number). Without ``[envelope]`` the drive is clamped to ``+-max_effort`` (PhysX's plain drive).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal, TypeVar

from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.envelope.model import JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.files import read_mapping
from drive_envelope._src.scenario.checks import check_finite as _check_finite
from drive_envelope._src.scenario.checks import check_int as _check_int
from drive_envelope._src.scenario.checks import choice as _choice
from drive_envelope._src.scenario.checks import quantities as _quantities
from drive_envelope._src.scenario.checks import read_text as _read_text
from drive_envelope._src.scenario.checks import require as _require
from drive_envelope._src.scenario.checks import table as _table
from drive_envelope._src.scenario.checks import unit_for as _unit
from drive_envelope._src.scenario.loads import (
    STANDARD_GRAVITY,
    FrictionSpec,
    PendulumSpec,
    read_friction,
    read_pendulum,
)
from drive_envelope._src.scenario.overrides import SECTIONS as _SECTIONS
from drive_envelope._src.scenario.overrides import apply_overrides
from drive_envelope._src.units import to_si
from drive_envelope._src.validation import check_keys as _check_keys

SolverType = Literal["pgs", "tgs"]
T = TypeVar("T")

_TOP_KEYS = ("name", "description", *_SECTIONS)
_ENVELOPE_KEYS = (
    "datasheet",
    "max_actuator_velocity",
    "velocity_dependent_resistance",
    "speed_effort_gradient",
)
# PhysX steps in float32: a (sub)step below its smallest normal number, or above its largest, is
# 0 or inf there, and the float64 reference would divide by a subnormal
_MIN_STEP = 1.1754943508222875e-38
MAX_POSITION = 1e6
"""Largest ``|initial_position|`` [rad or m]: float32's spacing there is 0.0625 (PhysX steps in float32)."""
_FLT_MAX = 3.4028234663852886e38


@dataclass(frozen=True, kw_only=True, slots=True)
class JointSpec:
    """The joint and the rigid inertia it moves (fixed base, one DOF)."""

    type: JointType = "revolute"
    """``"revolute"`` (angles in rad, efforts in N*m) or ``"prismatic"`` (m, N)."""
    inertia: float
    """Moment of inertia about the axis [kg*m^2] (revolute) or mass [kg] (prismatic) of the link,
    a ``[pendulum]`` point mass not included; ``> 0``."""
    armature: float = 0.0
    """Rotor inertia reflected to the joint, added to the joint-space inertia (PhysX
    ``armature``) [kg*m^2 or kg]; ``>= 0``."""
    initial_position: float = 0.0
    """Joint position at t = 0 [rad or m]."""
    initial_velocity: float = 0.0
    """Joint velocity at t = 0 [rad/s or m/s]."""

    def __post_init__(self) -> None:
        if self.type not in ("revolute", "prismatic"):
            raise InputError(f"joint.type must be 'revolute' or 'prismatic', got {self.type!r}")
        _check_finite("joint.inertia", self.inertia, positive=True)
        _check_finite("joint.armature", self.armature, nonnegative=True)
        _check_finite("joint.initial_position", self.initial_position)
        _check_finite("joint.initial_velocity", self.initial_velocity)
        if abs(self.initial_position) > MAX_POSITION:
            raise InputError(
                f"joint.initial_position must be within +-{MAX_POSITION:g} rad or m (float32 engines "
                f"resolve positions beyond it to worse than 0.06), got {self.initial_position!r}"
            )


@dataclass(frozen=True, kw_only=True, slots=True)
class DriveSpec:
    """A PhysX articulation drive (implicit spring-damper) on the joint."""

    type: DriveType = "force"
    """``"force"`` (gains act on the joint effort) or ``"acceleration"`` (gains scaled by inertia)."""
    stiffness: float = 0.0
    """Spring gain [N*m/rad or N/m] (force drive) or [1/s^2] (acceleration drive); ``>= 0``."""
    damping: float = 0.0
    """Damper gain [N*m*s/rad or N*s/m] (force drive) or [1/s] (acceleration drive); ``>= 0``."""
    target_position: float = 0.0
    """Drive target position [rad or m]."""
    target_velocity: float = 0.0
    """Drive target velocity [rad/s or m/s]."""
    max_effort: float = math.inf
    """PhysX ``maxForce``, the envelope's ``maxEffort`` [N*m or N]; ``>= 0``. ``inf`` (omitted)
    or PhysX's ``FLT_MAX`` (read as ``inf``) means unlimited, 0 turns the drive off."""

    def __post_init__(self) -> None:
        if self.type not in ("force", "acceleration"):
            raise InputError(f"drive.type must be 'force' or 'acceleration', got {self.type!r}")
        _check_finite("drive.stiffness", self.stiffness, nonnegative=True)
        _check_finite("drive.damping", self.damping, nonnegative=True)
        _check_finite("drive.target_position", self.target_position)
        _check_finite("drive.target_velocity", self.target_velocity)
        if math.isnan(self.max_effort) or self.max_effort < 0.0:
            raise InputError(f"drive.max_effort must be >= 0, got {self.max_effort!r}")
        if self.max_effort >= _FLT_MAX:  # PhysX's FLT_MAX is its "no limit" (NO_LIMIT_FIELDS)
            object.__setattr__(self, "max_effort", math.inf)


@dataclass(frozen=True, kw_only=True, slots=True)
class LoadSpec:
    """Constant efforts on the joint besides the drive."""

    external_effort: float = 0.0
    """Generalized force from outside the actuator (gravity, a brake, a spring) [N*m or N]; it is
    not actuator effort and the envelope does not limit it."""
    applied_effort: float = 0.0
    """Joint effort commanded beside the drive (PhysX joint force) [N*m or N]; it counts as
    actuator effort: drive + applied stay inside the envelope together."""

    def __post_init__(self) -> None:
        _check_finite("load.external_effort", self.external_effort)
        _check_finite("load.applied_effort", self.applied_effort)


@dataclass(frozen=True, kw_only=True, slots=True)
class SimulationSpec:
    """Time stepping and the PhysX articulation solver settings."""

    dt: float = 1.0 / 60.0
    """Time step [s]; ``> 0``, and ``dt / position_iterations`` within float32's normal range
    (1.2e-38 .. 3.4e38 s), as PhysX computes in float32."""
    duration: float = 1.0
    """Simulated time [s]; ``>= 0``. The number of steps is ``round(duration / dt)``, a finite
    number (the engines refuse more than their step limit, 10^8 by default)."""
    solver: SolverType = "tgs"
    """``"tgs"`` (PhysX's default through USD) or ``"pgs"``."""
    position_iterations: int = 4
    """Solver position iterations (TGS: substeps), 1..255."""
    velocity_iterations: int = 1
    """Solver velocity iterations, 0..255."""
    gravity: float = STANDARD_GRAVITY
    """Gravitational acceleration on a ``[pendulum]`` [m/s^2]; ``>= 0``. The stand has no
    gravity otherwise (the link's centre of mass is on the joint axis)."""

    def metadata(self) -> dict[str, object]:
        """The solver settings under the metadata keys every engine's trajectory carries."""
        return {
            "solver": self.solver,
            "dt": self.dt,
            "position_iterations": self.position_iterations,
            "velocity_iterations": self.velocity_iterations,
        }

    def __post_init__(self) -> None:
        _check_finite("simulation.dt", self.dt, positive=True)
        _check_finite("simulation.gravity", self.gravity, nonnegative=True)
        _check_finite("simulation.duration", self.duration, nonnegative=True)
        if self.solver not in ("pgs", "tgs"):
            raise InputError(f"simulation.solver must be 'pgs' or 'tgs', got {self.solver!r}")
        _check_int("simulation.position_iterations", self.position_iterations, 1)
        _check_int("simulation.velocity_iterations", self.velocity_iterations, 0)
        substep = self.dt / self.position_iterations
        if not _MIN_STEP <= substep <= _FLT_MAX:
            raise InputError(
                f"simulation.dt must give a (sub)step within float32's range {_MIN_STEP:.2g} .. "
                f"{_FLT_MAX:.2g} s (PhysX steps in float32), got dt = {self.dt!r} s with "
                f"{self.position_iterations} position iteration(s)"
            )
        if not math.isfinite(self.duration / self.dt):
            raise InputError(
                f"simulation.duration / simulation.dt must be a finite number of steps, got "
                f"{self.duration!r} s / {self.dt!r} s"
            )

    @property
    def steps(self) -> int:
        """Number of time steps, ``round(duration / dt)``."""
        return round(self.duration / self.dt)


@dataclass(frozen=True, kw_only=True, slots=True)
class Scenario:
    """A whole test-stand scenario: joint, drive, optional envelope, load and solver settings."""

    joint: JointSpec
    """The joint and its inertia."""
    drive: DriveSpec = field(default_factory=DriveSpec)
    """The PhysX drive."""
    envelope: PerformanceEnvelope | None = None
    """The performance envelope; None gives PhysX's plain drive (``+-drive.max_effort`` on
    drive + applied effort). Its ``max_effort`` must equal ``drive.max_effort``."""
    load: LoadSpec = field(default_factory=LoadSpec)
    """Constant external and applied efforts."""
    pendulum: PendulumSpec | None = None
    """A point mass pulled by gravity (revolute joints), or None."""
    friction: FrictionSpec = field(default_factory=FrictionSpec)
    """PhysX joint friction (static, dynamic, viscous); none by default."""
    simulation: SimulationSpec = field(default_factory=SimulationSpec)
    """Time step, duration and solver."""
    name: str = ""
    """Label for outputs (defaults to the file's stem)."""
    description: str = ""
    """Free text from the file."""

    def __post_init__(self) -> None:
        if self.pendulum is not None and self.joint.type != "revolute":
            raise InputError(f"[pendulum] needs a revolute joint, got joint.type {self.joint.type!r}")
        if self.envelope is None:
            return
        if self.envelope.joint != self.joint.type:
            raise InputError(
                f"envelope is for a {self.envelope.joint} joint but joint.type is {self.joint.type!r}"
            )
        if self.envelope.max_effort != self.drive.max_effort:
            raise InputError(
                f"envelope.max_effort ({self.envelope.max_effort!r}) must equal drive.max_effort "
                f"({self.drive.max_effort!r}): PhysX uses the drive's maxForce as maxEffort"
            )

    @property
    def effective_inertia(self) -> float:
        """Joint-space inertia PhysX solves with: link + armature + pendulum m*d^2 [kg*m^2 or kg]."""
        pendulum = self.pendulum.inertia if self.pendulum is not None else 0.0
        return self.joint.inertia + self.joint.armature + pendulum

    def effective_envelope(self) -> PerformanceEnvelope | None:
        """The envelope PhysX applies to drive + applied effort.

        Returns:
            The given envelope; for a plain drive with a finite ``max_effort`` the envelope
            ``(max_effort, inf, 0, 0)``; None when the drive is unlimited.
        """
        return effective_envelope(self.envelope, self.drive, self.joint.type)


def effective_envelope(
    envelope: PerformanceEnvelope | None, drive: DriveSpec, joint: JointType
) -> PerformanceEnvelope | None:
    """``envelope``, else PhysX's plain drive ``(max_effort, inf, 0, 0)``; None when it is unlimited too."""
    if envelope is not None:
        return envelope
    if math.isinf(drive.max_effort):
        return None
    return PerformanceEnvelope(max_effort=drive.max_effort, joint=joint)


# -- reading ----------------------------------------------------------------------------------------


def load_scenario(path: str | os.PathLike[str], overrides: Sequence[str] = ()) -> Scenario:
    """Read a scenario file (TOML, JSON or YAML) and apply ``--set section.key=value`` overrides.

    Args:
        path: The scenario file.
        overrides: ``section.key=value`` strings, applied in order after reading the file.

    Returns:
        The validated :class:`Scenario` (SI floats, joint side).

    Raises:
        InputError: one line naming the file, the key, the value and what was expected.
    """
    return from_file(path, overrides, scenario_from_mapping)


def from_file(path: str | os.PathLike[str], overrides: Sequence[str], build: Callable[..., T]) -> T:
    """``build`` of a scenario file's mapping after the ``--set`` overrides.

    ``build`` gets the file as ``source``, its folder as ``base_dir`` and its stem as ``default_name``.
    """
    file = Path(path)
    data = apply_overrides(read_mapping(file), overrides)
    return build(data, source=str(file), base_dir=file.parent, default_name=file.stem)


def scenario_from_mapping(
    data: Mapping[str, Any],
    *,
    source: str = "scenario",
    base_dir: str | os.PathLike[str] | None = None,
    default_name: str = "",
    other_tables: tuple[str, ...] = (),
) -> Scenario:
    """Build a :class:`Scenario` from a raw mapping (the parsed file).

    Args:
        data: Sections ``joint`` (required), ``drive``, ``envelope``, ``load``, ``pendulum``,
            ``friction``, ``simulation``.
        source: File name used in error messages.
        base_dir: Directory against which a relative ``envelope.datasheet`` path is resolved.
        default_name: Scenario name when the mapping has no ``name``.
        other_tables: Top-level tables the caller reads itself (identify's ``servo`` and
            ``bounds``): valid here, and listed when an unknown key is refused, but not read.

    Raises:
        InputError: one line naming ``source``, the key, the value and what was expected.
    """
    if "joint" not in data or isinstance(data["joint"], str):
        if any(key in data for key in ("max_effort", "max_actuator_velocity")):  # an envelope file
            raise InputError(
                f"{source}: an envelope file (max_effort at the top level), not a scenario or stand file "
                "([joint], [drive], ... tables): a scenario names it in [envelope] datasheet = FILE, and "
                "identify -o writes a stand"
            )
    _check_keys(data, (*_TOP_KEYS, *other_tables), source, "")
    if "joint" not in data:
        raise InputError(f"{source}: missing required table [joint] (type, inertia)")
    sections = {name: _table(data, name, source) for name in _SECTIONS}
    try:
        joint = _read_joint(sections["joint"], source)
        drive = _read_drive(sections["drive"], joint.type, source)
        envelope, drive = _read_envelope(sections["envelope"], drive, joint.type, source, base_dir)
        load = _read_load(sections["load"], joint.type, source)
        pendulum = read_pendulum(sections["pendulum"], joint.type, source)
        friction = read_friction(sections["friction"], joint.type, source)
        simulation = _read_simulation(sections["simulation"], source)
        name = _read_text(data, "name", source) or default_name
        description = _read_text(data, "description", source)
        return Scenario(
            joint=joint,
            drive=drive,
            envelope=envelope,
            load=load,
            pendulum=pendulum,
            friction=friction,
            simulation=simulation,
            name=name,
            description=description,
        )
    except InputError as exc:
        message = str(exc)
        raise InputError(message if message.startswith(f"{source}:") else f"{source}: {message}") from None


def _read_joint(table: Mapping[str, Any], source: str) -> JointSpec:
    keys = ("type", "inertia", "armature", "initial_position", "initial_velocity")
    _check_keys(table, keys, source, "joint")
    joint = _choice(table, "joint", "type", ("revolute", "prismatic"), source)
    _require(table, "joint", {"inertia": f"{_unit(joint, 'kg*m^2', 'kg')}, > 0"}, source)
    units = {
        "inertia": _unit(joint, "kg*m**2", "kg"),
        "armature": _unit(joint, "kg*m**2", "kg"),
        "initial_position": _unit(joint, "rad", "m"),
        "initial_velocity": _unit(joint, "rad/s", "m/s"),
    }
    return JointSpec(type=joint, **_quantities(table, "joint", units, source))  # type: ignore[arg-type]


def _read_drive(table: Mapping[str, Any], joint: str, source: str) -> DriveSpec:
    keys = ("type", "stiffness", "damping", "target_position", "target_velocity", "max_effort")
    _check_keys(table, keys, source, "drive")
    drive_type = _choice(table, "drive", "type", ("force", "acceleration"), source)
    if drive_type == "force":
        gains = {"stiffness": _unit(joint, "N*m/rad", "N/m"), "damping": _unit(joint, "N*m*s/rad", "N*s/m")}
    else:
        gains = {"stiffness": "1/s**2", "damping": "1/s"}
    units = {
        **gains,
        "target_position": _unit(joint, "rad", "m"),
        "target_velocity": _unit(joint, "rad/s", "m/s"),
        "max_effort": _unit(joint, "N*m", "N"),
    }
    return DriveSpec(type=drive_type, **_quantities(table, "drive", units, source))  # type: ignore[arg-type]


def _read_envelope(
    table: Mapping[str, Any],
    drive: DriveSpec,
    joint: str,
    source: str,
    base_dir: str | os.PathLike[str] | None,
) -> tuple[PerformanceEnvelope | None, DriveSpec]:
    """The envelope (or None) and the drive with ``max_effort`` made consistent with it."""
    if not table:
        return None, drive
    _check_keys(table, _ENVELOPE_KEYS, source, "envelope")
    units = {
        "max_actuator_velocity": _unit(joint, "rad/s", "m/s"),
        "velocity_dependent_resistance": _unit(joint, "N*m*s/rad", "N*s/m"),
        "speed_effort_gradient": _unit(joint, "(rad/s)/(N*m)", "(m/s)/N"),
    }
    values: dict[str, Any] = _quantities(table, "envelope", units, source)
    for key, value in values.items():  # checked here so the message names the key in the file
        if value < 0.0 or (math.isinf(value) and key != "max_actuator_velocity"):
            bound = (
                "a number >= 0 (inf allowed)" if key == "max_actuator_velocity" else "a finite number >= 0"
            )
            raise InputError(f"{source}: key 'envelope.{key}': expected {bound}, got {table[key]!r}")
    if "datasheet" in table:
        base = _resolve_datasheet(table["datasheet"], source, base_dir)
        if base.joint != joint:
            raise InputError(
                f"{source}: key 'envelope.datasheet': {table['datasheet']!r} describes a {base.joint} "
                f"actuator but joint.type is {joint!r}"
            )
        merged = {**base.to_dict(), **values}
        if math.isfinite(drive.max_effort):
            merged["max_effort"] = drive.max_effort  # [drive] max_effort replaces the datasheet's
        envelope = PerformanceEnvelope(**merged)
    else:  # an unlimited maxForce leaves only the speed line (eq. 2), as in PhysX
        envelope = PerformanceEnvelope(max_effort=drive.max_effort, joint=joint, **values)  # type: ignore[arg-type]
    if envelope.max_effort != drive.max_effort:
        drive = replace(drive, max_effort=envelope.max_effort)
    return envelope, drive


def _resolve_datasheet(
    spec: object, source: str, base_dir: str | os.PathLike[str] | None
) -> PerformanceEnvelope:
    """Envelope of ``envelope.datasheet``: a file (relative to the scenario) or a catalog name."""
    from drive_envelope._src.datasheet.resolve import resolve_envelope

    if not isinstance(spec, str) or not spec.strip():
        raise InputError(
            f"{source}: key 'envelope.datasheet': expected a file name or catalog name, got {spec!r}"
        )
    return resolve_envelope(spec, base=base_dir, where=f"{source}: key 'envelope.datasheet'")


def _read_load(table: Mapping[str, Any], joint: str, source: str) -> LoadSpec:
    _check_keys(table, ("external_effort", "applied_effort"), source, "load")
    unit = _unit(joint, "N*m", "N")
    return LoadSpec(**_quantities(table, "load", {"external_effort": unit, "applied_effort": unit}, source))


def _read_simulation(table: Mapping[str, Any], source: str) -> SimulationSpec:
    keys = ("dt", "duration", "solver", "position_iterations", "velocity_iterations", "gravity")
    _check_keys(table, keys, source, "simulation")
    solver = _choice(table, "simulation", "solver", ("tgs", "pgs"), source)
    times = {
        key: to_si(table[key], "s", f"{source}: key 'simulation.{key}'")
        for key in ("dt", "duration")
        if key in table
    }
    times.update(_quantities(table, "simulation", {"gravity": "m/s**2"}, source))
    counts = {}
    for key in ("position_iterations", "velocity_iterations"):
        if key in table:
            value = table[key]
            if isinstance(value, float) and value.is_integer():
                value = int(value)
            if isinstance(value, bool) or not isinstance(value, int):
                raise InputError(f"{source}: key 'simulation.{key}': expected an integer, got {value!r}")
            counts[key] = value
    return SimulationSpec(solver=solver, **times, **counts)  # type: ignore[arg-type]

"""Multi-DOF test-stand scenarios: a fixed-base chain (or tree) of driven links under gravity.

A chain scenario describes an articulation as PhysX builds it: a fixed base and links, each
hung on one driven joint, revolute about (or prismatic along) an axis of the link's frame. At
zero joint position a link's frame sits at its joint's ``origin`` in the parent link's frame,
turned by the fixed rotation ``quat`` (URDF's ``origin rpy``, MJCF's body ``quat``; parallel to the
parent's by default); the joint axis (``"x"``, ``"y"``, ``"z"`` or any vector) is in that frame,
as URDF's and MJCF's are. The link's centre of mass is in its frame, its inertia the principal
moments about the centre of mass along axes turned by ``inertia_quat`` (MJCF's inertial ``quat``,
PhysX's ``principalAxes``; a file may give the full tensor instead). Gravity acts along the
world's -Z (``[simulation] gravity``; a chain has gravity by default, unlike the one-joint stand).
Each joint has its drive, envelope, friction, armature, applied effort and target, read with the
one-joint tables' rules.

A one-joint scenario (:class:`~drive_envelope._src.scenario.spec.Scenario`) is a chain of one:
:func:`chain_from_scenario` turns it into the equivalent chain (the link's inertia about the joint
axis, a pendulum's point mass, gravity in the joint's plane).
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from drive_envelope._src.envelope.model import JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain_frames import (
    IDENTITY,
    Quaternion,
    principal_inertia,
    quat_from_rpy,
    quat_normalize,
    unit_vector,
)
from drive_envelope._src.scenario.checks import check_finite
from drive_envelope._src.scenario.loads import STANDARD_GRAVITY, FrictionSpec
from drive_envelope._src.scenario.spec import (
    DriveSpec,
    LoadSpec,
    Scenario,
    SimulationSpec,
    effective_envelope,
    from_file,
    scenario_from_mapping,
)

Vector3 = tuple[float, float, float]
AXES = ("x", "y", "z")
"""Named joint axes: the X, Y or Z axis of the link's frame."""


def _vector(name: str, value: object, *, nonnegative: bool = False) -> Vector3:
    if not isinstance(value, (tuple, list)) or len(value) != 3:
        raise InputError(f"{name} must be three numbers [x, y, z], got {value!r}")
    for i, item in enumerate(value):
        check_finite(f"{name}[{i}]", item, nonnegative=nonnegative)  # type: ignore[arg-type]
    return (float(value[0]), float(value[1]), float(value[2]))  # type: ignore[arg-type]


@dataclass(frozen=True, kw_only=True, slots=True)
class ChainJoint:
    """One driven joint of a chain and the link it carries."""

    name: str
    """Joint name (unique in the chain), used for columns, prims and MJCF names."""
    type: JointType = "revolute"
    """``"revolute"`` (rad, N*m) or ``"prismatic"`` (m, N)."""
    axis: str | Vector3 = "z"
    """The joint axis in the link's frame: ``"x"``, ``"y"``, ``"z"`` or a vector (made unit length)."""
    parent: int = -1
    """Index of the parent joint's link in the chain, ``-1`` for the fixed base; parents come first."""
    origin: Vector3 = (0.0, 0.0, 0.0)
    """Joint position in the parent link's frame (the base's frame is the world's) [m]."""
    quat: Quaternion = IDENTITY
    """Fixed rotation of the link's frame in its parent's at zero joint position, ``(w, x, y, z)``
    (made unit length, ``w >= 0``)."""
    mass: float
    """Link mass [kg]; ``> 0``."""
    com: Vector3 = (0.0, 0.0, 0.0)
    """Link centre of mass in the link's frame (whose origin is the joint) [m]."""
    inertia: Vector3
    """Principal moments of inertia about the centre of mass [kg*m^2]; each ``> 0``."""
    inertia_quat: Quaternion = IDENTITY
    """Rotation of the principal axes in the link's frame, ``(w, x, y, z)`` (PhysX
    ``principalAxes``, MJCF's inertial ``quat``); identity: along the link frame's axes."""
    armature: float = 0.0
    """Rotor inertia reflected to the joint (PhysX ``armature``) [kg*m^2 or kg]; ``>= 0``."""
    initial_position: float = 0.0
    """Joint position at t = 0 [rad or m]."""
    initial_velocity: float = 0.0
    """Joint velocity at t = 0 [rad/s or m/s]."""
    drive: DriveSpec = field(default_factory=DriveSpec)
    """The joint's PhysX drive."""
    envelope: PerformanceEnvelope | None = None
    """The performance envelope; None gives PhysX's plain drive (``+-drive.max_effort``)."""
    load: LoadSpec = field(default_factory=LoadSpec)
    """Applied joint effort (actuator) and external effort on the joint (not actuator)."""
    friction: FrictionSpec = field(default_factory=FrictionSpec)
    """PhysX joint friction; none by default."""

    def __post_init__(self) -> None:
        where = f"joint {self.name!r}"
        if not isinstance(self.name, str) or not self.name.strip():
            raise InputError(f"a chain joint needs a non-empty name, got {self.name!r}")
        if self.type not in ("revolute", "prismatic"):
            raise InputError(f"{where}: type must be 'revolute' or 'prismatic', got {self.type!r}")
        if isinstance(self.axis, str):
            if self.axis not in AXES:
                raise InputError(f"{where}: axis must be 'x', 'y', 'z' or [x, y, z], got {self.axis!r}")
        else:
            object.__setattr__(self, "axis", unit_vector(self.axis, f"{where}: axis"))
        object.__setattr__(self, "quat", quat_normalize(self.quat, f"{where}: quat"))
        object.__setattr__(self, "inertia_quat", quat_normalize(self.inertia_quat, f"{where}: inertia_quat"))
        if isinstance(self.parent, bool) or not isinstance(self.parent, int) or self.parent < -1:
            raise InputError(f"{where}: parent must be -1 (the base) or a joint index, got {self.parent!r}")
        object.__setattr__(self, "origin", _vector(f"{where}: origin", self.origin))
        object.__setattr__(self, "com", _vector(f"{where}: com", self.com))
        object.__setattr__(self, "inertia", _vector(f"{where}: inertia", self.inertia, nonnegative=True))
        check_finite(f"{where}: mass", self.mass, positive=True)
        if min(self.inertia) <= 0.0:
            raise InputError(f"{where}: inertia must be three numbers > 0 [kg*m^2], got {list(self.inertia)}")
        check_finite(f"{where}: armature", self.armature, nonnegative=True)
        check_finite(f"{where}: initial_position", self.initial_position)
        check_finite(f"{where}: initial_velocity", self.initial_velocity)
        if self.envelope is not None:
            if self.envelope.joint != self.type:
                raise InputError(
                    f"{where}: the envelope is for a {self.envelope.joint} joint, not {self.type}"
                )
            if self.envelope.max_effort != self.drive.max_effort:
                raise InputError(
                    f"{where}: envelope.max_effort ({self.envelope.max_effort!r}) must equal "
                    f"drive.max_effort ({self.drive.max_effort!r}): PhysX uses the drive's maxForce"
                )

    @property
    def axis_index(self) -> int | None:
        """0, 1 or 2 for a named axis (``"x"``, ``"y"``, ``"z"``), None for a vector."""
        return AXES.index(self.axis) if isinstance(self.axis, str) else None

    @property
    def axis_vector(self) -> Vector3:
        """The unit joint axis in the link's frame."""
        if isinstance(self.axis, str):
            unit = [0.0, 0.0, 0.0]
            unit[AXES.index(self.axis)] = 1.0
            return (unit[0], unit[1], unit[2])
        return self.axis

    def effective_envelope(self) -> PerformanceEnvelope | None:
        """The envelope PhysX applies to drive + applied effort (see ``Scenario.effective_envelope``)."""
        return effective_envelope(self.envelope, self.drive, self.type)


@dataclass(frozen=True, kw_only=True, slots=True)
class ChainScenario:
    """A multi-DOF test stand: a fixed-base articulation of driven joints, gravity and the solver."""

    joints: tuple[ChainJoint, ...]
    """The joints in PhysX's link order: every parent before its children."""
    simulation: SimulationSpec = field(default_factory=SimulationSpec)
    """Time step, duration, PhysX solver and gravity (along world -Z) [m/s^2]."""
    name: str = ""
    """Label for outputs (defaults to the file's stem)."""
    description: str = ""
    """Free text from the file."""

    def __post_init__(self) -> None:
        joints = tuple(self.joints)
        object.__setattr__(self, "joints", joints)
        if not joints:
            raise InputError("a chain scenario needs at least one joint in [[joints]]")
        names = set()
        for index, joint in enumerate(joints):
            if not isinstance(joint, ChainJoint):
                raise InputError(f"joints[{index}] must be a ChainJoint, got {type(joint).__name__}")
            if joint.name in names:
                raise InputError(f"joints[{index}]: the name {joint.name!r} is used twice")
            names.add(joint.name)
            if joint.parent >= index:
                raise InputError(
                    f"joint {joint.name!r}: parent {joint.parent} must be an earlier joint (or -1, the "
                    f"base); joints are listed parents first"
                )

    @property
    def dofs(self) -> int:
        """Number of joints (one DOF each)."""
        return len(self.joints)

    @property
    def names(self) -> tuple[str, ...]:
        """The joint names, in order."""
        return tuple(joint.name for joint in self.joints)

    @property
    def is_chain(self) -> bool:
        """Whether every joint hangs on the previous one (a serial chain, not a branching tree)."""
        return all(joint.parent == index - 1 for index, joint in enumerate(self.joints))


def chain_from_scenario(scenario: Scenario) -> ChainScenario:
    """The one-joint scenario as a chain of one.

    The joint turns about (or slides along) Z; the link carries the scenario's inertia about its
    centre of mass, which is on the axis without a ``[pendulum]`` (and the chain has no gravity, as
    on the one-joint stand). With a pendulum the joint turns about Y and the link's centre of mass
    is the point mass, ``distance`` from the axis, hanging straight down (-Z, along gravity) at
    ``position = -angle_offset``: gravity's effort is then ``-m*g*d*sin(position + angle_offset)``.
    """
    joint = scenario.joint
    pendulum = scenario.pendulum
    revolute = joint.type == "revolute"
    if pendulum is None:
        mass = 1.0 if revolute else joint.inertia
        com: Vector3 = (0.0, 0.0, 0.0)
        gravity = 0.0
    else:
        mass, gravity = pendulum.mass, scenario.simulation.gravity
        # chains pull along world -Z: the joint turns about Y, the mass hangs along -Z at 0
        offset, distance = pendulum.angle_offset, pendulum.distance
        com = (-distance * math.sin(offset), 0.0, -distance * math.cos(offset))
    inertia_about_axis = joint.inertia if revolute else 1.0
    axis = "y" if pendulum is not None else "z"
    single = ChainJoint(
        name=scenario.name or "joint",
        type=joint.type,
        axis=axis,
        mass=mass,
        com=com,
        inertia=(inertia_about_axis,) * 3,
        armature=joint.armature,
        initial_position=joint.initial_position,
        initial_velocity=joint.initial_velocity,
        drive=scenario.drive,
        envelope=scenario.envelope,
        load=scenario.load,
        friction=scenario.friction,
    )
    simulation = dataclasses.replace(scenario.simulation, gravity=gravity)
    return ChainScenario(
        joints=(single,), simulation=simulation, name=scenario.name, description=scenario.description
    )


# -- reading ----------------------------------------------------------------------------------------

_TOP_KEYS = ("name", "description", "simulation", "joints")
_JOINT_KEYS = (
    "name", "type", "axis", "parent", "origin", "quat", "rpy", "mass", "com", "inertia", "inertia_quat",
    "armature",
    "initial_position", "initial_velocity", "drive", "envelope", "load", "friction",
)  # fmt: skip


def is_chain_mapping(data: Mapping[str, Any]) -> bool:
    """Whether a parsed scenario file describes a chain (it has ``[[joints]]``)."""
    return "joints" in data


def load_chain_scenario(path: str | os.PathLike[str], overrides: Sequence[str] = ()) -> ChainScenario:
    """Read a chain scenario file (TOML, JSON or YAML); ``--set simulation.key=value`` overrides apply.

    Raises:
        InputError: one line naming the file, the key, the value and what was expected.
    """
    return from_file(path, overrides, chain_from_mapping)


def chain_from_mapping(
    data: Mapping[str, Any],
    *,
    source: str = "scenario",
    base_dir: str | os.PathLike[str] | None = None,
    default_name: str = "",
) -> ChainScenario:
    """Build a :class:`ChainScenario` from a parsed file: ``[simulation]`` and ``[[joints]]``.

    Each ``[[joints]]`` entry has ``name``, ``type``, ``axis`` (``"x"``, ``"y"``, ``"z"`` or
    ``[x, y, z]``), ``parent`` (``"base"`` or an earlier joint's name; the previous joint when
    omitted, so a list is a serial chain; several joints may share a parent: a tree), ``origin``,
    the frame's fixed rotation as ``quat = [w, x, y, z]`` or URDF's ``rpy = [roll, pitch, yaw]``
    [rad], ``mass``, ``com``, ``inertia`` (three principal moments, turned by ``inertia_quat =
    [w, x, y, z]``, or the six numbers ``[ixx, iyy, izz, ixy, ixz, iyz]`` of the full tensor in the
    link frame, MuJoCo's ``fullinertia`` order), ``armature``, ``initial_position``,
    ``initial_velocity`` and the tables ``drive``, ``envelope``, ``load``, ``friction`` with the
    one-joint file's keys.

    Raises:
        InputError: one line naming ``source``, the key, the value and what was expected.
    """
    from drive_envelope._src.scenario import spec as one
    from drive_envelope._src.scenario.checks import read_text, table
    from drive_envelope._src.validation import check_keys

    check_keys(data, _TOP_KEYS, source, "")
    entries = data.get("joints")
    if not isinstance(entries, list) or not entries or not all(isinstance(e, Mapping) for e in entries):
        raise InputError(f"{source}: key 'joints': expected a list of [[joints]] tables, got {entries!r}")
    try:
        simulation = one._read_simulation(table(data, "simulation", source), source)
        if "gravity" not in table(data, "simulation", source):
            simulation = dataclasses.replace(simulation, gravity=STANDARD_GRAVITY)
        joints: list[ChainJoint] = []
        for index, entry in enumerate(entries):
            joints.append(_read_chain_joint(entry, index, joints, source, base_dir, one))
        return ChainScenario(
            joints=tuple(joints),
            simulation=simulation,
            name=read_text(data, "name", source) or default_name,
            description=read_text(data, "description", source),
        )
    except InputError as exc:
        message = str(exc)
        raise InputError(message if message.startswith(f"{source}:") else f"{source}: {message}") from None


def _read_chain_joint(
    entry: Mapping[str, Any],
    index: int,
    earlier: list[ChainJoint],
    source: str,
    base_dir: str | os.PathLike[str] | None,
    one: Any,
) -> ChainJoint:
    from drive_envelope._src.scenario.checks import choice, quantities, read_text, require, table, unit_for
    from drive_envelope._src.scenario.loads import read_friction
    from drive_envelope._src.validation import check_keys

    where = f"joints[{index}]"
    check_keys(entry, _JOINT_KEYS, source, where)
    name = read_text(entry, "name", source) or f"joint{index}"
    kind = choice(entry, where, "type", ("revolute", "prismatic"), source)
    axis: str | Vector3 = "z"
    if isinstance(entry.get("axis"), (list, tuple)):
        axis = unit_vector(entry["axis"], f"{source}: key '{where}.axis'")
    else:
        axis = choice(entry, where, "axis", ("z", "x", "y"), source)
    parent_name = entry.get("parent", earlier[-1].name if earlier else "base")
    names = [joint.name for joint in earlier]
    if parent_name == "base":
        parent = -1
    elif parent_name in names:
        parent = names.index(parent_name)
    else:
        raise InputError(
            f"{source}: key '{where}.parent': expected 'base' or an earlier joint "
            f"({', '.join(names) or 'none yet'}), got {parent_name!r}"
        )
    require(entry, where, {"mass": "kg", "inertia": "kg*m^2, 3 principal or 6 full-tensor numbers"}, source)
    vectors: dict[str, Any] = {key: _read_vector(entry, key, where, source, unit) for key, unit in
                               (("origin", "m"), ("com", "m")) if key in entry}  # fmt: skip
    vectors.update(_read_frames(entry, where, source))
    units = {
        "mass": "kg",
        "armature": unit_for(kind, "kg*m**2", "kg"),
        "initial_position": unit_for(kind, "rad", "m"),
        "initial_velocity": unit_for(kind, "rad/s", "m/s"),
    }
    scalars = quantities(entry, where, units, source)
    prefix = f"{where}."
    drive = _with_prefix(lambda: one._read_drive(table(entry, "drive", source), kind, source), prefix)
    envelope, drive = _with_prefix(
        lambda: one._read_envelope(table(entry, "envelope", source), drive, kind, source, base_dir), prefix
    )
    load = _with_prefix(lambda: one._read_load(table(entry, "load", source), kind, source), prefix)
    friction = _with_prefix(lambda: read_friction(table(entry, "friction", source), kind, source), prefix)
    return ChainJoint(
        name=name, type=kind, axis=axis, parent=parent, drive=drive, envelope=envelope, load=load,  # type: ignore[arg-type]
        friction=friction, **vectors, **scalars,  # type: ignore[arg-type]
    )  # fmt: skip


def _with_prefix(read: Any, prefix: str) -> Any:
    """Run a one-joint table reader, naming the key inside this ``[[joints]]`` entry."""
    try:
        return read()
    except InputError as exc:
        message = str(exc)
        for section in ("drive", "envelope", "load", "friction", "joint"):
            message = message.replace(f"'{section}.", f"'{prefix}{section}.")
        raise InputError(message) from None


def _read_vector(entry: Mapping[str, Any], key: str, where: str, source: str, unit: str) -> Vector3:
    from drive_envelope._src.values import read_quantity

    value = entry[key]
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise InputError(
            f"{source}: key '{where}.{key}': expected three numbers [x, y, z] ({unit}), got {value!r}"
        )
    return tuple(read_quantity(item, unit, f"{source}: key '{where}.{key}'") for item in value)  # type: ignore[return-value]


def _read_quat(entry: Mapping[str, Any], key: str, where: str, source: str) -> Quaternion:
    name = f"{source}: key '{where}.{key}'"
    value = entry[key]
    if not isinstance(value, (list, tuple)):
        raise InputError(f"{name}: expected a quaternion [w, x, y, z], got {value!r}")
    return quat_normalize(value, name)


def _read_frames(entry: Mapping[str, Any], where: str, source: str) -> dict[str, Any]:
    """The fixed rotation (``quat`` or ``rpy``) and the inertia (3 principal or 6 full numbers)."""
    from drive_envelope._src.values import read_quantity

    frames: dict[str, Any] = {}
    if "quat" in entry and "rpy" in entry:
        raise InputError(
            f"{source}: key '{where}.rpy': give the frame's rotation once, as quat or as rpy, not both"
        )
    if "quat" in entry:
        frames["quat"] = _read_quat(entry, "quat", where, source)
    elif "rpy" in entry:
        roll, pitch, yaw = _read_vector(entry, "rpy", where, source, "rad")
        frames["quat"] = quat_from_rpy(roll, pitch, yaw)
    value = entry["inertia"]
    name = f"{source}: key '{where}.inertia'"
    if not isinstance(value, (list, tuple)) or len(value) not in (3, 6):
        raise InputError(
            f"{name}: expected three principal moments [ixx, iyy, izz] or the six numbers "
            f"[ixx, iyy, izz, ixy, ixz, iyz] (kg*m^2), got {value!r}"
        )
    numbers = [read_quantity(item, "kg*m**2", name) for item in value]
    if len(numbers) == 3:
        frames["inertia"] = tuple(numbers)
        if "inertia_quat" in entry:
            frames["inertia_quat"] = _read_quat(entry, "inertia_quat", where, source)
        return frames
    if "inertia_quat" in entry:
        raise InputError(
            f"{source}: key '{where}.inertia_quat': a full inertia tensor (6 numbers) has its axes "
            "already; expected inertia_quat only with three principal moments"
        )
    ixx, iyy, izz, ixy, ixz, iyz = numbers
    moments, axes = principal_inertia(((ixx, ixy, ixz), (ixy, iyy, iyz), (ixz, iyz, izz)), name)
    frames["inertia"], frames["inertia_quat"] = moments, axes
    return frames


def load_stand(path: str | os.PathLike[str], overrides: Sequence[str] = ()) -> Scenario | ChainScenario:
    """Read a one-joint or a chain scenario file: a file with ``[[joints]]`` is a chain.

    Raises:
        InputError: one line naming the file, the key, the value and what was expected.
    """
    return from_file(path, overrides, _stand_from_mapping)


def _stand_from_mapping(data: Mapping[str, Any], **where: Any) -> Scenario | ChainScenario:
    return (chain_from_mapping if is_chain_mapping(data) else scenario_from_mapping)(data, **where)

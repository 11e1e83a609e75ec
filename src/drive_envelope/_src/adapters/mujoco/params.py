"""A drive's numbers in the ``MjModel``: where they live, how to read and change them between steps.

Each drive keeps its six numbers in ``model.actuator_dynprm`` of its effort actuator (the first of
its joint's actuators in its plugin instance), in SI, and the plugin reads them at every step::

    dynprm[0]  max_effort                     [N*m or N]                 -1: no limit
    dynprm[1]  max_actuator_velocity          [rad/s or m/s]             -1: no limit
    dynprm[2]  velocity_dependent_resistance  [N*m*s/rad or N*s/m]
    dynprm[3]  speed_effort_gradient          [(rad/s)/(N*m) or (m/s)/N]
    dynprm[4]  stiffness                      [N*m/rad or N/m]; [1/s^2] for an acceleration drive
    dynprm[5]  damping                        [N*m*s/rad or N*s/m]; [1/s] for an acceleration drive
    dynprm[6:10] reserved, 0

Every number is in ``[0, 1e12]`` (:data:`PARAM_BOUND`); ``-1`` (:data:`NO_LIMIT`) stands for an
infinite ``max_effort`` or ``max_actuator_velocity`` because MuJoCo's MJCF writer cannot write
``inf``. So :func:`set_envelope` on a model takes effect at the next ``mj_step`` of every ``MjData``
of that model, and ``mujoco.rollout`` over several models uses each model's own numbers: this is
how to randomize the envelope (``examples/mujoco/domain_randomization.py``).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeAlias

from drive_envelope._src.adapters.mujoco.handle import MjDrive, read_number
from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.envelope.model import JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.format import first_few
from drive_envelope._src.params.table import si_unit

if TYPE_CHECKING:
    import mujoco

DYNPRM_SLOTS = (
    "max_effort",
    "max_actuator_velocity",
    "velocity_dependent_resistance",
    "speed_effort_gradient",
    "stiffness",
    "damping",
)
"""What ``actuator_dynprm[i, k]`` of a drive's effort actuator holds, for k = 0..5."""
PARAM_BOUND = 1e12
"""Largest finite number the plugin accepts in a slot [SI]; larger ones overflow the step."""
NO_LIMIT = -1.0
"""Slot value for an infinite ``max_effort`` or ``max_actuator_velocity`` (no limit)."""
INPUTS = ("pos", "vel", "ff")
NDYN = 10  # mujoco.mjNDYN, fixed by MuJoCo's model layout

# the plugin's declared attributes, in order: how they sit in model.plugin_attr
_ATTRIBUTES = ("drive_type", "input")


@dataclass(frozen=True, kw_only=True, slots=True)
class MjDriveInfo:
    """One drive of a compiled model, as the plugin sees it (:func:`model_drives`)."""

    name: str
    """Name of the effort actuator (or ``#id``)."""
    actuator: int
    """Id of the effort actuator, whose ``actuator_dynprm`` holds the numbers."""
    joint: str
    """The hinge or slide joint it drives."""
    instance: int
    """Plugin instance id."""
    inputs: tuple[str, ...]
    """Control inputs, a subset of ``("pos", "vel", "ff")`` in canonical order."""
    actuators: tuple[int, ...]
    """Actuator ids of the inputs, in the order of :attr:`inputs`."""
    drive_type: DriveType
    """``"force"`` or ``"acceleration"``."""
    envelope: PerformanceEnvelope | None
    """The envelope (SI), or None when ``max_effort`` is unlimited (-1) or a number is invalid."""
    stiffness: float
    """Drive stiffness [N*m/rad or N/m] (force drive) or [1/s^2] (acceleration drive)."""
    damping: float
    """Drive damping [N*m*s/rad or N*s/m] (force drive) or [1/s] (acceleration drive)."""
    dynprm: tuple[float, ...]
    """The six raw slot values (``-1``: no limit)."""


def _checked(value: float, label: str, unit: str, where: str, *, unlimited: bool) -> float:
    """``value`` as a slot number: in ``[0, 1e12]``, or ``inf`` -> ``-1`` where ``unlimited``."""
    number = float(value)
    if unlimited and math.isinf(number) and number > 0:
        return NO_LIMIT
    if not (0.0 <= number <= PARAM_BOUND):
        allowed = " or inf" if unlimited else ""
        raise InputError(f"{where}: {label} = {value!r}: expected a number in [0, 1e12]{allowed} [{unit}]")
    return number


def gain_units(joint: str, drive_type: DriveType) -> tuple[str, str]:
    """SI units of (stiffness, damping) for a ``"revolute"`` or ``"prismatic"`` joint and a drive type."""
    if drive_type == "acceleration":
        return "1/s**2", "1/s"
    if joint == "revolute":
        return "N*m/rad", "N*m*s/rad"
    return "N/m", "N*s/m"


def drive_dynprm(
    envelope: PerformanceEnvelope, *, stiffness: float, damping: float, where: str = "drive"
) -> list[float]:
    """The ten ``dynprm`` values of a drive's effort actuator (layout in this module's docstring).

    Args:
        envelope: The envelope (SI); an infinite ``max_actuator_velocity`` becomes ``-1``.
        stiffness: Drive stiffness, SI [N*m/rad or N/m] (force) or [1/s^2] (acceleration).
        damping: Drive damping, SI [N*m*s/rad or N*s/m] (force) or [1/s] (acceleration).
        where: Prefix of error messages (the call and the argument).

    Raises:
        InputError: a number outside ``[0, 1e12]``, naming it and its unit.
    """
    joint = envelope.joint
    values = [
        _checked(getattr(envelope, name), name, si_unit(name, joint), where, unlimited=index < 2)
        for index, name in enumerate(DYNPRM_SLOTS[:4])
    ]
    k_unit, c_unit = gain_units(joint, "force")
    values.append(_checked(stiffness, "stiffness", k_unit, where, unlimited=False))
    values.append(_checked(damping, "damping", c_unit, where, unlimited=False))
    return values + [0.0] * (NDYN - len(values))


def _instance_config(model: mujoco.MjModel, instance: int) -> tuple[DriveType, tuple[str, ...]]:
    """(drive type, inputs) of a plugin instance, read from ``model.plugin_attr``."""
    start = int(model.plugin_attradr[instance])
    raw = bytes(int(c) & 0xFF for c in model.plugin_attr[start:])
    fields = [f.decode() for f in raw.split(b"\0")[: len(_ATTRIBUTES)]]
    drive_type: DriveType = "acceleration" if fields[0] == "acceleration" else "force"
    words = set(fields[1].replace(",", " ").split()) if fields[1].strip() else {"pos"}
    return drive_type, tuple(name for name in INPUTS if name in words)


def _name(model: mujoco.MjModel, kind: int, index: int) -> str:
    import mujoco

    return mujoco.mj_id2name(model, kind, index) or f"#{index}"


def require_model(model: object, where: str) -> None:
    """One line for an ``MjSpec`` or an ``MjData`` (the arguments swapped) where an ``MjModel`` goes.

    Without it the first model field read fails as ``AttributeError: ... has no attribute
    'nplugin'`` (or ``'plugin_attradr'``, ``'compile'``).
    """
    import mujoco

    if not isinstance(model, mujoco.MjModel):
        hint = " (spec.compile())" if isinstance(model, mujoco.MjSpec) else ""
        raise InputError(
            f"{where}: argument 'model': expected a mujoco.MjModel{hint}, got {type(model).__name__}"
        )


def model_drives(model: mujoco.MjModel) -> tuple[MjDriveInfo, ...]:
    """Every drive of ``drive_envelope.envelope`` in a compiled model, in actuator order.

    The grouping is the plugin's: an instance's actuators are grouped by joint in order of
    appearance; the first of each joint carries the effort and the numbers.
    """
    from drive_envelope._src.adapters.mujoco.loader import plugin_slot

    require_model(model, "model_drives")
    slot = plugin_slot()
    drives = []
    for instance in range(model.nplugin):
        if int(model.plugin[instance]) != slot:
            continue
        drive_type, inputs = _instance_config(model, instance)
        groups: dict[int, list[int]] = {}
        for i in range(model.nu):
            if int(model.actuator_plugin[i]) == instance:
                groups.setdefault(int(model.actuator_trnid[i, 0]), []).append(i)
        for joint, actuators in groups.items():
            drives.append(_info(model, instance, joint, actuators, drive_type, inputs))
    drives.sort(key=lambda info: info.actuator)
    return tuple(drives)


def _info(
    model: mujoco.MjModel,
    instance: int,
    joint: int,
    actuators: Sequence[int],
    drive_type: DriveType,
    inputs: tuple[str, ...],
) -> MjDriveInfo:
    import mujoco

    first = actuators[0]
    raw = tuple(float(v) for v in model.actuator_dynprm[first, :6])
    try:
        envelope: PerformanceEnvelope | None = PerformanceEnvelope(
            max_effort=math.inf if raw[0] == NO_LIMIT else raw[0],
            max_actuator_velocity=math.inf if raw[1] == NO_LIMIT else raw[1],
            velocity_dependent_resistance=raw[2],
            speed_effort_gradient=raw[3],
            joint=_joint_type(model, first),
            name=_name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, first),
        )
    except InputError:
        envelope = None  # unlimited max_effort (-1) or a bad number: the plugin says which
    return MjDriveInfo(
        name=_name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, first),
        actuator=first,
        joint=_name(model, mujoco.mjtObj.mjOBJ_JOINT, joint),
        instance=instance,
        inputs=inputs,
        actuators=tuple(actuators),
        drive_type=drive_type,
        envelope=envelope,
        stiffness=raw[4],
        damping=raw[5],
        dynprm=raw,
    )


DriveRef: TypeAlias = "str | int | MjDrive | MjDriveInfo"
"""What names a drive: an actuator name, an actuator index, a joint name, an MjDrive, an MjDriveInfo."""
_EXPECTED = "an actuator name or index, a joint name, an MjDrive or an MjDriveInfo"


def drive_label(drive: object) -> str:
    """How a drive argument reads in a message: ``'el'``, ``3``, ``MjDrive 'el'``."""
    if isinstance(drive, (MjDrive, MjDriveInfo)):
        return f"{type(drive).__name__} {drive.name!r}"
    return repr(drive) if isinstance(drive, (str, numbers.Integral)) else type(drive).__name__


def find_drive(model: mujoco.MjModel, drive: object, where: str, argument: str = "actuator") -> MjDriveInfo:
    """The drive of ``model`` that ``drive`` names, with its current numbers.

    Lookup: an :class:`MjDriveInfo` by its effort actuator's index, an :class:`MjDrive` by its
    effort actuator's name, an integer as an actuator index and a string first as the name of any
    of a drive's actuators, then as the name of a driven joint (one drive per joint).

    Raises:
        InputError: nothing of that name or index, an actuator or joint without a drive, a handle
            from another model, or an argument of another type; naming ``argument``.
    """
    import mujoco

    require_model(model, where)
    drives = model_drives(model)
    owner = {a: info for info in drives for a in info.actuators}
    prefix = f"{where}: argument {argument!r}"
    if isinstance(drive, (MjDrive, MjDriveInfo)):
        index = (
            drive.actuator
            if isinstance(drive, MjDriveInfo)
            else mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, drive.name)
        )
        found = owner.get(index)
        if found is None or found.name != drive.name or found.joint != drive.joint:
            raise InputError(
                f"{prefix}: {drive_label(drive)} (joint {drive.joint!r}) is not a drive of this model; "
                f"its drives: {_listed([d.name for d in drives])}"
            )
        return found
    if isinstance(drive, numbers.Integral) and not isinstance(drive, bool):
        if not 0 <= int(drive) < model.nu:
            raise InputError(
                f"{prefix}: expected an actuator name, or an id in [0, {model.nu}), got {int(drive)}"
            )
        return _owner(model, owner, int(drive), prefix)
    if not isinstance(drive, str):
        raise InputError(f"{prefix}: expected {_EXPECTED}, got {type(drive).__name__}")
    index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, drive)
    if index >= 0 and index in owner:
        return owner[index]
    by_joint = {info.joint: info for info in drives}
    if drive in by_joint:
        return by_joint[drive]
    if index >= 0:
        return _owner(model, owner, index, prefix)
    if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, drive) >= 0:
        raise InputError(f"{prefix}: joint {drive!r} has no envelope drive; {_drives_hint(drives)}")
    import difflib

    actuators = [name for info in drives for name in _names(model, info.actuators)]
    close = difflib.get_close_matches(drive, list(dict.fromkeys(actuators + list(by_joint))), n=3)
    hint = f" (did you mean {_listed(close)}?)" if close else f"; {_drives_hint(drives)}"
    raise InputError(
        f"{prefix}: the model has no actuator named {drive!r} and no driven joint of that name{hint}"
    )


def _owner(model: mujoco.MjModel, owner: dict[int, MjDriveInfo], index: int, prefix: str) -> MjDriveInfo:
    import mujoco

    if index in owner:
        return owner[index]
    name = _name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, index)
    raise InputError(
        f"{prefix}: actuator {name!r} is not a drive of the drive_envelope.envelope plugin; "
        f"{_drives_hint(list(dict.fromkeys(owner.values())))}"
    )


def _names(model: mujoco.MjModel, actuators: Sequence[int]) -> list[str]:
    import mujoco

    return [_name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in actuators]


def _listed(names: Sequence[str]) -> str:
    return first_few(names, 6) or "none"


def _drives_hint(drives: Sequence[MjDriveInfo]) -> str:
    if not drives:
        return "the model has no envelope drive"
    return "its drives (actuator on joint): " + first_few(drives, 6, lambda d: f"{d.name!r} on {d.joint!r}")


def set_envelope(model: mujoco.MjModel, actuator: DriveRef, envelope: PerformanceEnvelope | str) -> None:
    """Give a drive a new envelope; it takes effect at the next ``mj_step`` of every ``MjData``.

    Args:
        model: The compiled model (its ``actuator_dynprm`` is written).
        actuator: The drive: see :func:`find_drive`.
        envelope: A :class:`PerformanceEnvelope`, or an envelope file, datasheet file or catalog name.

    Raises:
        InputError: no such drive, an envelope for the other joint type, or a number above 1e12.
    """
    from drive_envelope._src.datasheet.resolve import resolve_envelope

    where = f"set_envelope(actuator={drive_label(actuator)})"
    info = find_drive(model, actuator, "set_envelope")
    env = resolve_envelope(envelope, where=f"{where}: argument 'envelope'")
    kind = _joint_type(model, info.actuator)
    if env.joint != kind:
        raise InputError(f"{where}: the envelope is for a {env.joint} joint but {info.joint!r} is {kind}")
    values = drive_dynprm(env, stiffness=info.stiffness, damping=info.damping, where=where)
    model.actuator_dynprm[info.actuator, :4] = values[:4]


def set_gains(
    model: mujoco.MjModel,
    actuator: DriveRef,
    *,
    stiffness: float | str | None = None,
    damping: float | str | None = None,
) -> None:
    """Change a drive's gains; None keeps a gain. Takes effect at the next ``mj_step``.

    Args:
        model: The compiled model.
        actuator: The drive: see :func:`find_drive`.
        stiffness: Drive stiffness, SI number or string with units, as ``add_drive`` takes it
            ([N*m/rad or N/m] (force) or [1/s^2] (acceleration)).
        damping: Drive damping, SI number or string with units ([N*m*s/rad or N*s/m] (force) or
            [1/s] (acceleration)).

    Raises:
        InputError: no such drive, a gain that is not a number or a string of the right unit, or
            one outside ``[0, 1e12]``; a refused call changes neither gain.
    """
    where = f"set_gains(actuator={drive_label(actuator)})"
    info = find_drive(model, actuator, "set_gains")
    units = gain_units(_joint_type(model, info.actuator), info.drive_type)
    slots = {
        slot: _checked(
            read_number(value, unit, f"{where}: argument {label!r}"), label, unit, where, unlimited=False
        )
        for slot, label, value, unit in (
            (4, "stiffness", stiffness, units[0]),
            (5, "damping", damping, units[1]),
        )
        if value is not None
    }
    for slot, number in slots.items():  # both checked first
        model.actuator_dynprm[info.actuator, slot] = number


def get_envelope(model: mujoco.MjModel, actuator: DriveRef) -> PerformanceEnvelope:
    """The envelope a drive has in ``model`` now (SI).

    Raises:
        InputError: no such drive, or its numbers are not an envelope (unlimited or invalid).
    """
    where = f"get_envelope(actuator={drive_label(actuator)})"
    info = find_drive(model, actuator, "get_envelope")
    if info.envelope is None:
        raise InputError(f"{where}: drive {info.name!r} has no valid envelope: dynprm = {list(info.dynprm)}")
    return info.envelope


def get_gains(model: mujoco.MjModel, actuator: DriveRef) -> tuple[float, float]:
    """``(stiffness, damping)`` of a drive in ``model`` now (SI, see :func:`set_gains`)."""
    info = find_drive(model, actuator, "get_gains")
    return info.stiffness, info.damping


def _joint_type(model: mujoco.MjModel, actuator: int) -> JointType:
    """``"prismatic"`` if actuator ``actuator`` of ``model`` drives a slide joint, else ``"revolute"``."""
    import mujoco

    joint = int(model.actuator_trnid[actuator, 0])
    return "prismatic" if int(model.jnt_type[joint]) == int(mujoco.mjtJoint.mjJNT_SLIDE) else "revolute"

"""Write and read PhysxDrivePerformanceEnvelopeAPI on USD joints, with PhysX's unit conventions.

What PhysX 5.6 reads (``omni.physx`` ``usdLoad/Joint.cpp``):

* ``PhysicsDriveAPI:<inst>`` with ``drive:<inst>:physics:maxForce``: the envelope's maxEffort;
* ``PhysxDrivePerformanceEnvelopeAPI:<inst>`` beside it, with
  ``physxDrivePerformanceEnvelope:<inst>:{maxActuatorVelocity, velocityDependentResistance,
  speedEffortGradient}``; unauthored values fall back to the schema defaults (inf, 0, 0);
* instances: ``angular`` on revolute joints, ``linear`` on prismatic joints, ``rotX|rotY|rotZ`` on
  D6 (generic) joints. PhysX never reads an envelope on a D6 ``transX|Y|Z`` axis (and ignores linear
  drives on articulation D6 joints altogether, omni.physx ``UsdInterface.cpp``), and a D6 axis whose
  ``PhysicsLimitAPI`` has ``low > high`` is locked (no DOF, no drive): both are refused;
* angular instances store degrees (deg/s, N*m*s/deg, (deg/s)/(N*m)); every effort is in stage units
  (``metersPerUnit``, ``kilogramsPerUnit``), see :mod:`drive_envelope._src.adapters.usd.scale`;
* only articulation joints keep it, found as PhysX finds them
  (:mod:`~drive_envelope._src.adapters.usd.articulation`); a joint inside an instance is authored on
  its prototype's source (:mod:`~drive_envelope._src.adapters.usd.instancing`).

USD stores these attributes as 32-bit floats: a written value reads back to within float32
rounding (relative 6e-8), not bit for bit; a value beyond float32's range after the stage-unit
scaling would be stored as inf (an unlimited maxForce: no envelope at all) and is refused.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.usd.articulation import articulated_joints
from drive_envelope._src.adapters.usd.instancing import edit_site
from drive_envelope._src.adapters.usd.scale import ANGULAR_INSTANCES, LINEAR_INSTANCES, StageUnits, is_angular
from drive_envelope._src.adapters.usd.stage import stage_units, usd_errors
from drive_envelope._src.envelope.model import JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    from pxr import Usd

ENVELOPE_API = "PhysxDrivePerformanceEnvelopeAPI"
"""Schema name of the multiple-apply envelope API."""
_DRIVE_API = "PhysicsDriveAPI"
_ATTRIBUTES = {
    "max_actuator_velocity": "maxActuatorVelocity",
    "velocity_dependent_resistance": "velocityDependentResistance",
    "speed_effort_gradient": "speedEffortGradient",
}
_D6_INSTANCES = ("rotX", "rotY", "rotZ", "transX", "transY", "transZ")
_D6_TRANSLATIONS = ("transX", "transY", "transZ")
_FLT_MAX = 3.4028234663852886e38
# a drive whose gains saturate maxForce within this error (one degree, one degree per second) was
# most likely written with per-radian gains into USD's per-degree attributes
_SUSPICIOUS_ERROR_DEG = 1.0


class EnvelopeAuthoringWarning(UserWarning):
    """A USD edit that PhysX will accept but that probably does not do what was meant."""


@dataclass(frozen=True, kw_only=True, slots=True)
class DriveRecord:
    """One drive instance of one joint, with its values converted to SI."""

    joint_path: str
    """Prim path of the joint."""
    joint_kind: str
    """``"revolute"``, ``"prismatic"`` or ``"d6"``."""
    instance: str
    """Drive instance: ``angular``, ``linear``, ``rotX`` ... ``transZ``."""
    in_articulation: bool
    """Whether PhysX simulates the joint as an articulation joint (only those honour the envelope)."""
    max_effort: float
    """The drive's maxForce [N*m or N]; ``inf`` when unlimited."""
    stiffness: float
    """Drive stiffness [N*m/rad or N/m] (force drives; acceleration drives: [1/s^2])."""
    damping: float
    """Drive damping [N*m*s/rad or N*s/m] (force drives; acceleration drives: [1/s])."""
    envelope: PerformanceEnvelope | None
    """The envelope PhysX reads, or None when PhysxDrivePerformanceEnvelopeAPI is not applied
    (PhysX then uses ``(maxForce, inf, 0, 0)``); its ``max_effort`` is inf for an unlimited maxForce."""


# -- stage helpers ------------------------------------------------------------------------------------


def resolve_joint(prim_or_stage: Any, joint_path: str | None) -> Usd.Prim:
    """The joint prim named by ``joint_path`` (absolute, or relative to a given prim).

    Args:
        prim_or_stage: A ``Usd.Stage`` or a ``Usd.Prim``; with a prim and no ``joint_path`` the prim
            itself is the joint.
        joint_path: Prim path of the joint, or None.

    Raises:
        InputError: no such prim, or the prim is not a UsdPhysics joint.
    """
    from drive_envelope._src.adapters.usd.stage import register_schemas

    register_schemas()  # idempotent; the schema registry must know PhysxDrivePerformanceEnvelopeAPI
    from pxr import Sdf, Usd, UsdPhysics

    if isinstance(prim_or_stage, Usd.Stage):
        stage, base = prim_or_stage, Sdf.Path.absoluteRootPath
    elif isinstance(prim_or_stage, Usd.Prim) and prim_or_stage.IsValid():
        stage, base = prim_or_stage.GetStage(), prim_or_stage.GetPath()
    else:
        raise InputError(f"expected a Usd.Stage or a valid Usd.Prim, got {type(prim_or_stage).__name__}")
    if joint_path is None:
        if base == Sdf.Path.absoluteRootPath:
            raise InputError("joint_path is required when a stage is given")
        path = base
    else:
        if not Sdf.Path.IsValidPathString(joint_path):
            raise InputError(f"joint path {joint_path!r}: not a valid USD prim path")
        path = Sdf.Path(joint_path).MakeAbsolutePath(base)
    prim = stage.GetPrimAtPath(path)
    if not prim.IsValid():
        raise InputError(
            f"joint path {str(path)!r}: no such prim in {_stage_name(stage)}{_nearest_joints(stage, path)}"
        )
    if not prim.IsA(UsdPhysics.Joint):
        raise InputError(
            f"joint path {str(path)!r}: prim of type {prim.GetTypeName()!r} is not a UsdPhysics joint"
            f"{_nearest_joints(stage, path)}"
        )
    return prim


def _nearest_joints(stage: Usd.Stage, path: Any) -> str:
    """``" (did you mean '/A/B/joint'?)"``: joints whose path or name is closest to ``path``."""
    import difflib

    from pxr import Usd, UsdPhysics

    joints = [
        str(prim.GetPath())
        for prim in Usd.PrimRange.Stage(stage, Usd.TraverseInstanceProxies())
        if prim.IsA(UsdPhysics.Joint)
    ]
    wanted = str(path)
    same_name = [joint for joint in joints if joint.rsplit("/", 1)[-1] == wanted.rsplit("/", 1)[-1]]
    close = same_name[:3] or difflib.get_close_matches(wanted, joints, n=3, cutoff=0.6)
    if not close:
        return f"; it has {len(joints)} joint(s)" + (f", e.g. {joints[0]!r}" if joints else "")
    return " (did you mean " + " or ".join(repr(joint) for joint in close) + "?)"


def _stage_name(stage: Usd.Stage) -> str:
    """The file a user knows the stage by: the root layer, or the asset under an in-memory overlay."""
    root = stage.GetRootLayer()
    if root.anonymous and root.subLayerPaths:
        return str(root.subLayerPaths[0])
    return str(root.realPath or root.identifier) or "the stage"


def joint_kind(prim: Usd.Prim) -> str:
    """``"revolute"``, ``"prismatic"`` or ``"d6"`` (a generic ``PhysicsJoint``).

    Raises:
        InputError: another joint type (fixed, spherical, distance), which has no envelope.
    """
    from pxr import UsdPhysics

    if prim.IsA(UsdPhysics.RevoluteJoint):
        return "revolute"
    if prim.IsA(UsdPhysics.PrismaticJoint):
        return "prismatic"
    if prim.GetTypeName() == "PhysicsJoint":
        return "d6"
    raise InputError(
        f"joint {str(prim.GetPath())!r}: a {prim.GetTypeName()} has no drive envelope "
        "(only revolute, prismatic and D6 joints do)"
    )


def _choose_instance(prim: Usd.Prim, kind: str, instance: str | None) -> str:
    """The drive instance to use: given, or implied by the joint type."""
    where = f"joint {str(prim.GetPath())!r}"
    allowed = {"revolute": ("angular",), "prismatic": ("linear",), "d6": _D6_INSTANCES}[kind]
    if instance is None:
        if kind == "d6":
            from pxr import UsdPhysics

            driven = [axis for axis in ("rotX", "rotY", "rotZ") if prim.HasAPI(UsdPhysics.DriveAPI, axis)]
            hint = f" (it has drives on {', '.join(driven)})" if driven else ""
            raise InputError(f"{where}: a D6 joint needs an instance, one of rotX, rotY, rotZ{hint}")
        return allowed[0]
    if instance not in allowed:
        raise InputError(
            f"{where}: instance {instance!r} is not valid on a {kind} joint; expected {' or '.join(allowed)}"
        )
    return instance


def _check_d6_axis(prim: Usd.Prim, inst: str, where: str) -> None:
    """Refuse the D6 axes PhysX gives no envelope: translations, and axes the joint locks."""
    from pxr import UsdPhysics

    if inst in _D6_TRANSLATIONS:
        raise InputError(
            f"{where}: PhysX reads the envelope only on rotX/rotY/rotZ of a D6 joint, never on {inst} "
            "(and ignores linear drives on articulation D6 joints); a linear actuator needs a prismatic joint"
        )
    if prim.HasAPI(UsdPhysics.LimitAPI, inst):
        limit = UsdPhysics.LimitAPI(prim, inst)
        low, high = limit.GetLowAttr().Get(), limit.GetHighAttr().Get()
        if low is not None and high is not None and float(low) > float(high):
            raise InputError(
                f"{where}: the joint locks {inst} (PhysicsLimitAPI:{inst} low {float(low):g} > high "
                f"{float(high):g}), so PhysX gives it no DOF and no drive; choose a free axis"
            )


# -- writing ------------------------------------------------------------------------------------------


def write_envelope(
    prim_or_stage: Any,
    joint_path: str | None,
    envelope: PerformanceEnvelope | str,
    instance: str | None = None,
) -> str:
    """Author ``envelope`` on a joint's drive the way PhysX reads it.

    Applies ``PhysicsDriveAPI:<inst>`` (if absent) and ``PhysxDrivePerformanceEnvelopeAPI:<inst>``,
    sets ``drive:<inst>:physics:maxForce`` to ``max_effort`` and the three envelope attributes,
    converting radians to degrees on angular instances and SI to the stage's units. Edits go to the
    stage's current edit target; for a joint inside an instance, to its prototype's source. What
    PhysX would accept but probably not do as meant is reported with
    :class:`EnvelopeAuthoringWarning`: a joint that is not an articulation joint (PhysX strips its
    envelope), an existing maxForce that differs from ``max_effort``, stiffness or damping that look
    like per-radian values on an angular drive, and an edit redirected to a prototype's source.

    Args:
        prim_or_stage: A ``Usd.Stage``, or a ``Usd.Prim`` (the joint itself when ``joint_path`` is
            None, else the base of a relative ``joint_path``).
        joint_path: Prim path of the joint, or None.
        envelope: The envelope (joint side, SI), or an envelope file, datasheet file or catalog
            name (as ``drive_envelope.mujoco.set_envelope`` takes it); its ``joint`` type must
            match the instance.
        instance: Drive instance; default from the joint type (revolute -> ``angular``,
            prismatic -> ``linear``); D6 joints need one of ``rotX|rotY|rotZ``.

    Returns:
        The drive instance written.

    Raises:
        InputError: no such joint, an ``envelope`` that names no envelope, a joint type without
            envelope, an instance that does not fit the joint, a D6 translation or locked axis, an
            envelope for the other joint type, a value beyond float32 in the stage's units, or a
            joint inside an instance of another file.
    """
    from drive_envelope._src.datasheet.resolve import resolve_envelope

    prim = resolve_joint(prim_or_stage, joint_path)
    # a dict or None reached envelope.joint as an AttributeError
    env = resolve_envelope(envelope, where="write_envelope: argument 'envelope'")
    return author_envelope(prim, env, instance, articulated=articulated_joints(prim.GetStage()))


def author_envelope(
    prim: Usd.Prim, envelope: PerformanceEnvelope, instance: str | None, *, articulated: Collection[str]
) -> str:
    """:func:`write_envelope` on a resolved joint prim, given the stage's articulation joints.

    ``articulated`` is :func:`~drive_envelope._src.adapters.usd.articulation.articulated_joints` of
    the stage, computed once for a whole robot instead of once per joint.
    """
    kind = joint_kind(prim)
    inst = _choose_instance(prim, kind, instance)
    where = f"joint {str(prim.GetPath())!r} ({inst})"
    if kind == "d6":
        _check_d6_axis(prim, inst, where)
    expected = "revolute" if is_angular(inst) else "prismatic"
    if envelope.joint != expected:
        raise InputError(
            f"{where}: the envelope is for a {envelope.joint} joint, this drive needs a {expected} one"
        )
    units = stage_units(prim.GetStage())
    values = _usd_values(envelope, inst, units, where)
    site = edit_site(prim)
    if site.note:
        _warn(site.note)
    # an instanced joint's note already says why PhysX does not simulate it while instanced
    simulated = str(prim.GetPath()) in articulated or prim.IsInstanceProxy()
    _warn_before_write(prim, inst, envelope, units, where, simulated)
    with usd_errors(f"{where}: USD refused the edit"):
        _author(site.prim, inst, values, where)
    return inst


def _author(target: Usd.Prim, inst: str, values: dict[str, float], where: str) -> None:
    """Apply the two API schemas on ``target`` and set maxForce and the three envelope attributes."""
    from pxr import Sdf, UsdPhysics

    if not target.HasAPI(UsdPhysics.DriveAPI, inst):
        UsdPhysics.DriveAPI.Apply(target, inst)
    UsdPhysics.DriveAPI(target, inst).CreateMaxForceAttr().Set(values.pop("max_effort"))
    if not target.HasAPI(ENVELOPE_API, inst) and not target.ApplyAPI(ENVELOPE_API, inst):
        raise InputError(f"{where}: USD refused {ENVELOPE_API}:{inst} (are the physx-usd-schemas installed?)")
    for field, attr_name in _ATTRIBUTES.items():
        name = f"physxDrivePerformanceEnvelope:{inst}:{attr_name}"
        target.CreateAttribute(name, Sdf.ValueTypeNames.Float, False).Set(values[field])


def _usd_values(envelope: PerformanceEnvelope, inst: str, units: StageUnits, where: str) -> dict[str, float]:
    """The four values as the stage stores them; a finite value beyond float32 is refused.

    USD keeps them as 32-bit floats: beyond 3.4e38 a value becomes inf, which for maxForce means an
    unlimited drive (and so no envelope at all) and for a slope a wrong number.
    """
    values = {}
    for field, factor in _factors(units, inst).items():
        si = getattr(envelope, field)
        value = si * factor
        if math.isfinite(si) and not value <= _FLT_MAX:
            raise InputError(
                f"{where}: {field} {si:.6g} (SI) is {value:.6g} in this stage's units (metersPerUnit "
                f"{units.meters_per_unit:g}, kilogramsPerUnit {units.kilograms_per_unit:g}), beyond the "
                "largest float32 USD can store (3.4e38): it would be written as inf"
            )
        values[field] = value
    return values


def _factors(units: StageUnits, inst: str) -> dict[str, float]:
    """The SI -> stage factor of each envelope field on this drive instance."""
    return {
        "max_effort": units.effort(inst),
        "max_actuator_velocity": units.velocity(inst),
        "velocity_dependent_resistance": units.per_speed(inst),
        "speed_effort_gradient": units.speed_per_effort(inst),
    }


def _warn(message: str) -> None:
    warnings.warn(message, EnvelopeAuthoringWarning, stacklevel=4)


def _warn_before_write(
    prim: Usd.Prim, inst: str, envelope: PerformanceEnvelope, units: StageUnits, where: str, articulated: bool
) -> None:
    """Emit the authoring warnings that compare the new envelope with what the joint already has."""
    from pxr import UsdPhysics

    if not articulated:
        _warn(
            f"{where}: PhysX does not make it an articulation joint (no PhysicsArticulationRootAPI reaches "
            "it, or it anchors the articulation to the world, joins a link to the world, closes a loop or "
            "is excluded); PhysX ignores the envelope here"
        )
    if not prim.HasAPI(UsdPhysics.DriveAPI, inst):
        return
    drive = UsdPhysics.DriveAPI(prim, inst)
    current = drive.GetMaxForceAttr()
    if current.HasAuthoredValue():
        old = float(current.Get()) / units.effort(inst)
        if not math.isclose(old, envelope.max_effort, rel_tol=1e-6):
            _warn(f"{where}: replacing maxForce {old:.6g} with max_effort {envelope.max_effort:.6g} (SI)")
    if is_angular(inst) and drive.GetTypeAttr().Get() != "acceleration":
        _warn_per_radian_gains(drive, inst, envelope, units, where)


def _warn_per_radian_gains(
    drive: Any, inst: str, envelope: PerformanceEnvelope, units: StageUnits, where: str
) -> None:
    """Warn when a gain read per degree saturates maxEffort within one degree (or deg/s) of error."""
    torque_usd = envelope.max_effort * units.effort(inst)
    if not torque_usd > 0.0:
        return
    for label, attr in (("stiffness", drive.GetStiffnessAttr()), ("damping", drive.GetDampingAttr())):
        value = attr.Get() if attr.HasAuthoredValue() else None
        if value is not None and float(value) * _SUSPICIOUS_ERROR_DEG >= torque_usd:
            _warn(
                f"{where}: drive {label} {float(value):.6g} per degree saturates max_effort within "
                f"{_SUSPICIOUS_ERROR_DEG:g} degree{'/s' if label == 'damping' else ''}: "
                "USD stores angular gains per degree; was a per-radian value written?"
            )


# -- reading ------------------------------------------------------------------------------------------


def read_envelope(
    prim_or_stage: Any, joint_path: str | None = None, instance: str | None = None
) -> PerformanceEnvelope:
    """Read the envelope PhysX will use from a joint's drive: the exact inverse of :func:`write_envelope`.

    Unauthored envelope attributes take the schema defaults PhysX uses: ``maxActuatorVelocity``
    inf, the two slopes 0.

    Args:
        prim_or_stage: A ``Usd.Stage`` or ``Usd.Prim``, as for :func:`write_envelope`.
        joint_path: Prim path of the joint, or None.
        instance: Drive instance; default from the joint type.

    Returns:
        The envelope in SI (joint side), ``name`` set to the joint path.

    Raises:
        InputError: no such joint, no ``PhysxDrivePerformanceEnvelopeAPI:<inst>`` on it, or
            negative / NaN values.
    """
    prim = resolve_joint(prim_or_stage, joint_path)
    inst = _choose_instance(prim, joint_kind(prim), instance)
    if not prim.HasAPI(ENVELOPE_API, inst):
        raise InputError(f"joint {str(prim.GetPath())!r}: no {ENVELOPE_API}:{inst} applied")
    return _envelope_of(prim, inst, stage_units(prim.GetStage()))


def _number(attr: Any, default: float, where: str) -> float:
    """An attribute's value as a float (``default`` when it has none); anything else is refused."""
    raw = attr.Get() if attr else None
    if raw is None:
        return default
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        raise InputError(f"{where}: {attr.GetName()} is {raw!r}; expected a number")
    return float(raw)


def _drive_values(prim: Usd.Prim, inst: str, units: StageUnits) -> tuple[float, float, float]:
    """``(max_effort, stiffness, damping)`` of a drive in SI (inf for an unlimited maxForce)."""
    from pxr import UsdPhysics

    where = f"joint {str(prim.GetPath())!r} ({inst})"
    drive = UsdPhysics.DriveAPI(prim, inst)
    max_force = _number(drive.GetMaxForceAttr(), math.inf, where)
    max_effort = math.inf if max_force >= _FLT_MAX else max_force / units.effort(inst)
    stiffness = _number(drive.GetStiffnessAttr(), 0.0, where)
    damping = _number(drive.GetDampingAttr(), 0.0, where)
    if drive.GetTypeAttr().Get() == "acceleration":
        # acceleration gains are per time only; angular ones are still per degree
        angle = units.position(inst) if is_angular(inst) else 1.0
        return max_effort, stiffness * angle, damping * angle
    return max_effort, stiffness / units.per_position(inst), damping / units.per_speed(inst)


def model_rating(prim: Usd.Prim, instance: str | None) -> tuple[float, float]:
    """What the asset itself says a joint's drive can do, before an envelope replaces it.

    Returns:
        ``(maxForce, physxJoint:maxJointVelocity)`` in SI [N*m or N, rad/s or m/s]; ``inf`` where
        unauthored or unlimited (PhysX's FLT_MAX), or where the instance has no drive yet.
    """
    from pxr import UsdPhysics

    inst = _choose_instance(prim, joint_kind(prim), instance)
    units = stage_units(prim.GetStage())
    effort = math.inf
    if prim.HasAPI(UsdPhysics.DriveAPI, inst):
        effort = _drive_values(prim, inst, units)[0]
    speed = math.inf
    attr = prim.GetAttribute("physxJoint:maxJointVelocity")
    raw = attr.Get() if attr and attr.HasAuthoredValue() else None
    if isinstance(raw, (int, float)) and not isinstance(raw, bool) and 0.0 < float(raw) < _FLT_MAX:
        speed = float(raw) / units.velocity(inst)
    return effort, speed


def _envelope_of(prim: Usd.Prim, inst: str, units: StageUnits) -> PerformanceEnvelope:
    """The envelope of an instance that has the API applied.

    An unlimited maxForce gives ``max_effort = inf``: PhysX then keeps the speed line (eq. 2) alone.
    """
    max_effort, _, _ = _drive_values(prim, inst, units)
    factors = _factors(units, inst)
    where = f"joint {str(prim.GetPath())!r} ({inst})"
    values = {}
    for field, attr_name in _ATTRIBUTES.items():
        attr = prim.GetAttribute(f"physxDrivePerformanceEnvelope:{inst}:{attr_name}")
        value = _number(attr, math.inf if field == "max_actuator_velocity" else 0.0, where)
        if field == "max_actuator_velocity" and value >= _FLT_MAX:
            value = math.inf
        values[field] = value / factors[field]
    joint: JointType = "revolute" if is_angular(inst) else "prismatic"
    try:
        return PerformanceEnvelope(max_effort=max_effort, joint=joint, name=str(prim.GetPath()), **values)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None


def _drive_instances(prim: Usd.Prim) -> list[str]:
    """Instances of PhysicsDriveAPI applied on a prim, in a stable order."""
    names = []
    for schema in prim.GetAppliedSchemas():
        api, _, inst = str(schema).partition(":")
        if api == _DRIVE_API and inst:
            names.append(inst)
    order = {name: i for i, name in enumerate(ANGULAR_INSTANCES + LINEAR_INSTANCES)}
    return sorted(names, key=lambda name: (order.get(name, len(order)), name))


def has_envelope_api(prim: Usd.Prim, inst: str) -> bool:
    """Whether ``PhysxDrivePerformanceEnvelopeAPI:<inst>`` is applied, registered with USD or not.

    USD builds its schema registry once per process: if Newton's ``add_usd`` (or anything) read a
    stage before ``physx_usd_schemas`` was imported, ``HasAPI`` says False for an API that the
    layers do apply. The layers' ``apiSchemas`` list ops, composed weakest first, still say it, and
    the attributes are authored there, so the drive's envelope is read either way.
    """
    if prim.HasAPI(ENVELOPE_API, inst):
        return True
    applied: list[str] = []
    for spec in reversed(prim.GetPrimStack()):  # weakest opinion first
        if spec.HasInfo("apiSchemas"):
            applied = list(spec.GetInfo("apiSchemas").ApplyOperations(applied))
    return f"{ENVELOPE_API}:{inst}" in applied


def list_drives(stage: Usd.Stage) -> list[DriveRecord]:
    """Every drive on every revolute, prismatic or D6 joint of the stage, in SI, in stage order."""
    from pxr import Usd, UsdPhysics

    units = stage_units(stage)
    articulated = articulated_joints(stage)
    records = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if not prim.IsA(UsdPhysics.Joint):
            continue
        try:
            kind = joint_kind(prim)
        except InputError:
            continue
        for inst in _drive_instances(prim):
            max_effort, stiffness, damping = _drive_values(prim, inst, units)
            envelope = _envelope_of(prim, inst, units) if has_envelope_api(prim, inst) else None
            records.append(
                DriveRecord(
                    joint_path=str(prim.GetPath()),
                    joint_kind=kind,
                    instance=inst,
                    in_articulation=str(prim.GetPath()) in articulated,
                    max_effort=max_effort,
                    stiffness=stiffness,
                    damping=damping,
                    envelope=envelope,
                )
            )
    return records

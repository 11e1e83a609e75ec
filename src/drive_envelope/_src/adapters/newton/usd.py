"""``add_envelopes_from_usd``: the PhysX envelopes of a USD asset as Newton actuators.

Newton 1.8's ``ModelBuilder.add_usd`` reads a drive's gains and ``maxForce`` but drops
``PhysxDrivePerformanceEnvelopeAPI``. After ``builder.add_usd(source)``, :func:`add_envelopes_from_usd`
reads every joint drive of the same stage through the USD adapter (the one reader of the envelope:
per-degree values converted, :func:`~drive_envelope._src.adapters.usd.authoring.list_drives`) and,
for each drive with an envelope on an articulation joint, adds a Newton actuator on that DOF:
``DrivePD`` with the drive's stiffness and damping, clamped by ``ClampingPerformanceEnvelope``. It
then turns off Newton's own joint drive on that DOF (``joint_target_ke = joint_target_kd = 0``,
``joint_target_mode = EFFORT``: the effort comes through ``joint_f``), so the PD law is not applied
twice, once by the solver and once by the actuator.

As in PhysX, an envelope on a joint outside an articulation is ignored (with a warning), and a
drive with an unlimited ``maxForce`` has no envelope.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from typing import Any

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError

_ROTATION_AXES = {"rotX": 0, "rotY": 1, "rotZ": 2}
_PRISMATIC, _REVOLUTE, _D6 = 0, 1, 6  # newton.JointType values of the joints a drive can be on


class EnvelopeImportWarning(UserWarning):
    """An envelope in the USD that Newton will not apply, as PhysX would not (a non-articulation joint)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class UsdEnvelopeActuator:
    """One actuator :func:`add_envelopes_from_usd` added: a USD joint drive and its Newton DOF."""

    joint_path: str
    """Prim path of the joint (Newton's joint label)."""
    instance: str
    """USD drive instance: ``angular``, ``linear`` or ``rotX|rotY|rotZ``."""
    joint_index: int
    """Index of the joint in the builder."""
    dof_index: int
    """Index of the DOF in ``joint_qd``-shaped arrays (velocities, efforts, ``joint_f``)."""
    coord_index: int
    """Index of the DOF in ``joint_q``-shaped arrays (positions, position targets)."""
    envelope: PerformanceEnvelope
    """The envelope (SI, joint side) the actuator's ``ClampingPerformanceEnvelope`` got."""
    stiffness: float
    """The drive's stiffness, now the actuator's ``kp`` [N*m/rad or N/m]."""
    damping: float
    """The drive's damping, now the actuator's ``kd`` [N*m*s/rad or N*s/m]."""


def _check_builder(builder: Any) -> None:
    """Refuse anything but a ``newton.ModelBuilder``, and a builder that has been finalized.

    Newton 1.8 has no "finalized" flag and ``finalize`` may be called again, so it is detected by
    the one trace ``finalize`` leaves: it sets ``world_count = max(1, world_count)`` without adding
    a world's gravity, while ``begin_world``, ``add_world`` and ``replicate`` keep
    ``len(world_gravity) == world_count``. A builder whose entities are all global (one robot from
    ``add_usd``, the usual case) is caught; one finalized after ``begin_world``/``replicate`` leaves
    no trace and cannot be.
    """
    import newton

    if not isinstance(builder, newton.ModelBuilder):
        raise InputError(
            f"add_envelopes_from_usd: builder: expected a newton.ModelBuilder, got {type(builder).__name__}"
        )
    if builder.world_count > len(builder.world_gravity):
        raise InputError(
            "add_envelopes_from_usd: builder: already finalized (builder.finalize() was called); the "
            "model it made has none of the actuators added now: call add_envelopes_from_usd before finalize"
        )


def _check_source(source: Any) -> None:
    if isinstance(source, (str, os.PathLike)) or hasattr(source, "GetRootLayer"):
        return
    raise InputError(
        f"add_envelopes_from_usd: source: expected a USD file path (str or os.PathLike) or a Usd.Stage, "
        f"got {type(source).__name__}"
    )


def _open(source: Any) -> tuple[str, Any]:
    """The name and stage of ``source``: a path opened through the USD adapter, or a ``Usd.Stage``."""
    from drive_envelope._src.adapters.usd.stage import open_stage

    if isinstance(source, (str, os.PathLike)):
        # not strict: add_usd may have built USD's schema registry first; the envelope is read from
        # the layers' apiSchemas and authored attributes (authoring.has_envelope_api)
        return os.fspath(source), open_stage(source, strict=False)
    layer = source.GetRootLayer()
    return str(layer.realPath or layer.identifier), source


def _check_units(stage: Any, where: str) -> None:
    """Refuse stages Newton does not import in SI: the actuators' values would be in another unit."""
    from drive_envelope._src.adapters.usd.stage import stage_units

    units = stage_units(stage)
    if units.meters_per_unit != 1.0 or units.kilograms_per_unit != 1.0:
        raise InputError(
            f"{where}: metersPerUnit = {units.meters_per_unit:g}, kilogramsPerUnit = "
            f"{units.kilograms_per_unit:g}; Newton imports USD only in SI (both 1), so its model and "
            "the SI envelopes would disagree"
        )


def _joints_by_label(builder: Any) -> dict[str, list[int]]:
    joints: dict[str, list[int]] = {}
    for index, label in enumerate(builder.joint_label):
        joints.setdefault(str(label), []).append(index)
    return joints


def _dof_offset(builder: Any, joint: int, instance: str, where: str) -> int:
    """Offset of the drive instance's DOF within the joint's DOFs (0 except on D6 joints)."""
    kind = int(builder.joint_type[joint])
    if kind in (_PRISMATIC, _REVOLUTE):
        return 0
    if kind != _D6 or instance not in _ROTATION_AXES:
        raise InputError(
            f"{where}: Newton made it a joint of type {kind}; expected a revolute, prismatic or D6"
        )
    linear, angular = builder.joint_dof_dim[joint]
    start = builder.joint_qd_start[joint]
    axis = _ROTATION_AXES[instance]
    for k in range(linear, linear + angular):
        direction = [float(c) for c in builder.joint_axis[start + k]]
        if abs(direction[axis] - 1.0) < 1e-6 and sum(abs(c) for c in direction) < 1.0 + 1e-6:
            return k
    raise InputError(
        f"{where}: Newton has no free {instance} axis on this D6 joint (a locked axis has no DOF)"
    )


def _actuated_dofs(builder: Any) -> set[int]:
    """DOFs that already have an actuator in the builder."""
    return {index for entry in builder.actuator_entries.values() for index in entry.indices}


def add_envelopes_from_usd(builder: Any, source: Any) -> list[UsdEnvelopeActuator]:
    """Add a PD actuator clamped by the PhysX envelope for every USD joint drive that has one.

    Call it on the builder ``builder.add_usd(source)`` filled, before ``finalize`` (and before
    ``replicate`` or ``add_builder``, which copy the actuators with the robot). DOFs that already
    have an actuator are left as they are, so calling it again after a second ``add_usd`` adds
    only the new copies.

    Args:
        builder: A ``newton.ModelBuilder`` holding the asset's joints (labelled by prim path).
        source: The USD file (or ``Usd.Stage``) given to ``add_usd``; it must be in SI units
            (``metersPerUnit = kilogramsPerUnit = 1``), as Newton requires.

    Returns:
        One record per actuator added, in stage order.

    Raises:
        InputError: ``builder`` not a ``newton.ModelBuilder`` or already finalized (see
            ``docs/newton.md`` for what is detected), ``source`` not a path or ``Usd.Stage``, the
            file cannot be read, a stage not in SI, an acceleration drive (Newton's PD is a force
            drive), or a drive whose joint is not in the builder.

    Warns:
        EnvelopeImportWarning: an envelope on a joint outside an articulation (PhysX ignores it too).
    """
    from newton import JointTargetMode
    from newton.actuators import DrivePD

    from drive_envelope._src.adapters.newton.clamp_stage import ClampingPerformanceEnvelope
    from drive_envelope._src.adapters.usd.authoring import list_drives

    _check_builder(builder)
    _check_source(source)
    name, stage = _open(source)
    _check_units(stage, name)
    joints = _joints_by_label(builder)
    actuated = _actuated_dofs(builder)
    added = []
    records = list_drives(stage)
    for record in records:
        if record.envelope is None:
            continue
        where = f"{name}: joint {record.joint_path!r} ({record.instance})"
        if not record.in_articulation:
            warnings.warn(
                f"{where}: not an articulation joint; PhysX ignores its envelope and so does this import",
                EnvelopeImportWarning,
                stacklevel=2,
            )
            continue
        _check_drive_type(stage, record.joint_path, record.instance, where)
        if record.joint_path not in joints:
            raise InputError(
                f"{where}: no joint with this label in the builder; call builder.add_usd(source) first"
            )
        for joint in joints[record.joint_path]:
            offset = _dof_offset(builder, joint, record.instance, where)
            dof = builder.joint_qd_start[joint] + offset
            if dof in actuated:
                continue
            coord = builder.joint_q_start[joint] + offset
            envelope = {field: float(getattr(record.envelope, field)) for field in ENVELOPE_FIELDS}
            builder.add_actuator(
                DrivePD,
                index=dof,
                pos_index=coord,
                kp=record.stiffness,
                kd=record.damping,
                clamping=[(ClampingPerformanceEnvelope, envelope)],
            )
            # Newton's own drive would apply the same PD law a second time, unclamped
            builder.joint_target_ke[dof] = 0.0
            builder.joint_target_kd[dof] = 0.0
            builder.joint_target_mode[dof] = int(JointTargetMode.EFFORT)
            actuated.add(dof)
            added.append(
                UsdEnvelopeActuator(
                    joint_path=record.joint_path,
                    instance=record.instance,
                    joint_index=joint,
                    dof_index=dof,
                    coord_index=coord,
                    envelope=record.envelope,
                    stiffness=record.stiffness,
                    damping=record.damping,
                )
            )
    return added


def _check_drive_type(stage: Any, joint_path: str, instance: str, where: str) -> None:
    """Refuse an acceleration drive: its gains are per unit inertia, Newton's PD is a force law."""
    prim = stage.GetPrimAtPath(joint_path)
    attribute = prim.GetAttribute(f"drive:{instance}:physics:type") if prim else None
    kind = attribute.Get() if attribute else None
    if kind == "acceleration":
        raise InputError(
            f"{where}: drive type 'acceleration' (gains per unit inertia); Newton's DrivePD is a force "
            "drive: author physics:type = 'force' with the gains multiplied by the joint's inertia"
        )
    if kind not in (None, "force"):
        raise InputError(f"{where}: drive type {kind!r}; expected 'force' or 'acceleration'")

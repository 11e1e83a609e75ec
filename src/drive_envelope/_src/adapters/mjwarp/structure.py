"""The static structure of a model's envelope drives, as the MJWarp kernels read it (host side).

A drive is one hinge or slide joint, its effort actuator (whose ``actuator_dynprm`` holds the six
numbers, the layout of ``drive_envelope.mujoco``) and up to three input actuators (``pos``,
``vel``, ``ff``, one control each). :class:`DriveTable` keeps them in DOF order (root to leaves,
the order of the plugin's Gauss-Seidel sweeps) with everything a step needs that MJWarp's model
does not hold: which inputs are delayed, which actuator groups are disabled, which other actuators
push the model (their forces enter the prediction) and which actuators add joint damping.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError

INPUTS = ("pos", "vel", "ff")
"""The control inputs of a drive, in their canonical order (MuJoCo's ``pid`` actuator)."""

IntArray = npt.NDArray[np.int32]

# MuJoCo enum values the table is built from (mjtTrn, mjtJoint, mjtDyn; fixed by MuJoCo's ABI)
_TRN_JOINT, _TRN_JOINTINPARENT = 0, 1
_JNT_SLIDE, _JNT_HINGE = 2, 3
_DYN_NONE = 0


@dataclass(frozen=True, kw_only=True, slots=True)
class DriveSpec:
    """One drive before it is checked against the model: its actuators by id."""

    actuator: int
    """The effort actuator: carries the drive's total effort and holds its ``dynprm``."""
    inputs: tuple[int, int, int]
    """Actuator ids of the ``pos``, ``vel`` and ``ff`` inputs; -1: absent (0)."""
    acceleration: bool = False
    """True for an ``acceleration`` drive (gains per unit inertia), False for ``force``."""


def plugin_drive_specs(mj_model: Any) -> list[DriveSpec]:
    """The drives of ``drive_envelope.envelope`` plugin actuators in a compiled model (plugin loaded)."""
    from drive_envelope._src.adapters.mujoco.params import model_drives

    specs = []
    for info in model_drives(mj_model):
        ids = dict(zip(info.inputs, info.actuators, strict=True))
        inputs = (ids.get("pos", -1), ids.get("vel", -1), ids.get("ff", -1))
        specs.append(
            DriveSpec(actuator=info.actuator, inputs=inputs, acceleration=info.drive_type == "acceleration")
        )
    return specs


def _raw_name(mj_model: Any, kind: str, index: int) -> str:
    """The element's name, or ``#id`` when it has none."""
    return str(getattr(mj_model, kind)(index).name) or f"#{index}"


def _name(mj_model: Any, kind: str, index: int) -> str:
    """The element's name quoted for messages, or ``#id``."""
    name = _raw_name(mj_model, kind, index)
    return name if name.startswith("#") else f"'{name}'"


def _check_actuator(mj_model: Any, i: int) -> str:
    """Why actuator ``i`` cannot feed a drive, or an empty string (the plugin's own rules)."""
    if int(mj_model.actuator_trntype[i]) not in (_TRN_JOINT, _TRN_JOINTINPARENT):
        return "needs a joint transmission (a hinge or slide joint)"
    joint = int(mj_model.actuator_trnid[i, 0])
    if int(mj_model.jnt_type[joint]) not in (_JNT_SLIDE, _JNT_HINGE):
        return f"joint {_name(mj_model, 'joint', joint)} is not a hinge or slide joint (one DOF)"
    gear = np.asarray(mj_model.actuator_gear[i], dtype=np.float64)
    if gear[0] != 1.0:
        return "attribute 'gear' must be 1: the drive works on the joint side"
    if bool(mj_model.actuator_forcelimited[i]):
        return "attribute 'forcerange' must not be set: the envelope limits the effort"
    ctrlnum = int(getattr(mj_model, "actuator_ctrlnum", np.ones(mj_model.nu))[i])
    if (
        ctrlnum != 1
        or int(mj_model.actuator_actnum[i]) != 0
        or int(mj_model.actuator_dyntype[i]) != _DYN_NONE
    ):
        return "expected one control and no activation (dyntype 'none', no actdim)"
    return ""


@dataclass(frozen=True, kw_only=True, slots=True)
class DriveTable:
    """Every envelope drive of one model, in DOF order, as NumPy int32 arrays (built by :meth:`build`)."""

    names: tuple[str, ...]
    """Name of each drive's effort actuator (``#id`` when unnamed)."""
    joints: tuple[str, ...]
    """Name of each drive's joint."""
    prismatic: tuple[bool, ...]
    """Whether each drive's joint is a slide joint (SI units N, m/s) rather than a hinge."""
    dof: IntArray
    """DOF address of each drive, ascending."""
    qpos: IntArray
    """``qpos`` address of each drive's joint."""
    actuator: IntArray
    """Effort actuator of each drive."""
    inputs: IntArray
    """``(ndrive, 3)``: actuator of the pos, vel, ff input; -1: absent."""
    acceleration: IntArray
    """1 for an acceleration drive, 0 for a force drive."""
    enabled: IntArray
    """0 where the effort actuator's group is disabled (``opt.disableactuator``): the drive gives 0."""
    input_enabled: IntArray
    """``(ndrive, 3)``: 0 where an input actuator's group is disabled (it contributes 0)."""
    delayed: IntArray
    """``(ndrive, 3)``: row of each input in the delayed-control buffer, -1 when read directly."""
    delayed_actuators: tuple[int, ...]
    """The input actuators with a ``delay`` (read through MJWarp's history buffer), by row."""
    outputs: IntArray
    """``(ndrive, 3)``: every actuator of each drive (their forces are written), -1 padded."""
    native: IntArray
    """Actuators of no drive: their forces enter the drives' prediction."""
    damping_adr: IntArray
    """Per DOF, first entry in :attr:`damping_actuator` (actuators that add joint damping)."""
    damping_num: IntArray
    """Per DOF, number of entries in :attr:`damping_actuator`."""
    damping_actuator: IntArray
    """Actuators on each DOF's joint (their ``damping`` is integrated implicitly with it)."""

    @property
    def count(self) -> int:
        """Number of drives."""
        return len(self.names)

    def index(self, actuator: int | str, where: str) -> int:
        """The drive that ``actuator`` (a name or id of any of its actuators) belongs to."""
        if isinstance(actuator, str) and actuator in self.names:
            return self.names.index(actuator)
        if isinstance(actuator, int) and not isinstance(actuator, bool):
            hits = np.flatnonzero((self.outputs == actuator).any(axis=1))
            if hits.size:
                return int(hits[0])
        known = ", ".join(self.names) or "none"
        raise InputError(
            f"{where}: argument 'actuator': {actuator!r} is not a drive of this model (drives: {known})"
        )

    @classmethod
    def build(cls, mj_model: Any, specs: Sequence[DriveSpec]) -> DriveTable:
        """Check ``specs`` against the compiled ``mj_model`` and lay them out in DOF order.

        Raises:
            InputError: an actuator that cannot feed a drive, or two drives on one joint.
        """
        nu, nv = int(mj_model.nu), int(mj_model.nv)
        rows: list[tuple[int, int, DriveSpec]] = []
        seen: dict[int, int] = {}
        for spec in specs:
            used = [spec.actuator, *(i for i in spec.inputs if i >= 0)]
            for i in used:
                if not 0 <= i < nu:
                    raise InputError(f"drive actuator id {i}: expected an id in [0, {nu})")
                problem = _check_actuator(mj_model, i)
                if problem:
                    raise InputError(f"actuator {_name(mj_model, 'actuator', i)}: {problem}")
            joint = int(mj_model.actuator_trnid[spec.actuator, 0])
            for i in used:
                if int(mj_model.actuator_trnid[i, 0]) != joint:
                    raise InputError(
                        f"actuator {_name(mj_model, 'actuator', i)}: drives another joint than its effort "
                        f"actuator {_name(mj_model, 'actuator', spec.actuator)}"
                    )
            if joint in seen:
                first, second = (_name(mj_model, "actuator", i) for i in (seen[joint], spec.actuator))
                raise InputError(
                    f"joint {_name(mj_model, 'joint', joint)} has two drives: actuators {first} and {second}"
                )
            seen[joint] = spec.actuator
            rows.append((int(mj_model.jnt_dofadr[joint]), joint, spec))
        rows.sort(key=lambda row: row[0])
        return cls._layout(mj_model, rows, nu, nv)

    @classmethod
    def _layout(cls, mj_model: Any, rows: list[tuple[int, int, DriveSpec]], nu: int, nv: int) -> DriveTable:
        n = len(rows)
        disabled = int(getattr(mj_model.opt, "disableactuator", 0))
        groups = np.asarray(mj_model.actuator_group, dtype=np.int64)

        def enabled(i: int) -> int:
            group = int(groups[i])
            return 0 if 0 <= group <= 30 and disabled & (1 << group) else 1

        inputs = np.array([row[2].inputs for row in rows], dtype=np.int32).reshape(n, 3)
        delays = np.asarray(mj_model.actuator_delay, dtype=np.float64).reshape(nu)
        history = np.asarray(mj_model.actuator_history, dtype=np.int64).reshape(nu, 2)
        delayed = np.full((n, 3), -1, dtype=np.int32)
        delayed_actuators: list[int] = []
        for k in range(n):
            for s in range(3):
                i = int(inputs[k, s])
                if i >= 0 and delays[i] > 0 and history[i, 0] > 0:
                    delayed[k, s] = len(delayed_actuators)
                    delayed_actuators.append(i)
        outputs = np.full((n, 3), -1, dtype=np.int32)
        for k, (_, _, spec) in enumerate(rows):
            ids = sorted({spec.actuator, *(int(i) for i in spec.inputs if i >= 0)})
            outputs[k, : len(ids)] = ids
        driven = {int(i) for i in outputs.ravel() if i >= 0}
        adr, num, actuators = cls._damping(mj_model, nu, nv)
        return cls(
            names=tuple(_raw_name(mj_model, "actuator", row[2].actuator) for row in rows),
            joints=tuple(_raw_name(mj_model, "joint", row[1]) for row in rows),
            prismatic=tuple(int(mj_model.jnt_type[row[1]]) == _JNT_SLIDE for row in rows),
            dof=np.array([row[0] for row in rows], dtype=np.int32),
            qpos=np.array([int(mj_model.jnt_qposadr[row[1]]) for row in rows], dtype=np.int32),
            actuator=np.array([row[2].actuator for row in rows], dtype=np.int32),
            inputs=inputs,
            acceleration=np.array([int(row[2].acceleration) for row in rows], dtype=np.int32),
            enabled=np.array([enabled(row[2].actuator) for row in rows], dtype=np.int32),
            input_enabled=np.array(
                [[enabled(int(i)) if i >= 0 else 0 for i in row] for row in inputs], dtype=np.int32
            ).reshape(n, 3),
            delayed=delayed,
            delayed_actuators=tuple(delayed_actuators),
            outputs=outputs,
            native=np.array([i for i in range(nu) if i not in driven], dtype=np.int32),
            damping_adr=adr,
            damping_num=num,
            damping_actuator=actuators,
        )

    @staticmethod
    def _damping(mj_model: Any, nu: int, nv: int) -> tuple[IntArray, IntArray, IntArray]:
        """Per DOF, the actuators on its joint: MuJoCo adds their ``damping * gear^2`` to the joint's."""
        trntype = np.asarray(mj_model.actuator_trntype)
        trnid = np.asarray(mj_model.actuator_trnid)[:, 0]
        adr, num = np.zeros(nv, np.int32), np.zeros(nv, np.int32)
        found: list[int] = []
        for dof in range(nv):
            joint = int(mj_model.dof_jntid[dof])
            on_joint = [
                i for i in range(nu) if trntype[i] in (_TRN_JOINT, _TRN_JOINTINPARENT) and trnid[i] == joint
            ]
            adr[dof], num[dof] = len(found), len(on_joint)
            found.extend(on_joint)
        return adr, num, np.array(found or [0], dtype=np.int32)

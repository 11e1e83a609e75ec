"""A drive's numbers in an MJWarp model, per world: read and change them between steps.

They live where the C plugin keeps them, ``actuator_dynprm`` of the drive's effort actuator (the
layout of ``drive_envelope.mujoco``: max_effort, max_actuator_velocity, velocity_dependent_resistance,
speed_effort_gradient, stiffness, damping; -1 = no limit), now MJWarp's ``(B, nactuator)`` array
of float32 rows that world ``w`` reads at row ``w % B``. ``B`` is 1 unless the model was put with
``batch_sizes={"actuator_dynprm": nworld}`` (or expanded by mjlab's ``expand_model_fields``); then
each world has its own envelope: domain randomization. Writes go into the existing array (a CUDA
graph captured before keeps reading it) and take effect at the next step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.adapters.mjwarp.model import envelope_drives
from drive_envelope._src.adapters.mujoco.params import NO_LIMIT, drive_dynprm
from drive_envelope._src.envelope.model import JointType, PerformanceEnvelope
from drive_envelope._src.errors import InputError

Worlds = int | Sequence[int] | None


def _rows(batch: int, world: Worlds, where: str) -> npt.NDArray[np.intp]:
    """The rows of ``actuator_dynprm`` that ``world`` (None: all) selects."""
    if world is None:
        return np.arange(batch)
    worlds = np.atleast_1d(np.asarray(world))
    if worlds.dtype.kind not in "iu" or worlds.ndim != 1:
        raise InputError(
            f"{where}: argument 'world': expected a world index, a sequence of them or None, got {world!r}"
        )
    if batch == 1 and not (worlds == 0).all():
        raise InputError(
            f"{where}: argument 'world' = {world!r}: every world shares one actuator_dynprm row; put the "
            "model with batch_sizes={'actuator_dynprm': nworld} for an envelope per world"
        )
    if ((worlds < 0) | (worlds >= batch)).any():
        raise InputError(f"{where}: argument 'world' = {world!r}: expected indices in [0, {batch})")
    return worlds.astype(np.intp)


def _drive(m: Any, actuator: int | str, where: str) -> tuple[int, JointType]:
    """(effort actuator id, joint type) of the drive that ``actuator`` names."""
    table = envelope_drives(m, where).table
    k = table.index(actuator, where)
    return int(table.actuator[k]), "prismatic" if table.prismatic[k] else "revolute"


def set_envelope(
    m: Any, actuator: int | str, envelope: PerformanceEnvelope | str, world: Worlds = None
) -> None:
    """Give a drive a new envelope in one world, some or all; it takes effect at the next step.

    Args:
        m: The MJWarp model (from ``drive_envelope.mjwarp.put_model``).
        actuator: Name or id of any of the drive's actuators.
        envelope: A :class:`PerformanceEnvelope`, or an envelope file, datasheet file or catalog name.
        world: A world index or a sequence of them; None: every world.

    Raises:
        InputError: no such drive, an envelope for the other joint type, a number above 1e12, or a
            world index out of range (or any but 0 when the worlds share one row).
    """
    from drive_envelope._src.datasheet.resolve import resolve_envelope

    where = f"set_envelope(actuator={actuator!r})"
    index, kind = _drive(m, actuator, where)
    env = resolve_envelope(envelope, where=f"{where}: argument 'envelope'")
    if env.joint != kind:
        raise InputError(f"{where}: the envelope is for a {env.joint} joint but the drive's joint is {kind}")
    values = drive_dynprm(env, stiffness=0.0, damping=0.0, where=where)[:4]
    table = m.actuator_dynprm.numpy().copy()
    table[_rows(table.shape[0], world, where), index, :4] = values
    m.actuator_dynprm.assign(table)


def set_gains(
    m: Any,
    actuator: int | str,
    *,
    stiffness: float | None = None,
    damping: float | None = None,
    world: Worlds = None,
) -> None:
    """Change a drive's gains in one world, some or all (None keeps a gain); next step on.

    Args:
        m: The MJWarp model.
        actuator: Name or id of any of the drive's actuators.
        stiffness: Drive stiffness [N*m/rad or N/m] (force) or [1/s^2] (acceleration).
        damping: Drive damping [N*m*s/rad or N*s/m] (force) or [1/s] (acceleration).
        world: A world index or a sequence of them; None: every world.

    Raises:
        InputError: no such drive, a gain outside ``[0, 1e12]``, or a bad world index.
    """
    where = f"set_gains(actuator={actuator!r})"
    index, kind = _drive(m, actuator, where)
    probe = PerformanceEnvelope(max_effort=1.0, joint=kind)
    gains = drive_dynprm(probe, stiffness=_given(stiffness), damping=_given(damping), where=where)[4:6]
    table = m.actuator_dynprm.numpy().copy()
    rows = _rows(table.shape[0], world, where)
    if stiffness is not None:
        table[rows, index, 4] = gains[0]
    if damping is not None:
        table[rows, index, 5] = gains[1]
    m.actuator_dynprm.assign(table)


def _given(value: float | None) -> float:
    return 0.0 if value is None else value


def get_envelope(m: Any, actuator: int | str, world: int = 0) -> PerformanceEnvelope:
    """The envelope a drive has in world ``world`` now (SI; float32 values as the device holds them).

    Raises:
        InputError: no such drive, a bad world index, or numbers that are not an envelope.
    """
    where = f"get_envelope(actuator={actuator!r})"
    index, kind = _drive(m, actuator, where)
    table = m.actuator_dynprm.numpy()
    row = table[int(_rows(table.shape[0], world, where)[0]), index].astype(np.float64)
    try:
        return PerformanceEnvelope(
            max_effort=row[0],
            max_actuator_velocity=math.inf if row[1] == NO_LIMIT else row[1],
            velocity_dependent_resistance=row[2],
            speed_effort_gradient=row[3],
            joint=kind,
        )
    except InputError:
        raise InputError(
            f"{where}: world {world}: dynprm = {row[:6].tolist()} is not a valid envelope"
        ) from None


def get_gains(m: Any, actuator: int | str, world: int = 0) -> tuple[float, float]:
    """``(stiffness, damping)`` of a drive in world ``world`` now (SI, see :func:`set_gains`)."""
    where = f"get_gains(actuator={actuator!r})"
    index, _ = _drive(m, actuator, where)
    table = m.actuator_dynprm.numpy()
    row = table[int(_rows(table.shape[0], world, where)[0]), index]
    return float(row[4]), float(row[5])

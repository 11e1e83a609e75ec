"""How many contacts and constraint rows to allocate per world, measured in C MuJoCo.

MJWarp allocates its contact and constraint arrays once (``mujoco_warp.make_data(nconmax=,
njmax=)``); its defaults come from the model alone and can be far too small for a robot on the
floor: the Menagerie G1 peaks at 45 contacts and 216 constraint rows in C MuJoCo against defaults
of 48 and 64, and the rows MJWarp cannot hold are dropped (it drifted up to 16 rad/s from C
MuJoCo). The numbers depend on what the robot does, so they are measured: a C MuJoCo rollout of
the same model (with the plugin's drives, or without), under the caller's controls, and its peaks
times a margin.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple

from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco


class ConstraintSizes(NamedTuple):
    """Per-world sizes for ``mujoco_warp.make_data`` / ``put_data`` and the peaks behind them."""

    nconmax: int
    """Contacts to allocate per world: ``ceil(margin * peak_contacts)``, at least 1 [-]."""
    njmax: int
    """Constraint rows to allocate per world: ``ceil(margin * peak_rows)``, at least 1 [-]."""
    peak_contacts: int
    """Most contacts C MuJoCo had at once in the rollout (``MjData.ncon``) [-]."""
    peak_rows: int
    """Most constraint rows it had at once (``MjData.nefc``: contacts, limits, equalities,
    friction loss) [-]."""


def constraint_sizes(
    mj_model: mujoco.MjModel,
    *,
    steps: int = 2000,
    keyframe: int | None = 0,
    control: Callable[[Any, Any], None] | None = None,
    margin: float = 1.25,
) -> ConstraintSizes:
    """Measure the contacts and constraint rows a rollout needs, for MJWarp's ``nconmax`` / ``njmax``.

    Args:
        mj_model: The model MJWarp will run (compiled; with the plugin's drives the plugin must be
            loaded, ``drive_envelope.mujoco.load_plugin``).
        steps: Steps of the C MuJoCo rollout [-], ``>= 1``.
        keyframe: Keyframe to start from (its qpos and ctrl), or None for ``qpos0``; ignored when
            the model has no keyframes.
        control: ``control(model, data)``, called before every step to set ``data.ctrl`` (the
            motion the worlds will make; a robot that only stands needs fewer contacts than one
            that walks); None keeps the keyframe's controls.
        margin: Factor over the peaks [-], ``>= 1``.

    Raises:
        InputError: ``steps < 1`` or ``margin < 1`` (or not finite).
    """
    import mujoco

    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise InputError(f"steps: expected an integer >= 1, got {steps!r}")
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 1.0):
        raise InputError(f"margin: expected a finite number >= 1, got {margin!r}")
    data = mujoco.MjData(mj_model)
    if keyframe is not None and mj_model.nkey > 0:
        if not 0 <= keyframe < mj_model.nkey:
            raise InputError(f"keyframe: expected an index in [0, {mj_model.nkey}), got {keyframe!r}")
        mujoco.mj_resetDataKeyframe(mj_model, data, keyframe)
    contacts = rows = 0
    mujoco.mj_forward(mj_model, data)
    for _ in range(steps):
        contacts, rows = max(contacts, int(data.ncon)), max(rows, int(data.nefc))
        if control is not None:
            control(mj_model, data)
        mujoco.mj_step(mj_model, data)
    contacts, rows = max(contacts, int(data.ncon)), max(rows, int(data.nefc))
    return ConstraintSizes(
        nconmax=max(1, math.ceil(margin * contacts)),
        njmax=max(1, math.ceil(margin * rows)),
        peak_contacts=contacts,
        peak_rows=rows,
    )

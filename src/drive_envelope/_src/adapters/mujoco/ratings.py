"""What the model itself says a driven joint can do, compared with the envelope that replaces it.

A robot model carries its own effort rating: a joint's ``actuatorfrcrange``, the replaced actuator's
``forcerange``, a motor's ``ctrlrange`` (its torque, times gain and gear). ``mujoco apply`` compares
the envelope with the tightest of these, in the model MuJoCo compiled before the edit, and reports
per map key (one line for a group of joints):

* a cap more than 10 % below the model's own rating: the sources disagree (the catalog's vendor
  file against the model's author), and the user should know which one the drive now uses;
* an ``actuatorfrcrange`` below the cap: MuJoCo clips the drive's effort after the envelope, so
  the implicit solve's effort is not the one applied. An ``actuatorfrcrange`` at or above the cap
  cannot bind (the drive's own effort never exceeds ``max_effort``) and says nothing.

It also finds joint equalities that couple driven joints: their constraint force acts beside the
drives, so the envelope does not bound what those joints get.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from drive_envelope._src.format import first_few

if TYPE_CHECKING:
    import mujoco

DISAGREEMENT = 0.10
"""A cap this fraction below the model's own rating is reported [1]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class Rating:
    """The model's own effort rating of one joint, the tightest of what it states."""

    effort: float
    """The rating [N*m or N]; ``inf`` when the model states none."""
    source: str
    """What states it: ``"actuatorfrcrange"``, ``"forcerange of 'a'"``, ``"ctrlrange of motor 'a'"``."""
    frcrange: float
    """The joint's ``actuatorfrcrange`` alone (the tighter side) [N*m or N]; ``inf`` if none."""


def _tighter(low: float, high: float) -> float:
    return min(abs(low), abs(high))


def joint_ratings(model: mujoco.MjModel, joints: Sequence[str]) -> dict[str, Rating]:
    """The model's own rating of each of ``joints`` (those it does not know are left out).

    Args:
        model: The model compiled before any edit (resolved limits, classes and ``autolimits``).
        joints: Joint names.
    """
    import mujoco

    from drive_envelope._src.adapters.mujoco.existing import compiled_gain_kind

    ratings = {}
    for joint in joints:
        j = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint))
        if j < 0:
            continue
        frc = math.inf
        if bool(model.jnt_actfrclimited[j]):
            frc = _tighter(*(float(v) for v in model.jnt_actfrcrange[j]))
        candidates = [(frc, "actuatorfrcrange")]
        for i in range(model.nu):
            joint_trn = int(model.actuator_trntype[i]) in (
                int(mujoco.mjtTrn.mjTRN_JOINT),
                int(mujoco.mjtTrn.mjTRN_JOINTINPARENT),
            )
            if not joint_trn or int(model.actuator_trnid[i, 0]) != j:
                continue
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) or f"#{i}"
            gear = abs(float(model.actuator_gear[i, 0]))
            if bool(model.actuator_forcelimited[i]):
                force = _tighter(*(float(v) for v in model.actuator_forcerange[i]))
                candidates.append((force * gear, f"forcerange of {name!r}"))
            if compiled_gain_kind(model, i)[0] == "motor" and bool(model.actuator_ctrllimited[i]):
                torque = _tighter(*(float(v) for v in model.actuator_ctrlrange[i]))
                gain = abs(float(model.actuator_gainprm[i, 0]))
                candidates.append((torque * gain * gear, f"ctrlrange of motor {name!r}"))
        effort, source = min(candidates, key=lambda c: c[0])
        ratings[joint] = Rating(effort=effort, source=source, frcrange=frc)
    return ratings


def _unit(joint_type: str) -> str:
    return "N*m" if joint_type == "revolute" else "N"


def rating_lines(groups: dict[str, list[tuple[str, float, str]]], ratings: dict[str, Rating]) -> list[str]:
    """One line per group whose cap is more than :data:`DISAGREEMENT` below the model's own rating.

    Args:
        groups: Map key (or flag) -> its joints as (joint, max_effort [N*m or N], joint type).
        ratings: :func:`joint_ratings` of the model before the edit.
    """
    lines = []
    for where, items in groups.items():
        low = [
            (joint, cap, kind)
            for joint, cap, kind in items
            if joint in ratings
            and math.isfinite(ratings[joint].effort)
            and cap < (1.0 - DISAGREEMENT) * ratings[joint].effort
        ]
        if not low:
            continue
        by_rating: dict[tuple[float, str], list[str]] = {}
        for joint, _, _ in low:
            rating = ratings[joint]
            by_rating.setdefault((rating.effort, rating.source), []).append(joint)
        cap, unit = low[0][1], _unit(low[0][2])
        parts = [
            f"{effort:g} {unit} ({label}) on {first_few(joints, 4, str)}"
            for (effort, label), joints in by_rating.items()
        ]
        worst = max(1.0 - cap / ratings[j].effort for j, _, _ in low)
        lines.append(
            f"{where}: max_effort {cap:g} {unit} is {100 * worst:.0f} % below the model's own rating, "
            f"{'; '.join(parts)}: the drive caps these joints at {cap:g} {unit} (the sources disagree; "
            "give the joints another envelope to keep the model's)"
        )
    return lines


def binding_force_ranges(
    groups: dict[str, list[tuple[str, float, str]]], ratings: dict[str, Rating]
) -> list[str]:
    """One line per group with an ``actuatorfrcrange`` below its cap: MuJoCo clips after the envelope."""
    lines = []
    for where, items in groups.items():
        tight = [
            (joint, cap, kind)
            for joint, cap, kind in items
            if joint in ratings and ratings[joint].frcrange < cap * (1.0 - 1e-9)
        ]
        if not tight:
            continue
        _, cap, kind = tight[0]
        unit = _unit(kind)
        frc = min(ratings[j].frcrange for j, _, _ in tight)
        lines.append(
            f"{where}: actuatorfrcrange {frc:g} {unit} on {first_few([j for j, _, _ in tight], 4, str)} "
            f"is below the envelope's max_effort {cap:g} {unit}: MuJoCo clips the drive's effort after the "
            "envelope (lower max_effort to it, or remove actuatorfrcrange)"
        )
    return lines


def coupled_driven_joints(model: mujoco.MjModel, driven: Sequence[str]) -> list[str]:
    """One line per active joint equality that couples two driven joints (or ties one to the world)."""
    import mujoco

    names = set(driven)
    lines = []
    for e in range(model.neq):
        if int(model.eq_type[e]) != int(mujoco.mjtEq.mjEQ_JOINT):
            continue
        first = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, int(model.eq_obj1id[e])) or ""
        second_id = int(model.eq_obj2id[e])
        second = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, second_id) if second_id >= 0 else None
        touched = [j for j in (first, second) if j in names]
        if len(touched) < (2 if second else 1):
            continue
        label = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, e) or f"#{e}"
        joints = " and ".join(repr(j) for j in touched)
        state = "" if bool(model.eq_active0[e]) else " (inactive at start)"
        lines.append(
            f"equality {label!r}{state} couples driven joint(s) {joints}: its constraint force acts beside "
            "the drives, so the envelope does not bound the effort these joints get (drive one of them, or "
            "couple them in the controller)"
        )
    return lines

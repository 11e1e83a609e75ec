"""The identified envelope in canonical form: every line it reports can bind.

Two envelopes with the same feasible region in the (velocity, effort) plane clamp every request the
same way (PhysX's clamp keeps the largest feasible magnitude), so a line that never reaches the
boundary of the region is not identified by any log: its numbers can wander along a flat valley of
the cost (the issue's seed spread of ``max_effort`` 0.57-0.63 N*m while the speed line caps the
effort at rest at 0.40 N*m). The canonical form moves such a line to where it starts to bind:

* **eq. 1 never binds** (``max_effort >= max_actuator_velocity / speed_effort_gradient`` and
  ``max_effort - velocity_dependent_resistance * max_actuator_velocity >= 0``: the speed line lies
  under it on the whole speed range) -> ``max_effort = max_actuator_velocity /
  speed_effort_gradient`` (the stall effort) and ``velocity_dependent_resistance = 0``;
* **eq. 2 never binds** (``velocity_dependent_resistance > 0``, eq. 1's zero-effort speed
  ``max_effort / velocity_dependent_resistance`` at or below eq. 2's, and eq. 2 above eq. 1 at
  rest) -> ``max_actuator_velocity = max_effort / velocity_dependent_resistance`` and
  ``speed_effort_gradient = 0``.

Both keep the region, so the replay is the same (to rounding in the clamp). A servo's stiffness
``duty_per_rad * duty_effort`` keeps the search's ``duty_effort``: when ``max_effort`` moves, the
loop gain is written beside it (``[servo] duty_effort``) instead of changing with it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping


def canonical_envelope(
    values: Mapping[str, float], unit: str = "N*m"
) -> tuple[dict[str, float], tuple[str, ...]]:
    """The values with the envelope in canonical form, and a note per line moved.

    Args:
        values: Every parameter [SI] (``max_effort``, ``max_actuator_velocity``,
            ``velocity_dependent_resistance``, ``speed_effort_gradient``, ``duty_effort`` among them).
        unit: The effort unit for the notes (``N*m`` or ``N``).

    Returns:
        ``(values, notes)``: a copy with the moved lines, and what was moved and why.
    """
    out = dict(values)
    notes: list[str] = []
    effort = out["max_effort"]
    speed = out["max_actuator_velocity"]
    resistance = out["velocity_dependent_resistance"]
    gradient = out["speed_effort_gradient"]
    if not (math.isfinite(effort) and effort > 0.0 and speed > 0.0):
        return out, ()
    at_rest = speed / gradient if gradient > 0.0 and math.isfinite(speed) else math.inf
    if math.isfinite(at_rest) and effort >= at_rest and effort - resistance * speed >= 0.0:
        notes.append(
            f"max_effort {effort:.6g} {unit} never binds: the speed line (eq. 2) caps the effort at rest "
            f"at {at_rest:.6g} {unit} and stays below eq. 1 at every speed; reported as max_effort = "
            f"{at_rest:.6g} {unit} with velocity_dependent_resistance 0 (eq. 1 not identified)"
            + (
                f"; the servo loop keeps duty_effort = {out['duty_effort']:.6g} {unit}"
                if "duty_effort" in out
                else ""
            )
        )
        out["max_effort"] = at_rest
        out["velocity_dependent_resistance"] = 0.0
        return out, tuple(notes)
    if resistance > 0.0 and math.isfinite(speed):
        zero = effort / resistance  # eq. 1 allows no effort beyond this speed
        if speed >= zero and at_rest >= effort:
            notes.append(
                f"max_actuator_velocity {speed:.6g} never binds: eq. 1 reaches zero effort at "
                f"{zero:.6g} (rad/s or m/s) first; reported as max_actuator_velocity = {zero:.6g} with "
                "speed_effort_gradient 0 (eq. 2 not identified)"
            )
            out["max_actuator_velocity"] = zero
            out["speed_effort_gradient"] = 0.0
    return out, tuple(notes)


def binding_lines(values: Mapping[str, float]) -> dict[str, bool]:
    """Whether eq. 1 and eq. 2 each form part of the region's boundary (after :func:`canonical_envelope`)."""
    effort = values["max_effort"]
    speed = values["max_actuator_velocity"]
    resistance = values["velocity_dependent_resistance"]
    gradient = values["speed_effort_gradient"]
    at_rest = speed / gradient if gradient > 0.0 and math.isfinite(speed) else math.inf
    eq1 = not (math.isfinite(at_rest) and effort > at_rest and effort - resistance * speed > 0.0)
    eq2 = math.isfinite(speed) and not (resistance > 0.0 and speed > effort / resistance and at_rest > effort)
    return {"eq1": eq1, "eq2": eq2}

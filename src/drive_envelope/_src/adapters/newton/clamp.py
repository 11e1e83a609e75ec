# mypy: disable-error-code="index"
# (Warp kernel bodies index wp.array values, which Warp's type stubs do not declare indexable)
"""``ClampingPerformanceEnvelope``: the PhysX envelope as a clamping stage of ``newton.actuators``.

Newton (``newton.actuators``) composes an actuator as delay -> drive -> clamping. A clamping stage
bounds the drive's effort in two places, and this one implements both with the envelope's effort
limit ``L(v) = max(min(max_effort - R|v|, (v_max - |v|)/G), 0)``:

* explicit mode, ``modify_forces``: ``clip(effort, -L(v), L(v))`` at the measured velocity;
* implicit mode (``Actuator.set_effort_mode_implicit``), ``evaluate_clamp``: the same clip at the
  solve's predicted END-of-step velocity. Newton's solve finds the impulse ``p`` with
  ``p = dt * clip(drive(v(p)), -L(v(p)), L(v(p)))``, ``v(p) = v + A p``; for a saturated request
  that fixed point is the boundary point PhysX's ``clampDriveImpulse`` returns (largest feasible
  effort along the request), and with zero feasible effort both give 0 (the drive lets go).

Only Newton's public API is used (``newton.actuators.ClampingBase``). Both modes evaluate the shared
Warp building block ``clamp_effort_func`` (``drive_envelope._src.kernels.warp_funcs``), float32 in
``modify_forces`` and float64 in ``evaluate_clamp``: one formula, one NaN rule. The class lives in
:mod:`~drive_envelope._src.adapters.newton.clamp_stage`, which imports Newton and Warp at its top;
this module (the argument rules) imports neither.

PhysX's PGS/TGS iteration (``drive_envelope.mujoco.set_solver``, issue 21) does not fit this API:
a clamping stage is one function of the velocity Newton's solve predicts for the whole step. It
sees neither the DOF's response ``(M^-1)_ii``, nor the other drives' impulses one by one (Newton
solves the actuators of a step together, not in a root-to-leaf sweep), nor a TGS substep's loads
and displacement, nor a velocity pass that re-clamps the step's total. So this stage keeps the
whole-step implicit solve, which is PhysX's PGS on an isolated DOF. The one-joint test stand runs
PhysX's PGS/TGS iteration without this API: its drive kernel
(:mod:`~drive_envelope._src.adapters.newton.physx_drive`) computes the effort before Newton's step
and hands it over as ``joint_f``.

Where it differs from Newton's ``ClampingDCMotor`` (``sat``, ``v_lim``, ``max_e``): with
``max_actuator_velocity = v_lim``, ``speed_effort_gradient = v_lim / sat``, ``R = 0`` the two agree
whenever effort and velocity have the same sign (driving quadrants) and at rest. When braking the
DC motor allows ``min(sat*(1 + |v|/v_lim), max_e)``, growing with speed up to the cap, while the
envelope allows ``L(|v|)``, shrinking with speed (PhysX's symmetric curves). Above ``v_lim`` the DC
motor forces a braking effort; the envelope allows none.
"""

from collections.abc import Mapping
from typing import Any

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.validation import nearest_key
from drive_envelope._src.values import read_envelope_value


def resolve_envelope_arguments(args: dict[str, Any]) -> dict[str, float]:
    """Validate one DOF's envelope arguments and fill the defaults (Newton's ``resolve_arguments``).

    Args:
        args: ``max_effort`` (required) [N*m or N], ``max_actuator_velocity`` (default inf)
            [rad/s or m/s], ``velocity_dependent_resistance`` (default 0) [N*m*s/rad or N*s/m],
            ``speed_effort_gradient`` (default 0) [(rad/s)/(N*m) or (m/s)/N]: SI numbers or strings
            with units.

    Returns:
        The four values as SI floats, keyed by the spec names.

    Raises:
        InputError: unknown key, missing ``max_effort``, wrong unit, negative, NaN, or infinite
            where not allowed.
    """
    where = "ClampingPerformanceEnvelope"
    if not isinstance(args, Mapping):
        raise InputError(
            f"{where}: args: expected a dict of envelope arguments ({', '.join(ENVELOPE_FIELDS)}), "
            f"got {type(args).__name__}"
        )
    for key in args:
        if key not in ENVELOPE_FIELDS:
            hint = nearest_key(str(key), ENVELOPE_FIELDS)
            raise InputError(
                f"{where}: unknown argument {key!r}{hint}; expected {', '.join(ENVELOPE_FIELDS)}"
            )
    if "max_effort" not in args:
        raise InputError(f"{where}: missing argument 'max_effort' (the drive's effort cap [N*m or N])")
    values = {
        field: read_envelope_value(args[field], field, f"{where}: {field}")
        for field in ENVELOPE_FIELDS
        if field in args
    }
    try:
        envelope = PerformanceEnvelope(**values)  # type: ignore[arg-type]
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    return {field: float(getattr(envelope, field)) for field in ENVELOPE_FIELDS}

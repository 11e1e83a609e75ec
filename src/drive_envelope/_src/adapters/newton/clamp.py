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
``modify_forces`` and float64 in ``evaluate_clamp``: one formula, one NaN rule. Newton and Warp are
imported in :func:`build`, so this module can be imported without them.

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

import functools
import math
from collections.abc import Mapping
from typing import Any

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import nearest_key, read_envelope_value

__all__ = ["build", "resolve_envelope_arguments"]


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


@functools.cache
def build() -> type:
    """Import Newton and Warp and define ``ClampingPerformanceEnvelope`` (once per process)."""
    import warp as wp
    from newton.actuators import ClampingBase

    from drive_envelope._src.kernels import warp_funcs

    # the shared building block, generic: float32 in modify_forces, float64 inside the implicit solve
    clamp_effort_func = warp_funcs.clamp_effort_func

    @wp.func
    def _evaluate_envelope_clamp(
        value: wp.float64,
        q: wp.float64,
        qd: wp.float64,
        params: wp.array2d[wp.float32],
        i: int,
        base: int,
    ) -> wp.float64:
        """Implicit-solve entry point; params row is ``[max_effort, v_max, R, G]``.

        ``qd`` is the predicted end-of-step velocity, so ``|effort| <= L(qd)`` holds at the end of
        the step: clip(value, -L(qd), L(qd)), L(v) = max(min(max_effort - R|v|, (v_max - |v|)/G), 0).
        The float32 parameters are widened to float64 (exactly) so that one generic function serves
        both stages: Warp's generic functions need one type per call, it does not promote.
        """
        return clamp_effort_func(
            wp.float64(params[i, base]),
            wp.float64(params[i, base + 1]),
            wp.float64(params[i, base + 2]),
            wp.float64(params[i, base + 3]),
            value,
            qd,
        )

    @wp.kernel(enable_backward=False)
    def _clamp_envelope_kernel(
        current_vel: wp.array[wp.float32],
        state_indices: wp.array[wp.uint32],
        max_effort: wp.array[wp.float32],
        max_actuator_velocity: wp.array[wp.float32],
        velocity_dependent_resistance: wp.array[wp.float32],
        speed_effort_gradient: wp.array[wp.float32],
        src: wp.array[wp.float32],
        dst: wp.array[wp.float32],
    ):
        """dst[i] = clip(src[i], -L_i(v), L_i(v)) at the measured velocity v of DOF i."""
        i = wp.tid()
        dst[i] = clamp_effort_func(
            max_effort[i],
            max_actuator_velocity[i],
            velocity_dependent_resistance[i],
            speed_effort_gradient[i],
            src[i],
            current_vel[state_indices[i]],
        )

    class ClampingPerformanceEnvelope(ClampingBase):  # type: ignore[misc,valid-type]
        """PhysX drive performance envelope as a Newton clamping stage (explicit and implicit modes).

        Bounds the drive's effort to ``L(v) = max(min(max_effort - R|v|, (v_max - |v|)/G), 0)``
        at the measured velocity (explicit mode) or at the predicted end-of-step velocity (implicit
        mode, PhysX's semantics). Usage with a model builder::

            builder.add_actuator(DrivePD, index=dof, kp=50.0, kd=2.0,
                                 clamping=[(ClampingPerformanceEnvelope, {"max_effort": 12.0,
                                            "max_actuator_velocity": 8.0, "speed_effort_gradient": 0.5})])
        """

        @classmethod
        def resolve_arguments(cls, args: dict[str, Any]) -> dict[str, Any]:
            """Validate scalar arguments (SI numbers or strings with units) and fill defaults."""
            return resolve_envelope_arguments(args)

        def __init__(
            self,
            max_effort: Any,
            max_actuator_velocity: Any = None,
            velocity_dependent_resistance: Any = None,
            speed_effort_gradient: Any = None,
        ) -> None:
            """Initialize from per-DOF float32 arrays of shape ``(N,)`` (shapes are checked, values not).

            Args:
                max_effort: Effort cap at zero velocity [N*m or N]. Shape ``(N,)``.
                max_actuator_velocity: Speed cap at zero effort [rad/s or m/s]; ``None``: inf.
                velocity_dependent_resistance: R [N*m*s/rad or N*s/m]; ``None``: 0.
                speed_effort_gradient: G [(rad/s)/(N*m) or (m/s)/N]; ``None``: 0.
            """
            for name, array in zip(
                ENVELOPE_FIELDS,
                (max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient),
                strict=True,
            ):
                if array is not None and not isinstance(array, wp.array):
                    raise InputError(
                        f"ClampingPerformanceEnvelope: {name}: expected a float32 wp.array of shape (N,) "
                        f"(pass scalars through builder.add_actuator), got {type(array).__name__}"
                    )
            n, device = max_effort.shape, max_effort.device
            if max_actuator_velocity is None:
                max_actuator_velocity = wp.full(n, math.inf, dtype=wp.float32, device=device)
            if velocity_dependent_resistance is None:
                velocity_dependent_resistance = wp.zeros(n, dtype=wp.float32, device=device)
            if speed_effort_gradient is None:
                speed_effort_gradient = wp.zeros(n, dtype=wp.float32, device=device)
            given = (max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient)
            for name, array in zip(ENVELOPE_FIELDS[1:], given, strict=True):
                if array.shape != n:
                    raise InputError(f"{name} shape {array.shape} must match max_effort shape {n}")
            self.max_effort = max_effort
            self.max_actuator_velocity = max_actuator_velocity
            self.velocity_dependent_resistance = velocity_dependent_resistance
            self.speed_effort_gradient = speed_effort_gradient

        evaluate_clamp = _evaluate_envelope_clamp  # type: ignore[assignment]  # a wp.Function at runtime

        def finalize(self, device: Any, num_actuators: int) -> None:
            """Check that the parameter arrays cover the actuator's DOFs."""
            if self.max_effort.shape[0] != num_actuators:
                count = self.max_effort.shape[0]
                raise InputError(f"ClampingPerformanceEnvelope: {count} DOFs, its actuator {num_actuators}")

        def param_width(self) -> int:
            """Columns in the packed parameter array: max_effort, v_max, R, G."""
            return 4

        def bind_params(self, block: Any) -> None:
            """Copy the parameters into the packed block and re-point the attributes at its columns."""
            for column, name in enumerate(ENVELOPE_FIELDS):
                block[:, column].assign(getattr(self, name))
                setattr(self, name, block[:, column])

        def modify_forces(
            self,
            src_forces: Any,
            dst_forces: Any,
            positions: Any,
            velocities: Any,
            pos_indices: Any,
            vel_indices: Any,
            device: Any = None,
        ) -> None:
            """Read effort from ``src_forces``, clamp it at the current velocity, write ``dst_forces``.

            Args:
                src_forces: Drive effort [N*m or N]. Shape ``(N,)``.
                dst_forces: Output effort [N*m or N] (may be ``src_forces``). Shape ``(N,)``.
                positions: Joint positions [rad or m] (unused).
                velocities: Joint velocities [rad/s or m/s], indexed by ``vel_indices``.
                pos_indices: Indices into ``positions`` (unused).
                vel_indices: Index of each DOF into ``velocities``.
                device: Warp device for the launch.
            """
            wp.launch(
                kernel=_clamp_envelope_kernel,
                dim=len(src_forces),
                inputs=[
                    velocities,
                    vel_indices,
                    self.max_effort,
                    self.max_actuator_velocity,
                    self.velocity_dependent_resistance,
                    self.speed_effort_gradient,
                    src_forces,
                ],
                outputs=[dst_forces],
                device=device,
            )

    ClampingPerformanceEnvelope.__module__ = "drive_envelope.newton"
    ClampingPerformanceEnvelope.__qualname__ = "ClampingPerformanceEnvelope"
    return ClampingPerformanceEnvelope

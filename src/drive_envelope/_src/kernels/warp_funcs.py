# mypy: disable-error-code="index"
# (Warp kernel bodies index wp.array values, which Warp's type stubs do not declare indexable)
"""Warp building blocks and kernels of the envelope, float32 with PhysX's float rules.

Everything Warp-specific is created on first use by :func:`build` (Warp is imported there, never at
module level, so importing this module stays free of it). The ``@wp.func`` building blocks are
meant to be called inside users' own kernels; the module-private ``_..._kernel`` kernels back the
launch wrappers of :mod:`drive_envelope.warp`.

PhysX rules kept on purpose (``physx/source/lowleveldynamics/shared/DyCpuGpuArticulation.h``):

* absolute epsilon ``2^-23`` on the denominators ``response -/+ gradient`` (below it a curve is
  ignored, or turns into a yes/no test),
* ``FLT_MAX`` sentinels for absent bounds,
* ``PxMax(a, b) = a > b ? a : b`` and ``PxMin(a, b) = a < b ? a : b`` (PhysX's float
  ``selectMax``/``selectMin``): which operand a NaN turns into follows from these selects, so they
  are reproduced with ``wp.where`` instead of ``wp.max``/``wp.min``.

This module deliberately has no ``from __future__ import annotations``: Warp reads the annotations
of functions defined inside :func:`build`, which only resolve while ``wp`` is a live local there.
"""

import functools
import types
from typing import Any

from drive_envelope._src.envelope.clamp import PX_EPS_F32, PX_MAX_F32

__all__ = ["build", "warp_module"]


@functools.cache
def build() -> types.SimpleNamespace:
    """Import Warp and define the building blocks and kernels (once per process).

    Returns:
        A namespace with the ``@wp.func`` building blocks (``effort_limit_func``,
        ``clamp_effort_func``, ``clamp_drive_impulse_func``, ``clamp_effort_implicit_func``) and the
        kernels (``effort_limit_kernel``, ``clamp_effort_kernel``, ``clamp_drive_impulse_kernel``,
        ``clamp_effort_implicit_kernel``).
    """
    import warp as wp

    eps = wp.constant(wp.float32(PX_EPS_F32))
    big = wp.constant(wp.float32(PX_MAX_F32))

    @wp.func
    def _px_max(a: wp.float32, b: wp.float32) -> wp.float32:
        """``PxMax(float)`` = ``intrinsics::selectMax``: ``a > b ? a : b`` (a NaN in ``b`` survives)."""
        return wp.where(a > b, a, b)

    @wp.func
    def _px_min(a: wp.float32, b: wp.float32) -> wp.float32:
        """``PxMin(float)`` = ``intrinsics::selectMin``: ``a < b ? a : b`` (a NaN in ``b`` survives)."""
        return wp.where(a < b, a, b)

    @wp.func
    def _np_min(a: wp.float32, b: wp.float32) -> wp.float32:
        """``numpy.minimum``: a NaN in either operand wins (the reference's explicit clamp)."""
        return wp.where((b < a) or (b != b), b, a)

    @wp.func
    def _np_max(a: wp.float32, b: wp.float32) -> wp.float32:
        """``numpy.maximum``: a NaN in either operand wins."""
        return wp.where((b > a) or (b != b), b, a)

    @wp.func
    def effort_limit_func(
        velocity: wp.float32,
        max_effort: wp.float32,
        max_actuator_velocity: wp.float32,
        velocity_dependent_resistance: wp.float32,
        speed_effort_gradient: wp.float32,
    ) -> wp.float32:
        """Largest |effort| [N*m or N] the envelope allows at ``velocity`` [rad/s or m/s].

        limit = max(min(max_effort - R*|v|, (v_max - |v|)/G), 0); with G = 0 the second term is
        replaced by the test |v| > v_max -> 0.
        """
        speed = wp.abs(velocity)
        limit = max_effort - velocity_dependent_resistance * speed
        if speed_effort_gradient > wp.float32(0.0):
            limit = _np_min(limit, (max_actuator_velocity - speed) / speed_effort_gradient)
        elif speed > max_actuator_velocity:
            limit = wp.float32(0.0)
        return _np_max(limit, wp.float32(0.0))

    @wp.func
    def clamp_effort_func(
        effort: wp.float32,
        velocity: wp.float32,
        max_effort: wp.float32,
        max_actuator_velocity: wp.float32,
        velocity_dependent_resistance: wp.float32,
        speed_effort_gradient: wp.float32,
    ) -> wp.float32:
        """Explicit clamp: ``clip(effort, -L(v), L(v))`` [N*m or N] at the current velocity v."""
        limit = effort_limit_func(
            velocity, max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient
        )
        return _np_min(_np_max(effort, -limit), limit)

    @wp.func
    def _bounds_positive(
        dev: wp.float32,
        max_v: wp.float32,
        denom1: wp.float32,
        denom2: wp.float32,
        impulse: wp.float32,
        denom_tol: wp.float32,
    ) -> wp.vec2:
        """``computeBoundsForPositiveImpulse``: feasible [lower, upper] for a positive request.

        ``denom_tol`` is PhysX's epsilon on the denominators (``eps*dt`` in effort units).
        """
        if wp.abs(denom2) < denom_tol:  # the curve is ignored
            return wp.vec2(-big, big)
        if wp.abs(denom1) < denom_tol:  # the lower curve is a yes/no test on (dev - max_v)
            flat = -big
            if not (wp.abs(dev - max_v) < eps) and (dev - max_v) > wp.float32(0.0):
                flat = big
            return wp.vec2(_px_max(wp.float32(0.0), flat), (dev + max_v) / denom2)
        bound1 = (dev - max_v) / denom1
        bound2 = (dev + max_v) / denom2
        if denom1 >= wp.float32(0.0):
            return wp.vec2(_px_max(wp.float32(0.0), bound1), _px_min(bound2, impulse))
        return wp.vec2(wp.float32(0.0), _px_min(_px_min(bound1, bound2), impulse))

    @wp.func
    def _bounds_negative(
        dev: wp.float32,
        max_v: wp.float32,
        denom1: wp.float32,
        denom2: wp.float32,
        impulse: wp.float32,
        denom_tol: wp.float32,
    ) -> wp.vec2:
        """``computeBoundsForNegativeImpulse``: feasible [lower, upper] for a negative or zero request."""
        if wp.abs(denom1) < denom_tol:
            return wp.vec2(-big, big)
        if wp.abs(denom2) < denom_tol:
            flat = big
            if not (wp.abs(dev + max_v) < eps) and not ((dev + max_v) > wp.float32(0.0)):
                flat = -big
            return wp.vec2((dev - max_v) / denom1, _px_min(wp.float32(0.0), flat))
        bound1 = (dev - max_v) / denom1
        bound2 = (dev + max_v) / denom2
        if denom2 >= wp.float32(0.0):
            return wp.vec2(_px_max(bound1, impulse), _px_min(wp.float32(0.0), bound2))
        return wp.vec2(_px_max(_px_max(bound1, bound2), impulse), wp.float32(0.0))

    @wp.func
    def _clamp_impulse(
        joint_vel0: wp.float32,
        drive_impulse0: wp.float32,
        drive_impulse: wp.float32,
        response: wp.float32,
        max_joint_vel: wp.float32,
        max_impulse: wp.float32,
        speed_impulse_gradient: wp.float32,
        velocity_dependent_resistance: wp.float32,
        denom_tol: wp.float32,
    ) -> wp.float32:
        """``clampDriveImpulse`` with the denominators' epsilon as an argument."""
        dev = drive_impulse0 * response - joint_vel0
        resist = velocity_dependent_resistance
        grad = speed_impulse_gradient
        b1 = wp.vec2()
        b2 = wp.vec2(-max_impulse, max_impulse)
        if drive_impulse > wp.float32(0.0):
            b1 = _bounds_positive(
                dev, max_joint_vel, response - grad, response + grad, drive_impulse, denom_tol
            )
            if resist != wp.float32(0.0):
                inv = wp.float32(1.0) / resist
                b2 = _bounds_positive(
                    dev, max_impulse / resist, response - inv, response + inv, drive_impulse, denom_tol
                )
        else:
            b1 = _bounds_negative(
                dev, max_joint_vel, response + grad, response - grad, drive_impulse, denom_tol
            )
            if resist != wp.float32(0.0):
                inv = wp.float32(1.0) / resist
                b2 = _bounds_negative(
                    dev, max_impulse / resist, response + inv, response - inv, drive_impulse, denom_tol
                )
        lower = _px_max(b1[0], b2[0])
        upper = _px_min(b1[1], b2[1])
        if lower > upper:
            return wp.float32(0.0)
        return _px_min(upper, _px_max(lower, drive_impulse))

    @wp.func
    def clamp_drive_impulse_func(
        joint_vel0: wp.float32,
        drive_impulse0: wp.float32,
        drive_impulse: wp.float32,
        response: wp.float32,
        max_joint_vel: wp.float32,
        max_impulse: wp.float32,
        speed_impulse_gradient: wp.float32,
        velocity_dependent_resistance: wp.float32,
    ) -> wp.float32:
        """PhysX ``clampDriveImpulse``: largest feasible total impulse [N*m*s or N*s] not above the request.

        Feasible: |v(x)| <= max_joint_vel - speed_impulse_gradient*|x| and
        |x| <= max_impulse - velocity_dependent_resistance*|v(x)|, v(x) = joint_vel0 + response*(x - x0);
        an empty set gives 0 (the drive lets go).
        """
        return _clamp_impulse(
            joint_vel0,
            drive_impulse0,
            drive_impulse,
            response,
            max_joint_vel,
            max_impulse,
            speed_impulse_gradient,
            velocity_dependent_resistance,
            eps,
        )

    @wp.func
    def clamp_effort_implicit_func(
        requested_effort: wp.float32,
        velocity: wp.float32,
        response: wp.float32,
        applied_effort: wp.float32,
        dt: wp.float32,
        max_effort: wp.float32,
        max_actuator_velocity: wp.float32,
        velocity_dependent_resistance: wp.float32,
        speed_effort_gradient: wp.float32,
    ) -> wp.float32:
        """Implicit clamp in effort units [N*m or N]: PhysX's impulse clamp with x = effort*dt.

        The clamp is invariant under scaling impulses by 1/dt, so it runs in effort units directly
        (response*dt per unit effort, max_effort, G, R, epsilon on the denominators times dt): the
        same result as clampDriveImpulse(v, e0*dt, e*dt, r, v_max, max_effort*dt, G/dt, R*dt)/dt
        up to float32 rounding, without its five scalings and two divisions.
        """
        return _clamp_impulse(
            velocity,
            applied_effort,
            requested_effort,
            response * dt,
            max_actuator_velocity,
            max_effort,
            speed_effort_gradient,
            velocity_dependent_resistance,
            eps * dt,
        )

    @wp.kernel(enable_backward=False)
    def _effort_limit_kernel(
        velocity: wp.array[wp.float32],
        max_effort: wp.array[wp.float32],
        max_actuator_velocity: wp.array[wp.float32],
        velocity_dependent_resistance: wp.array[wp.float32],
        speed_effort_gradient: wp.array[wp.float32],
        limit: wp.array[wp.float32],
    ):
        """limit[i] = effort_limit(velocity[i]) with DOF i's envelope."""
        i = wp.tid()
        limit[i] = effort_limit_func(
            velocity[i],
            max_effort[i],
            max_actuator_velocity[i],
            velocity_dependent_resistance[i],
            speed_effort_gradient[i],
        )

    @wp.kernel(enable_backward=False)
    def _clamp_effort_kernel(
        effort: wp.array[wp.float32],
        velocity: wp.array[wp.float32],
        max_effort: wp.array[wp.float32],
        max_actuator_velocity: wp.array[wp.float32],
        velocity_dependent_resistance: wp.array[wp.float32],
        speed_effort_gradient: wp.array[wp.float32],
        clamped: wp.array[wp.float32],
    ):
        """clamped[i] = clip(effort[i], -L_i(velocity[i]), L_i(velocity[i]))."""
        i = wp.tid()
        clamped[i] = clamp_effort_func(
            effort[i],
            velocity[i],
            max_effort[i],
            max_actuator_velocity[i],
            velocity_dependent_resistance[i],
            speed_effort_gradient[i],
        )

    @wp.kernel(enable_backward=False)
    def _clamp_drive_impulse_kernel(
        joint_vel0: wp.array[wp.float32],
        drive_impulse0: wp.array[wp.float32],
        drive_impulse: wp.array[wp.float32],
        response: wp.array[wp.float32],
        max_joint_vel: wp.array[wp.float32],
        max_impulse: wp.array[wp.float32],
        speed_impulse_gradient: wp.array[wp.float32],
        velocity_dependent_resistance: wp.array[wp.float32],
        clamped: wp.array[wp.float32],
    ):
        """clamped[i] = clampDriveImpulse(...) of DOF i, PhysX argument order."""
        i = wp.tid()
        clamped[i] = clamp_drive_impulse_func(
            joint_vel0[i],
            drive_impulse0[i],
            drive_impulse[i],
            response[i],
            max_joint_vel[i],
            max_impulse[i],
            speed_impulse_gradient[i],
            velocity_dependent_resistance[i],
        )

    @wp.kernel(enable_backward=False)
    def _clamp_effort_implicit_kernel(
        requested_effort: wp.array[wp.float32],
        velocity: wp.array[wp.float32],
        response: wp.array[wp.float32],
        applied_effort: wp.array[wp.float32],
        dt: wp.float32,
        max_effort: wp.array[wp.float32],
        max_actuator_velocity: wp.array[wp.float32],
        velocity_dependent_resistance: wp.array[wp.float32],
        speed_effort_gradient: wp.array[wp.float32],
        clamped: wp.array[wp.float32],
    ):
        """clamped[i] = clampDriveImpulse(effort*dt at the end-of-step velocity) / dt for DOF i."""
        i = wp.tid()
        clamped[i] = clamp_effort_implicit_func(
            requested_effort[i],
            velocity[i],
            response[i],
            applied_effort[i],
            dt,
            max_effort[i],
            max_actuator_velocity[i],
            velocity_dependent_resistance[i],
            speed_effort_gradient[i],
        )

    @wp.kernel(enable_backward=False)
    def _copy_kernel(src: wp.array[wp.float32], dst: wp.array[wp.float32]):
        """dst[i] = src[i]: the bandwidth baseline of the benchmarks."""
        i = wp.tid()
        dst[i] = src[i]

    return types.SimpleNamespace(
        effort_limit_func=effort_limit_func,
        clamp_effort_func=clamp_effort_func,
        clamp_drive_impulse_func=clamp_drive_impulse_func,
        clamp_effort_implicit_func=clamp_effort_implicit_func,
        effort_limit_kernel=_effort_limit_kernel,
        clamp_effort_kernel=_clamp_effort_kernel,
        clamp_drive_impulse_kernel=_clamp_drive_impulse_kernel,
        clamp_effort_implicit_kernel=_clamp_effort_implicit_kernel,
        copy_kernel=_copy_kernel,
    )


def warp_module() -> Any:
    """The ``warp`` module (imported on first use)."""
    import warp as wp

    return wp

# mypy: disable-error-code="index,valid-type"
# (Warp kernel bodies index wp.array values and annotate with Warp types, which mypy does not follow)
"""Warp building blocks and kernels of the envelope, with PhysX's float rules.

This module imports Warp at the top, as Newton's kernel modules do; only :mod:`drive_envelope.warp`
and the launch wrappers (:mod:`drive_envelope._src.kernels.warp_ops`) import it, lazily. The
``@wp.func`` building blocks are generic (``typing.Any`` arguments): one function serves
``wp.float32`` and ``wp.float64`` (all arguments of one call share the type); Warp compiles one
overload per type. The module-private ``_..._kernel`` kernels work on float32 arrays and back the
launch wrappers.

``clamp_drive_impulse_func`` is the port of PhysX's ``clampDriveImpulse``
(``physx/source/lowleveldynamics/shared/DyCpuGpuArticulation.h``) with the default guard of
:func:`drive_envelope.clamp_drive_impulse` (cap kept, never NaN; both request signs through the
positive branch, as in the NumPy core) or, with ``physx_exact=True``, the literal port of both
branches, PhysX's arithmetic bit for bit: absolute epsilon ``2^-23`` on the denominators
``response -/+ gradient``, ``FLT_MAX`` sentinels, ``PxMax(a, b) = a > b ? a : b`` and
``PxMin(a, b) = a < b ? a : b`` (which decide what a NaN turns into, hence ``wp.where`` and not
``wp.max``/``wp.min``).
"""

from typing import Any

import warp as wp

from drive_envelope._src.envelope.clamp import PX_EPS_F32, PX_MAX_F32

# no fused multiply-add: dev = x0*r - v0 must round twice, as in PhysX's CPU build and NumPy (NVRTC
# fuses by default). NaN tests are written x != x: Warp's isnan is a call on the CPU, ten times slower.
wp.set_module_options({"fuse_fp": False})

_EPS = wp.constant(PX_EPS_F32)
_FLT_MAX = wp.constant(PX_MAX_F32)
_INF = wp.constant(float("inf"))


@wp.func
def _px_max(a: Any, b: Any):
    """``PxMax(float)`` = ``intrinsics::selectMax``: ``a > b ? a : b`` (a NaN in ``b`` survives)."""
    return wp.where(a > b, a, b)


@wp.func
def _px_min(a: Any, b: Any):
    """``PxMin(float)`` = ``intrinsics::selectMin``: ``a < b ? a : b`` (a NaN in ``b`` survives)."""
    return wp.where(a < b, a, b)


@wp.func
def _max_nan(a: Any, b: Any):
    """``numpy.maximum``: the larger operand, NaN if either is NaN."""
    return wp.where(a != a, a, wp.where(a > b, a, b))


@wp.func
def _min_nan(a: Any, b: Any):
    """``numpy.minimum``: the smaller operand, NaN if either is NaN."""
    return wp.where(a != a, a, wp.where(a < b, a, b))


@wp.func
def effort_limit_func(
    max_effort: Any,
    max_actuator_velocity: Any,
    velocity_dependent_resistance: Any,
    speed_effort_gradient: Any,
    velocity: Any,
):
    """Largest |effort| [N*m or N] the envelope allows at ``velocity`` [rad/s or m/s].

    limit = max(min(max_effort - R*|v|, (v_max - |v|)/G), 0); with G = 0 the second term is
    replaced by the test |v| > v_max -> 0. A NaN velocity gives 0; an infinite one the limit at
    infinite speed: 0 when R > 0 or v_max is finite, else max_effort (no 0*inf, no inf - inf).
    """
    zero = type(velocity)(0.0)
    if velocity != velocity:  # NaN: the drive lets go
        return zero
    speed = wp.abs(velocity)
    if speed - speed != zero:  # infinite (x - x is NaN only for inf here; isinf is a call on the CPU)
        if velocity_dependent_resistance > zero or max_actuator_velocity - max_actuator_velocity == zero:
            return zero
        return max_effort
    limit = max_effort - velocity_dependent_resistance * speed
    if speed_effort_gradient > zero:
        limit = _min_nan(limit, (max_actuator_velocity - speed) / speed_effort_gradient)
    elif speed > max_actuator_velocity:
        limit = zero
    return _max_nan(limit, zero)


@wp.func
def clamp_effort_func(
    max_effort: Any,
    max_actuator_velocity: Any,
    velocity_dependent_resistance: Any,
    speed_effort_gradient: Any,
    effort: Any,
    velocity: Any,
):
    """Explicit clamp: ``clip(effort, -L(v), L(v))`` [N*m or N] at the current velocity v.

    A NaN effort or velocity gives 0 (the drive lets go), an infinite effort +-L(v), an infinite
    velocity the limit at infinite speed (:func:`effort_limit_func`): never NaN.
    """
    limit = effort_limit_func(
        max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient, velocity
    )
    if effort != effort:
        return type(limit)(0.0)
    return _min_nan(_max_nan(effort, type(limit)(-1.0) * limit), limit)


@wp.func
def _bounds_positive_physx(dev: Any, limit: Any, denom1: Any, denom2: Any, impulse: Any, tol: Any):
    """``computeBoundsForPositiveImpulse``: feasible (lower, upper) for a positive request.

    ``tol`` is PhysX's epsilon on the denominators (``2^-23``, times dt in effort units).
    """
    zero, eps, big = type(dev)(0.0), type(dev)(_EPS), type(dev)(_FLT_MAX)
    if wp.abs(denom2) < tol:  # the curve is ignored
        return -big, big
    if wp.abs(denom1) < tol:  # the lower curve is a yes/no test on (dev - limit)
        flat = -big
        if not (wp.abs(dev - limit) < eps) and (dev - limit) > zero:
            flat = big
        return _px_max(zero, flat), (dev + limit) / denom2
    bound1 = (dev - limit) / denom1
    bound2 = (dev + limit) / denom2
    if denom1 >= zero:
        return _px_max(zero, bound1), _px_min(bound2, impulse)
    return zero, _px_min(_px_min(bound1, bound2), impulse)


@wp.func
def _bounds_negative_physx(dev: Any, limit: Any, denom1: Any, denom2: Any, impulse: Any, tol: Any):
    """``computeBoundsForNegativeImpulse``: feasible (lower, upper) for a negative or zero request."""
    zero, eps, big = type(dev)(0.0), type(dev)(_EPS), type(dev)(_FLT_MAX)
    if wp.abs(denom1) < tol:
        return -big, big
    if wp.abs(denom2) < tol:
        flat = big
        if not (wp.abs(dev + limit) < eps) and not ((dev + limit) > zero):
            flat = -big
        return (dev - limit) / denom1, _px_min(zero, flat)
    bound1 = (dev - limit) / denom1
    bound2 = (dev + limit) / denom2
    if denom2 >= zero:
        return _px_max(bound1, impulse), _px_min(zero, bound2)
    return _px_max(_px_max(bound1, bound2), impulse), zero


@wp.func
def _quotient(a: Any, b: Any, denom: Any, split: bool):
    """(a + b) / denom; with ``split``, where a + b overflows although a and b are finite, a/denom + b/denom.

    PhysX's form turns a finite bound into an infinite one there (operands near the end of the
    float range) and the curve is lost. The tests are written without calls (x - x == 0: finite;
    inf - inf is NaN), as Warp's isinf and isfinite are calls on the CPU. ``split``, a literal at each
    call: else the compiler computes the split's two divisions for every bound, 40 % of the clamp.
    """
    total = a + b
    if split:
        if total - total != type(a)(0.0) and a - a == type(a)(0.0) and b - b == type(a)(0.0):
            return a / denom + b / denom
    return total / denom


@wp.func
def _bounds_positive(dev: Any, limit: Any, denom1: Any, denom2: Any, impulse: Any, tol: Any, split: bool):
    """The guarded ``computeBoundsForPositiveImpulse``: feasible (lower, upper) for a positive request.

    Absent bounds are inf, minima and maxima carry NaN, and a flat curve that says no gives a NaN
    lower bound (the caller then returns 0).
    """
    zero, eps = type(dev)(0.0), type(dev)(_EPS)
    if wp.abs(denom2) < tol:  # the curve is ignored
        return type(dev)(-_INF), type(dev)(_INF)
    if wp.abs(denom1) < tol:  # the lower curve is a yes/no test on (dev - limit); NaN answers no
        lower = type(dev)(wp.nan)
        if wp.abs(dev - limit) < eps or (dev - limit) <= zero:
            lower = zero
        return lower, _quotient(dev, limit, denom2, split)
    bound1 = _quotient(dev, type(limit)(-1.0) * limit, denom1, split)
    bound2 = _quotient(dev, limit, denom2, split)
    if denom1 >= zero:
        return _max_nan(zero, bound1), _min_nan(bound2, impulse)
    return zero, _min_nan(_min_nan(bound1, bound2), impulse)


@wp.func
def _clamp_impulse_physx(
    joint_vel0: Any,
    drive_impulse0: Any,
    drive_impulse: Any,
    response: Any,
    max_joint_vel: Any,
    max_impulse: Any,
    speed_impulse_gradient: Any,
    velocity_dependent_resistance: Any,
    tol: Any,
):
    """PhysX's ``clampDriveImpulse`` bit for bit, with the denominators' epsilon ``tol`` as an argument."""
    zero, one = type(joint_vel0)(0.0), type(joint_vel0)(1.0)
    dev = drive_impulse0 * response - joint_vel0
    resist = velocity_dependent_resistance
    grad = speed_impulse_gradient
    inv = one / resist  # used where resist != 0 only
    limit = max_impulse / resist
    lo1, hi1 = zero, zero
    lo2, hi2 = type(max_impulse)(-1.0) * max_impulse, max_impulse  # (Warp's -x is 0 - x: -0.0 lost)
    if drive_impulse > zero:
        lo1, hi1 = _bounds_positive_physx(
            dev, max_joint_vel, response - grad, response + grad, drive_impulse, tol
        )
        if resist != zero:
            lo2, hi2 = _bounds_positive_physx(dev, limit, response - inv, response + inv, drive_impulse, tol)
    else:
        lo1, hi1 = _bounds_negative_physx(
            dev, max_joint_vel, response + grad, response - grad, drive_impulse, tol
        )
        if resist != zero:
            lo2, hi2 = _bounds_negative_physx(dev, limit, response + inv, response - inv, drive_impulse, tol)
    lower = _px_max(lo1, lo2)
    upper = _px_min(hi1, hi2)
    if lower > upper:  # even zero effort is infeasible: the drive lets go
        return zero
    return _px_min(upper, _px_max(lower, drive_impulse))


@wp.func
def _clamp_core(
    dev: Any,
    request: Any,
    response: Any,
    max_joint_vel: Any,
    max_impulse: Any,
    grad: Any,
    inv: Any,
    limit: Any,
    plain: bool,
    tol: Any,
    split: bool,
):
    """:func:`_clamp_impulse` on sign-normalized inputs (``request >= 0``), eq. 1 left out if ``plain``."""
    zero = type(dev)(0.0)
    lo1, hi1 = _bounds_positive(dev, max_joint_vel, response - grad, response + grad, request, tol, split)
    lo2, hi2 = type(dev)(-_INF), type(dev)(_INF)
    if not plain:
        lo2, hi2 = _bounds_positive(dev, limit, response - inv, response + inv, request, tol, split)
    # |x| <= max_impulse bounds the interval (implied by eq. 1, kept through rounding)
    lower = _max_nan(_max_nan(lo1, lo2), type(max_impulse)(-1.0) * max_impulse)
    upper = _min_nan(_min_nan(hi1, hi2), max_impulse)
    clamped = _min_nan(upper, _max_nan(lower, request))
    if not (lower <= upper) or clamped != clamped:  # empty, or a NaN: the drive lets go
        return zero
    return clamped


@wp.func
def _clamp_impulse(
    joint_vel0: Any,
    drive_impulse0: Any,
    drive_impulse: Any,
    response: Any,
    max_joint_vel: Any,
    max_impulse: Any,
    speed_impulse_gradient: Any,
    velocity_dependent_resistance: Any,
    tol: Any,
):
    """The guarded ``clampDriveImpulse`` (the default): |result| <= max_impulse, no NaN.

    As in the NumPy core, both request signs take the positive branch on sign-normalized inputs
    (``dev`` and the request times ``s = +-1``, the result times ``s``): the negative branch's
    numbers, up to the sign of a zero. A zero or NaN request takes ``s = -1`` (both give 0). Only
    where ``dev -+ limit`` can overflow, both finite, do bounds take :func:`_quotient`'s split form.
    """
    zero, one = type(joint_vel0)(0.0), type(joint_vel0)(1.0)
    sign = wp.where(drive_impulse > zero, one, type(one)(-1.0))
    request = drive_impulse * sign
    dev = (drive_impulse0 * response - joint_vel0) * sign
    inv = one / velocity_dependent_resistance
    limit = max_impulse / velocity_dependent_resistance
    # a resistance whose 1/R or max_impulse/R overflows acts as R = 0 (inf - inf and NaN are not 0)
    plain = velocity_dependent_resistance == zero or (inv - inv) + (limit - limit) != zero
    reach = wp.where(dev - dev == zero, wp.abs(dev), zero) + wp.max(  # a non-finite operand: 0
        wp.where(max_joint_vel - max_joint_vel == zero, wp.abs(max_joint_vel), zero),
        wp.where(plain, zero, wp.abs(limit)),
    )
    g, v_max = speed_impulse_gradient, max_joint_vel
    if reach - reach != zero:
        return sign * _clamp_core(dev, request, response, v_max, max_impulse, g, inv, limit, plain, tol, True)
    return sign * _clamp_core(dev, request, response, v_max, max_impulse, g, inv, limit, plain, tol, False)


@wp.func
def clamp_drive_impulse_func(
    joint_vel0: Any,
    drive_impulse0: Any,
    drive_impulse: Any,
    response: Any,
    max_joint_vel: Any,
    max_impulse: Any,
    speed_impulse_gradient: Any,
    velocity_dependent_resistance: Any,
    physx_exact: bool = False,
):
    """PhysX ``clampDriveImpulse``: largest feasible total impulse [N*m*s or N*s] not above the request.

    Feasible: |v(x)| <= max_joint_vel - speed_impulse_gradient*|x| and
    |x| <= max_impulse - velocity_dependent_resistance*|v(x)|, v(x) = joint_vel0 + response*(x - x0);
    an empty set gives 0 (the drive lets go). Default: the cap kept and never NaN; ``physx_exact``:
    PhysX's arithmetic bit for bit.
    """
    tol = type(joint_vel0)(_EPS)
    if physx_exact:
        return _clamp_impulse_physx(
            joint_vel0,
            drive_impulse0,
            drive_impulse,
            response,
            max_joint_vel,
            max_impulse,
            speed_impulse_gradient,
            velocity_dependent_resistance,
            tol,
        )
    return _clamp_impulse(
        joint_vel0,
        drive_impulse0,
        drive_impulse,
        response,
        max_joint_vel,
        max_impulse,
        speed_impulse_gradient,
        velocity_dependent_resistance,
        tol,
    )


@wp.func
def clamp_effort_implicit_func(
    max_effort: Any,
    max_actuator_velocity: Any,
    velocity_dependent_resistance: Any,
    speed_effort_gradient: Any,
    requested_effort: Any,
    velocity: Any,
    response: Any,
    dt: Any,
    applied_effort: Any,
):
    """Implicit clamp in effort units [N*m or N]: PhysX's impulse clamp with x = effort*dt, guarded.

    The clamp is invariant under scaling impulses by 1/dt, so it runs in effort units directly
    (response*dt per unit effort, max_effort, G, R, epsilon on the denominators times dt): the
    same result as clampDriveImpulse(v, e0*dt, e*dt, r, v_max, max_effort*dt, G/dt, R*dt)/dt up to
    rounding, without its five scalings and two divisions; |result| <= max_effort always.
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
        type(dt)(_EPS) * dt,
    )


@wp.func
def implicit_drive_impulse(
    stiffness: wp.float64,
    damping: wp.float64,
    position_error: wp.float64,
    velocity: wp.float64,
    target_velocity: wp.float64,
    response: wp.float64,
    dt: wp.float64,
    acceleration: int,
):
    """Unclamped impulse [N*m*s or N*s] of PhysX's implicit PD drive (``ImplicitDriveEffort`` * dt).

    J = (dt*k*err + dt*c*vt - a*v) / (1 + a*r), a = dt*(dt*k + c), so that J = dt*k*(err - dt*v1)
    + dt*c*(vt - v1) at v1 = v + r*J; 0 when r <= 0 (a DOF that does not respond); an acceleration
    drive divides by (1 + a)*r instead (gains per unit inertia).
    """
    a = dt * (dt * stiffness + damping)
    rhs = dt * stiffness * position_error + dt * damping * target_velocity - a * velocity
    if acceleration != 0:
        return rhs / ((wp.float64(1.0) + a) * response)
    if response > wp.float64(0.0):
        return (wp.float64(1.0) / (wp.float64(1.0) + a * response)) * rhs
    return wp.float64(0.0)


@wp.func
def implicit_drive_params(
    stiffness: wp.float64,
    damping: wp.float64,
    position_error: wp.float64,
    target_velocity: wp.float64,
    response: wp.float64,
    span: wp.float64,
    dt: wp.float64,
    acceleration: int,
    tgs: int,
):
    """PhysX's ``computeImplicitDriveParams`` as the coefficients of ``computeDriveImpulse`` [SI].

    Over ``span`` (the step, or a TGS substep of the step ``dt``): ``a = span*(span*k + c)``,
    ``x = 1/(1 + a*r)`` (force drive) or ``1/(1 + a)`` with the gains times ``scale = 1/r``
    (acceleration drive), ``bias = k*x*scale*span``. Returns ``(constant, bias, velocity,
    accumulated, elapsed)`` such that the drive's request at joint velocity ``v`` with ``J``
    already applied, ``moved`` travelled and ``t`` elapsed in the step is
    ``J*accumulated + v*velocity + constant - moved*bias + t*elapsed`` [N*m*s or N*s], where
    ``constant = x*span*c*vt*scale + bias*(error - (dt - span)*vt)``, ``velocity = -x*a*scale``,
    ``accumulated = 1`` (TGS) or ``1 - x`` (PGS) and ``elapsed = bias*vt`` (TGS) or 0.
    """
    zero = wp.float64(0.0)
    one = wp.float64(1.0)
    a = span * (span * stiffness + damping)
    b = span * (damping * target_velocity)
    initial = position_error - (dt - span) * target_velocity
    x = zero
    scale = one
    if acceleration != 0:
        x = one / (one + a)
        scale = one / response
    elif response > zero:
        x = one / (one + a * response)
    bias = stiffness * x * scale * span
    accumulated = one - x
    elapsed = zero
    if tgs != 0:
        accumulated = one
        elapsed = bias * target_velocity
    return x * b * scale + bias * initial, bias, -x * a * scale, accumulated, elapsed


@wp.kernel(enable_backward=False)
def _effort_limit_kernel(
    max_effort: wp.array[wp.float32],
    max_actuator_velocity: wp.array[wp.float32],
    velocity_dependent_resistance: wp.array[wp.float32],
    speed_effort_gradient: wp.array[wp.float32],
    velocity: wp.array[wp.float32],
    limit: wp.array[wp.float32],
):
    """limit[i] = max(min(max_effort - R|v|, (v_max - |v|)/G), 0) with DOF i's envelope, v = velocity[i]."""
    i = wp.tid()
    limit[i] = effort_limit_func(
        max_effort[i],
        max_actuator_velocity[i],
        velocity_dependent_resistance[i],
        speed_effort_gradient[i],
        velocity[i],
    )


@wp.kernel(enable_backward=False)
def _clamp_effort_kernel(
    max_effort: wp.array[wp.float32],
    max_actuator_velocity: wp.array[wp.float32],
    velocity_dependent_resistance: wp.array[wp.float32],
    speed_effort_gradient: wp.array[wp.float32],
    effort: wp.array[wp.float32],
    velocity: wp.array[wp.float32],
    clamped: wp.array[wp.float32],
):
    """clamped[i] = clip(effort[i], -L_i(v), L_i(v)), v = velocity[i], L_i the effort limit of DOF i."""
    i = wp.tid()
    clamped[i] = clamp_effort_func(
        max_effort[i],
        max_actuator_velocity[i],
        velocity_dependent_resistance[i],
        speed_effort_gradient[i],
        effort[i],
        velocity[i],
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
    physx_exact: bool,
    clamped: wp.array[wp.float32],
):
    """clamped[i] = the largest x of drive_impulse[i]'s sign, |x| <= |drive_impulse[i]|, with v(x) feasible.

    Feasible: |v(x)| <= max_joint_vel - G|x| and |x| <= max_impulse - R|v(x)|,
    v(x) = joint_vel0 + response*(x - drive_impulse0); none gives 0 (the drive lets go).
    """
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
        physx_exact,
    )


@wp.kernel(enable_backward=False)
def _clamp_effort_implicit_kernel(
    max_effort: wp.array[wp.float32],
    max_actuator_velocity: wp.array[wp.float32],
    velocity_dependent_resistance: wp.array[wp.float32],
    speed_effort_gradient: wp.array[wp.float32],
    requested_effort: wp.array[wp.float32],
    velocity: wp.array[wp.float32],
    response: wp.array[wp.float32],
    applied_effort: wp.array[wp.float32],
    dt: wp.float32,
    clamped: wp.array[wp.float32],
):
    """clamped[i] = clampDriveImpulse(e*dt) / dt at the end-of-step velocity v + r*dt*(e - e0), DOF i."""
    i = wp.tid()
    clamped[i] = clamp_effort_implicit_func(
        max_effort[i],
        max_actuator_velocity[i],
        velocity_dependent_resistance[i],
        speed_effort_gradient[i],
        requested_effort[i],
        velocity[i],
        response[i],
        dt,
        applied_effort[i],
    )


@wp.kernel(enable_backward=False)
def _copy_kernel(src: wp.array[wp.float32], dst: wp.array[wp.float32]):
    """dst[i] = src[i]: the bandwidth baseline of the benchmarks."""
    i = wp.tid()
    dst[i] = src[i]

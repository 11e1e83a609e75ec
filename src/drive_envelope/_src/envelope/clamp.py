"""Clamping a drive's effort to the envelope: explicit, and implicit with PhysX's semantics.

:func:`clamp_drive_impulse` is a vectorized port of PhysX 5.6+ ``Dy::clampDriveImpulse``
(``physx/source/lowleveldynamics/shared/DyCpuGpuArticulation.h``): same argument order, same
bounds, same absolute epsilon ``2^-23`` (``PX_EPS_F32``) on the denominators. The implicit clamp
finds the largest total impulse ``x`` (same sign as the request, not above it) such that ``x`` and
the joint velocity after applying it, ``v(x) = v0 + r*(x - x0)``, satisfy::

    |v(x)| <= max_joint_vel - speed_impulse_gradient * |x|
    |x|    <= max_impulse - velocity_dependent_resistance * |v(x)|   (|x| <= max_impulse if R = 0)

and returns 0 when no such ``x`` exists (the drive lets go).

Two modes, one implementation:

* ``physx_exact=True`` reproduces PhysX's arithmetic bit for bit, flaws included: ``FLT_MAX``
  sentinels and PhysX's float ``PxMax(a, b) = a > b ? a : b`` / ``PxMin(a, b) = a < b ? a : b``
  selects (``intrinsics::selectMax``/``selectMin``), which decide what a NaN turns into. With
  ``dtype=numpy.float32`` it equals PhysX on every row of ``tests/golden`` (34,100 vectors).
* The default keeps the effort cap for every finite input. PhysX loses it in two places: a
  resistance whose reciprocal (or ``max_impulse/R``) overflows (``R*dt = 1e-310`` in float64
  gives 12.86 N*m against a cap of 10), and a resistance so large that ``r -+ 1/R`` rounds to
  ``r`` (float32, from ``R*dt*r`` of about 1e7). The default treats such a resistance as ``R = 0`` (the
  plain box, its ``R -> 0`` limit), intersects the feasible interval with ``|x| <= max_impulse``
  (implied by eq. 1 in exact arithmetic), uses ``inf`` instead of ``FLT_MAX`` for absent bounds,
  empties the interval when a flat curve's yes/no test says no (PhysX's ``FLT_MAX`` lower bound
  can return ``FLT_MAX`` instead), and lets the drive go (0) when a bound it uses or the request
  is NaN (PhysX's selects may drop a NaN bound and return the bare request). Everywhere else the
  two modes give the same numbers.

Sign symmetry: the negative-request branch of PhysX (``computeBoundsForNegativeImpulse``) mirrors
the positive one, and negation commutes exactly with ``PxMax``/``PxMin``
(``-PxMin(-a, -b) == PxMax(a, b)``, NaN and ties included). So both branches are evaluated as the
positive branch on sign-normalized inputs (``dev -> s*dev``, ``x -> s*x``, result times ``s``,
``s = +1`` for ``x > 0`` else ``-1``), with per-element selects by sign where PhysX's negative
branch is not the literal mirror: its falling-curve bound ``PxMax(PxMax(b1, b2), x)`` (the mirror
of ``PxMin(PxMin(b1, b2), x)`` with ``b1``, ``b2`` swapped), its flat-curve yes/no test on a NaN
gap, and its final ``PxMin(upper, PxMax(lower, x))`` (mirror: ``PxMax(lower, PxMin(upper, x))``;
the two orders pick the same value, NaN included, and differ only in the sign of a zero on a tie).
For the signs of zeros to follow too, the exact mode forms the normalized numerators as
``s*(dev -+ s*m)`` (``-dev - m`` is ``+0.0`` where PhysX's ``-(dev + m)`` is ``-0.0``) and mirrors
PhysX's literal 0 as ``-0.0``. The result is PhysX's bit for bit, NaN patterns included
(``tests/test_clamp_oracle.py`` holds the literal two-branch port and checks it on the whole float
range); the default mode leaves the sign of a zero result unspecified. Where no bound is NaN
(checked once per call), PhysX's selects are ``numpy.minimum``/``numpy.maximum``, which also return
their second operand on a tie.

Speed (``benchmarks/bench_kernels.py``, N = 1e6 float64, thread CPU time, 2-core EPYC): the
default mode takes 9-12x the time of ``np.clip`` on the same arrays (the issue's goal: 10x), since
a large clamp runs in blocks of ``_BLOCK`` elements that stay in the cache and one or two
reductions skip the per-element selects where every curve has one slope sign or no denominator is
near 0 (each remaining pass costs about a third of ``np.clip``); ``physx_exact=True`` 14-20x.
Selects on the request's sign are bit operations (``select``): ``numpy.where`` under a mask that
flips at random costs ten integer passes.

Why torch has its own port (``kernels/torch_ops.py``): it must not take these data-dependent
branches (host syncs, graph breaks), and the bit selects and ``out=`` buffers have no array-API
form. One branch-free array-API version gives the same numbers at 3.6x the NumPy core's time in
float64 and 4.1x in float32 and only ties the torch port (``benchmarks/bench_array_api_clamp.py``).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.bitselect import bits, int_mask, into, select, sign_bit_pattern
from drive_envelope._src.envelope.model import PerformanceEnvelope, require_envelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.validation import broadcast_shape, check_numbers, refuse_negative_response

PX_EPS_F32 = float(np.finfo(np.float32).eps)
"""PhysX's absolute epsilon for near-zero denominators, ``FLT_EPSILON = 2^-23``."""
PX_MAX_F32 = float(np.finfo(np.float32).max)
"""PhysX's sentinel for an absent bound, ``FLT_MAX``."""
CLAMP_DRIVE_IMPULSE_ARGS = (
    "joint_vel0",
    "drive_impulse0",
    "drive_impulse",
    "response",
    "max_joint_vel",
    "max_impulse",
    "speed_impulse_gradient",
    "velocity_dependent_resistance",
)
"""Argument names of :func:`clamp_drive_impulse`, in PhysX's order (every backend uses them)."""

Array = npt.NDArray[Any]


def clamp_effort(envelope: PerformanceEnvelope, effort: npt.ArrayLike, velocity: npt.ArrayLike) -> Array:
    """Limit ``effort`` to the envelope at the given (current) velocity: the explicit clamp.

    This is what a plain actuator model does each control step: the effort keeps its sign and its
    magnitude is capped at :meth:`PerformanceEnvelope.effort_limit` of ``velocity``. NaN and
    infinity follow the rule of every backend (``docs/kernels.md``): a NaN effort or velocity
    gives 0 (the drive lets go, as the implicit clamp does), an infinite effort the limit, an
    infinite velocity the limit at infinite speed.

    Args:
        envelope: The envelope (joint side, SI).
        effort: Requested effort [N*m or N]; broadcast with ``velocity``.
        velocity: Current joint velocity [rad/s or m/s].

    Returns:
        Clamped effort [N*m or N], float64, broadcast shape; never NaN.
    """
    envelope = require_envelope(envelope, "clamp_effort")
    check_numbers("clamp_effort", effort=effort, velocity=velocity)
    effort = np.asarray(effort, dtype=np.float64)
    shape = broadcast_shape("clamp_effort", ("effort", "velocity"), (effort.shape, np.shape(velocity)))
    limit = envelope.effort_limit(velocity)  # >= 0, never NaN
    clamped = np.minimum(effort, limit, out=np.empty(shape))
    # -L as 0 - L, not np.negative: where L = 0 the lower bound is +0.0, so a let-go (L = 0) gives
    # +0.0 whatever the effort's sign (np.maximum returns its second operand on a tie), as torch
    # and Warp do; where L > 0 it is -L exactly and an effort of -0.0 stays -0.0
    np.maximum(clamped, np.subtract(0.0, limit, out=limit), out=clamped)
    if np.isnan(np.min(clamped, initial=0.0)):  # a NaN effort (one read pass finds it): let go
        clamped[np.isnan(clamped)] = 0.0
    return clamped


def check_time_step(dt: object) -> float:
    """``dt`` as a float: a Python or NumPy number, finite and ``> 0`` [s] (every backend's rule).

    An array or a tensor is refused, not read: ``float()`` of a CUDA tensor would sync with the
    device, and the time step is one host number for the whole batch.
    """
    if not isinstance(dt, (int, float, np.integer, np.floating)):
        kind = f"{type(dt).__module__}.{type(dt).__name__}"
        raise InputError(f"dt: expected a Python float time step [s], got a {kind} {dt!r}; pass float(dt)")
    if isinstance(dt, bool) or not 0.0 < float(dt) < math.inf:
        raise InputError(f"dt: expected a time step > 0 and finite [s], got {dt!r}")
    return float(dt)


def clamp_effort_implicit(
    envelope: PerformanceEnvelope,
    requested_effort: npt.ArrayLike,
    velocity: npt.ArrayLike,
    response: npt.ArrayLike,
    dt: float,
    applied_effort: npt.ArrayLike = 0.0,
) -> Array:
    """Clamp a requested total effort with PhysX's implicit semantics (at the end-of-step velocity).

    The result ``e`` is the clamped TOTAL actuator effort such that ``e`` and the post-step velocity
    ``velocity + response*dt*(e - applied_effort)`` satisfy both envelope curves; it keeps the sign
    of the request, never exceeds it in magnitude nor ``max_effort``, and is 0 when even zero effort
    is infeasible or an input is NaN. It is :func:`clamp_drive_impulse` (default mode, the cap kept)
    on ``effort*dt``.

    Args:
        envelope: The envelope (joint side, SI).
        requested_effort: Requested total actuator effort for the step [N*m or N].
        velocity: Joint velocity that already contains ``applied_effort`` [rad/s or m/s].
        response: Joint velocity change per unit joint impulse, ``1/inertia`` for one DOF
            [rad/s/(N*m*s) or m/s/(N*s)], ``>= 0`` (a NaN lets the drive go).
        dt: Time step [s], ``> 0`` and finite.
        applied_effort: Total actuator effort already applied this step [N*m or N].

    Returns:
        Clamped total effort [N*m or N], float64, broadcast shape.

    Raises:
        InputError: ``dt`` not a finite number ``> 0``, or a negative ``response``.
    """
    envelope, step = require_envelope(envelope, "clamp_effort_implicit"), check_time_step(dt)
    numbers = dict(requested_effort=requested_effort, velocity=velocity, response=response)
    check_numbers("clamp_effort_implicit", **numbers, applied_effort=applied_effort)
    refuse_negative_response(response)
    r = np.asarray(response, dtype=np.float64)
    requested = np.asarray(requested_effort, dtype=np.float64)
    broadcast_shape(
        "clamp_effort_implicit",
        ("requested_effort", "velocity", "response", "applied_effort"),
        (requested.shape, np.shape(velocity), r.shape, np.shape(applied_effort)),
    )
    impulse = clamp_drive_impulse(
        velocity,
        np.asarray(applied_effort, dtype=np.float64) * step,
        requested * step,
        r,
        envelope.max_actuator_velocity,
        envelope.max_effort * step,
        envelope.speed_effort_gradient / step,
        envelope.velocity_dependent_resistance * step,
    )
    # (x*dt)/dt can round one ulp above x or max_effort: the clamp grows neither, nor may we
    magnitude = np.fmin(np.abs(impulse / step), np.abs(requested))  # fmin: a NaN request gives 0
    return np.copysign(np.minimum(magnitude, envelope.max_effort), impulse)


def clamp_drive_impulse(
    joint_vel0: npt.ArrayLike,
    drive_impulse0: npt.ArrayLike,
    drive_impulse: npt.ArrayLike,
    response: npt.ArrayLike,
    max_joint_vel: npt.ArrayLike,
    max_impulse: npt.ArrayLike,
    speed_impulse_gradient: npt.ArrayLike,
    velocity_dependent_resistance: npt.ArrayLike,
    *,
    dtype: npt.DTypeLike = np.float64,
    physx_exact: bool = False,
) -> Array:
    """PhysX ``clampDriveImpulse``, vectorized: clamp a total drive impulse to the envelope.

    Arguments follow PhysX's order and meaning; all broadcast together.

    Args:
        joint_vel0: Joint velocity before the new impulse, containing ``drive_impulse0``
            [rad/s or m/s].
        drive_impulse0: Total drive impulse applied so far this step [N*m*s or N*s].
        drive_impulse: Requested total drive impulse [N*m*s or N*s].
        response: Joint velocity change per unit impulse [rad/s/(N*m*s) or m/s/(N*s)].
        max_joint_vel: ``maxActuatorVelocity`` [rad/s or m/s] (``inf`` allowed).
        max_impulse: ``maxEffort * dt`` [N*m*s or N*s].
        speed_impulse_gradient: ``speedEffortGradient / dt`` [(rad/s)/(N*m*s) or (m/s)/(N*s)].
        velocity_dependent_resistance: ``velocityDependentResistance * dt`` [N*m*s/rad or N*s/m]
            (times seconds: impulse per unit speed); exactly 0 selects the plain ``|x| <= max_impulse``.
        dtype: ``numpy.float64`` (default) or ``numpy.float32`` to compute in PhysX's precision.
        physx_exact: Reproduce PhysX's arithmetic bit for bit, including where it loses the effort
            cap or returns NaN. The default keeps ``|result| <= max_impulse`` and never returns
            NaN (a NaN lets the drive go, 0); see the module docstring for the differences.

    Returns:
        The clamped total drive impulse [N*m*s or N*s], of ``dtype``, broadcast shape.
    """
    kind: np.dtype[Any] = np.dtype(dtype)
    values: tuple[npt.ArrayLike, ...] = (joint_vel0, drive_impulse0, drive_impulse, response)
    values += (max_joint_vel, max_impulse, speed_impulse_gradient, velocity_dependent_resistance)
    if not all(type(v) is np.ndarray and v.dtype.kind == "f" for v in values):  # a batch's own arrays pass
        check_numbers("clamp_drive_impulse", **dict(zip(CLAMP_DRIVE_IMPULSE_ARGS, values, strict=True)))
    if kind not in (np.float32, np.float64):
        raise ValueError(f"dtype must be numpy.float32 or numpy.float64, got {kind}")
    args = [np.asarray(a, dtype=kind) for a in values]
    shape = broadcast_shape("clamp_drive_impulse", CLAMP_DRIVE_IMPULSE_ARGS, [a.shape for a in args])
    # IEEE overflow, inf - inf and x/0 happen inside PhysX too and are part of what we reproduce
    with np.errstate(divide="ignore", over="ignore", invalid="ignore", under="ignore"):
        if math.prod(shape) >= 2 * _BLOCK:
            result = _clamp_blocks(args, shape, exact=bool(physx_exact))
        else:
            result = _clamp(*args, exact=bool(physx_exact))
    if result.shape != shape:  # an argument that no bound used still sets the shape
        result = np.array(np.broadcast_to(result, shape))
    return np.asarray(result, dtype=kind)  # a 0-d array, not a NumPy scalar, for scalar arguments


_BLOCK = 32768
"""Elements per block of a large clamp (``_clamp_blocks``).

The clamp is some fifty array passes; on a million DOFs each pass streams its operands through
memory, on blocks of this size they stay in the cache: 2.7x faster at N = 1e6 float64 (16 ms
against 44 ms, thread CPU time, 2-core EPYC). Smaller blocks pay the per-call overhead of the
passes (8192: 21 ms; 16384: 1.25x this size's time), larger ones leave a 512 KiB L2 cache (65536:
1.04-1.09x, 131072: 1.4x, 262144: 28 ms; interleaved, same process).
"""


def _clamp_blocks(args: list[Array], shape: tuple[int, ...], *, exact: bool) -> Array:
    """:func:`_clamp` over a large broadcast shape, in blocks of ``_BLOCK`` elements.

    Every element's result depends on that element's arguments only (the per-call checks, such
    as whether any bound is NaN, pick between formulas that agree wherever both apply), so the
    blocks give the same bits as one call.
    """
    flat: list[Array] = []
    for a in args:
        if a.size == 1:
            flat.append(a.reshape(()))  # a 0-d operand broadcasts in every block
        else:
            flat.append(np.broadcast_to(a, shape).reshape(-1))  # a view unless a is broadcast
    size = math.prod(shape)
    out = np.empty(size, dtype=args[0].dtype)
    for start in range(0, size, _BLOCK):
        block = slice(start, start + _BLOCK)
        target = out[block]
        part = _clamp(*(a if a.ndim == 0 else a[block] for a in flat), exact=exact, out=target)
        if part is not target:
            target[...] = part
    return out.reshape(shape)


def _pmax(a: Any, b: Any) -> Array:
    """``PxMax(float)``: ``a > b ? a : b`` (a NaN in ``b`` survives, a NaN in ``a`` does not).

    PhysX specializes ``PxMax`` for float to ``intrinsics::selectMax``, which differs from the generic
    template ``a < b ? b : a`` exactly when a NaN is involved.
    """
    return np.where(a > b, a, b)


def _pmin(a: Any, b: Any) -> Array:
    """``PxMin(float)``: ``a < b ? a : b`` (a NaN in ``b`` survives, a NaN in ``a`` does not)."""
    return np.where(a < b, a, b)


def _has_nan(*arrays: Any) -> bool:
    """Whether any of the arrays holds a NaN (one read pass each: a minimum propagates NaN)."""
    return any(bool(np.isnan(np.min(a, initial=np.inf))) for a in arrays)


class _Signs(NamedTuple):
    """Per-element sign data of the exact mode."""

    sign: Array
    """``-1`` where PhysX takes its negative branch (``x <= 0`` or NaN), else ``+1``."""
    negative: Array
    """Integer mask (:func:`int_mask`) of ``sign < 0``."""
    zero: Array
    """PhysX's literal ``0`` as the positive branch sees it after mirroring: ``-0.0`` where negative."""


def _bounds(
    num1: Array,
    num2: Any,
    denom1: Any,
    denom2: Any,
    request: Array,
    signs: _Signs | None,
    parts: tuple[Array, Any] | None = None,
) -> tuple[Array, Array, bool]:
    """``computeBoundsForPositiveImpulse`` on sign-normalized inputs: feasible ``[lower, upper]``.

    ``num1 = s*dev - limit`` and ``num2 = s*dev + limit`` are the normalized numerators (``limit``
    the curve's speed limit, ``max_joint_vel`` or ``max_impulse/R``), ``denom1 = r - k`` and
    ``denom2 = r + k`` with the curve's slope ``k``, ``request = s*x``. ``signs`` is given in exact
    mode only. The default mode leaves out each curve's ``PxMin(..., x)`` and the lower bound's
    ``PxMax(0, ...)`` (the caller applies both once) and marks a flat curve that says no with a NaN
    lower bound, which empties the interval.

    Returns:
        ``(lower, upper, nan_free)``; ``nan_free`` (exact mode) says that neither bound formula
        gave a NaN, so PhysX's selects are plain minima and maxima here (numpy's minimum and
        maximum also return the second operand on a tie, as PhysX's selects do, so even the sign
        of a zero bound follows).
    """
    real = num1.dtype.type
    eps, zero = real(PX_EPS_F32), real(0.0)
    bound1 = np.true_divide(num1, denom1)
    bound2 = into(np.true_divide, num2, denom2)
    if parts is not None:
        dev, limit = parts
        bound1 = _split_overflow(bound1, num1, dev, limit, denom1, negate=True)
        bound2 = _split_overflow(bound2, num2, dev, limit, denom2)
    if signs is None:
        nan_free = True
        # one slope sign for every element is the common case (a whole robot's drives on one side
        # of r = k): a reduction or two then replace the per-element selects (7 passes)
        low = np.min(denom1, initial=np.inf)
        # the maximum only where a slope is near or past r = k (a NaN minimum fails the test too);
        # _near_zero reuses both
        high = None if low >= eps else np.max(denom1, initial=-np.inf)
        if high is None or low >= zero:  # every curve rising
            upper, lower = bound2, bound1
        elif high < zero:  # every curve falling (a NaN denominator fails both tests)
            upper, lower = np.minimum(bound1, bound2), np.zeros((), dtype=real)
        else:
            rising = int_mask(np.greater_equal(denom1, zero), real)
            upper = select(rising, bound2, np.minimum(bound1, bound2), real)
            lower = into(np.bitwise_and, bits(bound1, real), rising).view(real)  # where(rising, b1, 0)
    else:
        rising = int_mask(np.greater_equal(denom1, zero), real)
        nan_free = not _has_nan(bound1, bound2, request)
        pmin = np.minimum if nan_free else _pmin
        # PxMax(0, bound1) (0 is never NaN, so numpy.maximum selects alike); falling: 0
        lower = np.maximum(signs.zero, select(rising, bound1, signs.zero, real))
        # PhysX's negative branch takes PxMax(PxMax(bound1, bound2), x): mirrored, b2 comes first
        swap = into(np.bitwise_and, np.bitwise_xor(bits(bound1, real), bits(bound2, real)), signs.negative)
        first = np.bitwise_xor(bits(bound1, real), swap).view(real)
        second = into(np.bitwise_xor, swap, bits(bound2, real)).view(real)
        upper = pmin(select(rising, bound2, pmin(first, second), real), request)
    flat = _near_zero(denom1, eps, None if signs is not None else (low, high))
    if flat is not None:  # denom1 ~ 0: the lower curve is a yes/no test on the gap num1
        near = np.abs(num1) < eps
        if signs is None:
            flat_lower = np.where(near | (num1 <= zero), zero, real(np.nan))
        else:  # PhysX's negative branch answers no on a NaN gap, its positive one yes
            negative = signs.negative != 0
            no = ~near & np.where(negative, ~(num1 < zero), num1 > zero)
            flat_lower = np.where(no, real(PX_MAX_F32), signs.zero)
        lower = np.where(flat, flat_lower, lower)
        upper = np.where(flat, bound2, upper)
    ignored = _near_zero(denom2, eps)
    if ignored is not None:  # the curve is ignored
        big = real(np.inf if signs is None else PX_MAX_F32)
        lower = np.where(ignored, -big, lower)
        upper = np.where(ignored, big, upper)
    return lower, upper, nan_free


def _near_zero(denom: Any, eps: Any, extremes: tuple[Any, Any | None] | None = None) -> Array | None:
    """The mask ``|denom| < eps``, or None where no element is that close to 0.

    Two reductions decide the common case (every denominator on one side, away from 0) without
    the three passes of the mask; a NaN fails both tests and takes the mask. ``extremes``: the
    ``(min, max)`` of ``denom`` already reduced (``max`` None where ``min >= eps`` made it moot).
    """
    low, high = extremes if extremes is not None else (np.min(denom, initial=np.inf), None)
    if low >= eps:
        return None
    if (np.max(denom, initial=-np.inf) if high is None else high) <= -eps:
        return None
    near = np.abs(denom) < eps
    return near if np.any(near) else None


def _split_overflow(bound: Array, num: Array, a: Array, b: Any, denom: Any, *, negate: bool = False) -> Array:
    """``(a -+ b) / denom``, as ``a/denom -+ b/denom`` where the numerator overflowed, ``a``, ``b`` finite.

    PhysX's form turns a finite bound into an infinite one there (operands near the end of the float
    range), which loses the curve; the split form does not. One reduction finds the common case
    (no infinity) cheaply. The same rule, in the same operations, is in every backend.
    """
    if np.isfinite(np.add.reduce(num, axis=None)):
        return bound
    over = np.isinf(num) & np.isfinite(a) & np.isfinite(b)
    if not np.any(over):
        return bound
    part = np.true_divide(b, denom)
    split = np.true_divide(a, denom) + (np.negative(part) if negate else part)
    return np.where(over, split, bound)


def _numerators(dev: Array, limit: Any, signs: _Signs | None) -> tuple[Array, Array]:
    """The normalized numerators ``s*dev -+ limit`` of a curve's two bounds.

    Exact mode: ``s*(dev -+ s*limit)``, the negated PhysX numerator bit for bit (``-dev - m`` would
    be ``+0.0`` where PhysX's ``-(dev + m)`` is ``-0.0``); the default mode gets ``dev`` already
    normalized.
    """
    if signs is None:
        return np.subtract(dev, limit), np.add(dev, limit)
    signed = np.multiply(limit, signs.sign)
    return (
        into(np.multiply, np.subtract(dev, signed), signs.sign),
        into(np.multiply, into(np.add, signed, dev), signs.sign),
    )


def _clamp(
    v0: Array,
    x0: Array,
    x: Array,
    r: Array,
    max_v: Array,
    max_x: Array,
    grad: Array,
    resist: Array,
    *,
    exact: bool,
    out: Array | None = None,
) -> Array:
    """The clamp on arrays of one dtype (broadcasting), both branches through the positive one.

    ``out``: where the default mode may write its result (it does where the shapes agree; the
    caller copies what is returned otherwise), saving the copy of a block.
    """
    real = x.dtype.type
    one, zero = real(1.0), real(0.0)
    dev = into(np.subtract, np.multiply(x0, r), v0)
    if exact:
        negative = int_mask(~(x > zero), real)
        sign = select(negative, -one, one, real)
        signed_zero = np.bitwise_and(negative, sign_bit_pattern(real)).view(real)  # -0.0 where negative
        signs: _Signs | None = _Signs(sign, negative, signed_zero)
        request = x * sign
    else:
        # s = copysign(1, x): a zero request may take either branch (both give 0), a NaN one gives 0.
        # Flipping the sign bit is the multiplication by s, exactly.
        signs = None
        sign_bit = np.bitwise_and(bits(x, real), sign_bit_pattern(real))
        request = np.bitwise_xor(bits(x, real), sign_bit).view(real)  # |x|
        dev = into(np.bitwise_xor, bits(dev, real), sign_bit).view(real)
    # eq. 2 (speed-effort line)
    parts1 = None if exact else (dev, max_v)
    lo1, hi1, clean1 = _bounds(*_numerators(dev, max_v, signs), r - grad, r + grad, request, signs, parts1)
    # eq. 1 (effort-speed line) written as |v| <= max_x/R - (1/R)|x|; R = 0 is the box |x| <= max_x
    if exact:
        plain = resist == zero
        safe = np.where(plain, one, resist)
        inv_r, limit_r = one / safe, max_x / safe
    else:
        # a resistance whose 1/R or max_x/R overflows acts as R = 0 (so does R = 0: 1/0 = inf)
        inv_r, limit_r = one / resist, max_x / resist
        plain = None
        if not np.isfinite(np.add.reduce(inv_r, axis=None) + np.add.reduce(limit_r, axis=None)):
            plain = ~(np.isfinite(inv_r) & np.isfinite(limit_r))
    parts2 = None if exact else (dev, limit_r)
    lo2, hi2, clean2 = _bounds(
        *_numerators(dev, limit_r, signs), r - inv_r, r + inv_r, request, signs, parts2
    )
    if signs is not None:
        lo2, hi2 = np.where(plain, -max_x, lo2), np.where(plain, max_x, hi2)
        # no NaN (a NaN max_x shows in the bounds): PhysX's selects are numpy's minima and maxima
        pmax, pmin = (np.maximum, np.minimum) if clean1 and clean2 else (_pmax, _pmin)
        lower, upper = pmax(lo1, lo2), pmin(hi1, hi2)
        # PxClamp(x, lower, upper) = PxMin(upper, PxMax(lower, x)), mirrored for negative requests
        # (the two orders differ only in the sign of a zero: a tie returns the second operand)
        mirrored = pmax(lower, pmin(upper, request))
        clamped = select(signs.negative, mirrored, pmin(upper, pmax(lower, request)), real)
        return np.where(lower > upper, zero, into(np.multiply, clamped, sign))
    if plain is not None and np.any(plain):
        lo2 = np.where(plain, real(-np.inf), lo2)
        hi2 = np.where(plain, real(np.inf), hi2)
    # |x| <= max_x holds inside eq. 1 exactly; as a bound it survives rounding (and R = 0 is it).
    # The floor also holds PhysX's PxMax(0, bound1) of both curves.
    # -max_x <= 0 unless a cap is negative (or NaN): then the floor is the element's own
    floor = zero if np.min(max_x, initial=np.inf) >= zero else np.maximum(np.negative(max_x), zero)
    lower = into(np.maximum, np.maximum(lo1, lo2), floor)
    upper = into(np.minimum, into(np.minimum, np.minimum(hi1, hi2), max_x), request)
    # lower <= min(upper, x) is PhysX's lower <= upper here; a NaN fails it and the drive lets go
    feasible = int_mask(lower <= upper, real)
    result = into(np.bitwise_xor, bits(upper, real), sign_bit)  # times s
    if out is not None and out.shape == np.broadcast_shapes(result.shape, feasible.shape):
        np.bitwise_and(result, feasible, out=out.view(result.dtype))  # where(feasible, ..., +0.0)
        return out
    return into(np.bitwise_and, result, feasible).view(real)

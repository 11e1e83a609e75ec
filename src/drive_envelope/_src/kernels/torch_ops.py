"""The envelope on PyTorch tensors: batched, device-agnostic, no Python loops over DOFs.

Every function imports ``torch`` on call. The effort-level ops take an :class:`EnvelopeTensors`
first and compute in its dtype on its device, and return that dtype; states may be tensors of that
dtype (another is refused, not cast), NumPy arrays or scalars (read in it) that broadcast with it
(e.g. ``(num_envs, num_joints)``). :func:`clamp_drive_impulse` has the core's
signature; its inputs land on the device of the first tensor given (the CPU when there is none).

:func:`clamp_drive_impulse` is the same port as the NumPy core (``envelope/clamp.py``): PhysX's
two request signs evaluated through the positive branch on sign-normalized inputs, with the same
two modes. ``physx_exact=True`` follows PhysX select for select (``PxMax(a, b) = a > b ? a : b``,
absolute epsilon ``2^-23``, ``FLT_MAX`` sentinels), so float32 tensors give PhysX's float32
numbers; the default keeps ``|result| <= max_impulse`` and never returns NaN. Unlike NumPy it has no
data-dependent branches (every patch is a ``torch.where``), so it runs without host syncs on CUDA
and ``torch.compile`` fuses it whole (:func:`fused_clamp_drive_impulse`). Why it is not one
array-API implementation shared with NumPy: measured in ``envelope/clamp.py``'s docstring.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from drive_envelope._src.envelope.clamp import (
    CLAMP_DRIVE_IMPULSE_ARGS,
    PX_EPS_F32,
    PX_MAX_F32,
    check_time_step,
)
from drive_envelope._src.kernels.torch_envelope import (
    EnvelopeTensors,
    broadcast_states,
    check_params,
    records_grad,
    resolve_dtype,
    state_tensors,
)
from drive_envelope._src.validation import broadcast_shape, refuse_negative_response

if TYPE_CHECKING:
    import torch


@functools.cache
def _zero(dtype: torch.dtype, device: torch.device) -> torch.Tensor:
    """A 0-d zero of ``dtype`` on ``device``, made once (a clamp bound without a per-call allocation)."""
    import torch

    with torch.inference_mode(False):
        return torch.zeros((), dtype=dtype, device=device)


def _pmax(a: torch.Tensor | float, b: torch.Tensor) -> torch.Tensor:
    """``PxMax(float)`` = ``selectMax``: ``a > b ? a : b`` (a NaN in ``b`` survives)."""
    import torch

    return torch.where(a > b, a, b)


def _pmin(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """``PxMin(float)`` = ``selectMin``: ``a < b ? a : b`` (a NaN in ``b`` survives)."""
    import torch

    return torch.where(a < b, a, b)


def _bounds(
    num1: torch.Tensor,
    num2: torch.Tensor,
    denom1: torch.Tensor,
    denom2: torch.Tensor,
    request: torch.Tensor,
    negative: torch.Tensor | None,
    zero: torch.Tensor | float,
    parts: tuple[torch.Tensor, torch.Tensor] | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """``computeBoundsForPositiveImpulse`` on sign-normalized inputs (see ``envelope/clamp.py``).

    ``num1``, ``num2`` are the normalized numerators ``s*dev -+ limit``; ``negative`` (exact mode
    only) marks PhysX's negative branch and ``zero`` is its literal 0 as mirrored (``-0.0`` there).
    ``parts = (s*dev, limit)`` in the default mode: a numerator that overflows although both parts
    are finite is divided part by part, as in every backend.
    """
    import torch

    bound1 = num1 / denom1
    bound2 = num2 / denom2
    if parts is not None:
        dev, limit = parts
        bound1 = _split_overflow(bound1, num1, dev, -limit, denom1)
        bound2 = _split_overflow(bound2, num2, dev, limit, denom2)
    rising = denom1 >= 0.0
    near = num1.abs() < PX_EPS_F32
    if negative is not None:
        lower = _pmax(zero, torch.where(rising, bound1, zero))  # PxMax(0, b1); falling: 0
        # PhysX's negative branch takes PxMax(PxMax(bound1, bound2), x): mirrored, b2 comes first
        first, second = torch.where(negative, bound2, bound1), torch.where(negative, bound1, bound2)
        upper = _pmin(torch.where(rising, bound2, _pmin(first, second)), request)
        # PhysX's negative branch answers no on a NaN gap, its positive one yes
        no = ~near & torch.where(negative, ~(num1 < 0.0), num1 > 0.0)
        flat_lower = torch.where(no, num1.new_tensor(PX_MAX_F32), zero)
        big = num1.new_tensor(PX_MAX_F32)
    else:
        lower = torch.where(rising, bound1, 0.0)
        upper = torch.where(rising, bound2, torch.minimum(bound1, bound2))
        flat_lower = torch.where(near | (num1 <= 0.0), 0.0, num1.new_tensor(math.nan))  # NaN: says no
        big = num1.new_tensor(math.inf)
    flat = denom1.abs() < PX_EPS_F32  # the lower curve is a yes/no test on the gap num1
    lower = torch.where(flat, flat_lower, lower)
    upper = torch.where(flat, bound2, upper)
    ignored = denom2.abs() < PX_EPS_F32  # the curve is ignored
    return torch.where(ignored, -big, lower), torch.where(ignored, big, upper)


def _split_overflow(
    bound: torch.Tensor, num: torch.Tensor, a: torch.Tensor, b: torch.Tensor, denom: torch.Tensor
) -> torch.Tensor:
    """``(a + b) / denom`` as ``a/denom + b/denom`` where ``a + b`` overflowed with ``a``, ``b`` finite."""
    import torch

    over = torch.isinf(num) & torch.isfinite(a) & torch.isfinite(b)
    return torch.where(over, a / denom + b / denom, bound)


def _clamp_drive_impulse_tensors(
    v0: torch.Tensor,
    x0: torch.Tensor,
    x: torch.Tensor,
    r: torch.Tensor,
    max_v: torch.Tensor,
    max_x: torch.Tensor,
    grad: torch.Tensor,
    resist: torch.Tensor,
    exact: bool = False,
) -> torch.Tensor:
    """The port proper, on tensors of one shape, dtype and device (what ``torch.compile`` fuses)."""
    import torch

    dev = x0 * r - v0
    if exact:
        is_negative = ~(x > 0.0)
        negative: torch.Tensor | None = is_negative
        sign = torch.where(is_negative, -1.0, torch.ones_like(x))
        zero: torch.Tensor | float = torch.where(is_negative, -0.0, torch.zeros_like(x))
        request = x * sign

        def numerators(limit: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            # s*(dev -+ s*limit): the negated PhysX numerator, the sign of a zero included
            signed = limit * sign
            return (dev - signed) * sign, (dev + signed) * sign

    else:  # a zero request may take either branch (both give 0); a NaN one gives 0 here
        negative, zero = None, 0.0
        sign = torch.copysign(torch.ones_like(x), x)
        request = x.abs()
        dev = dev * sign

        def numerators(limit: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            return dev - limit, dev + limit

    # eq. 2 (speed-effort line)
    lo1, hi1 = _bounds(
        *numerators(max_v), r - grad, r + grad, request, negative, zero, None if exact else (dev, max_v)
    )
    # eq. 1 (effort-speed line) as |v| <= max_x/R - (1/R)|x|; R = 0 is the plain box |x| <= max_x
    if exact:
        plain = resist == 0.0
        safe = torch.where(plain, torch.ones_like(resist), resist)
        inv_r, limit_r = 1.0 / safe, max_x / safe
    else:  # a resistance whose 1/R or max_x/R overflows acts as R = 0 (so does R = 0)
        inv_r, limit_r = 1.0 / resist, max_x / resist
        plain = ~(torch.isfinite(inv_r) & torch.isfinite(limit_r))
    lo2, hi2 = _bounds(
        *numerators(limit_r), r - inv_r, r + inv_r, request, negative, zero, None if exact else (dev, limit_r)
    )
    if negative is not None:
        lower = _pmax(lo1, torch.where(plain, -max_x, lo2))
        upper = _pmin(hi1, torch.where(plain, max_x, hi2))
        # PxClamp(x, lower, upper) = PxMin(upper, PxMax(lower, x)), mirrored for negative requests
        mirrored = _pmax(lower, _pmin(upper, request))
        clamped = torch.where(negative, mirrored, _pmin(upper, _pmax(lower, request))) * sign
        return torch.where(lower > upper, torch.zeros_like(clamped), clamped)  # empty: +0.0
    lo2 = torch.where(plain, -math.inf, lo2)
    hi2 = torch.where(plain, math.inf, hi2)
    # |x| <= max_x bounds the interval; the floor also holds PhysX's PxMax(0, bound1)
    floor = torch.clamp_min(-max_x, 0.0)
    lower = torch.maximum(torch.maximum(lo1, lo2), floor)
    upper = torch.minimum(torch.minimum(torch.minimum(hi1, hi2), max_x), request)
    # lower <= min(upper, x) is PhysX's lower <= upper here; a NaN fails it: the drive lets go
    return torch.where(lower <= upper, upper * sign, 0.0)


def _impulse_tensors(values: tuple[object, ...], dtype: Any, where: str) -> list[torch.Tensor]:
    """The arguments as tensors of one float dtype on the first tensor's device (the CPU if none), broadcast.

    A tensor already of that dtype and device is used as it is (no copy).
    """
    import torch

    kind = resolve_dtype(dtype, *values)
    device = next((v.device for v in values if isinstance(v, torch.Tensor)), torch.device("cpu"))
    tensors = [torch.as_tensor(v, dtype=kind, device=device) for v in values]
    # a user mistake, named as NumPy and Warp name it (torch's own error is a RuntimeError)
    broadcast_shape(where, CLAMP_DRIVE_IMPULSE_ARGS, [tuple(t.shape) for t in tensors])
    return list(torch.broadcast_tensors(*tensors))


def clamp_drive_impulse(
    joint_vel0: Any,
    drive_impulse0: Any,
    drive_impulse: Any,
    response: Any,
    max_joint_vel: Any,
    max_impulse: Any,
    speed_impulse_gradient: Any,
    velocity_dependent_resistance: Any,
    *,
    dtype: Any = None,
    physx_exact: bool = False,
) -> torch.Tensor:
    """PhysX ``clampDriveImpulse`` on tensors, the core's signature and argument order.

    See :func:`drive_envelope.clamp_drive_impulse` for the meaning of each argument and the modes.

    Args:
        joint_vel0: Joint velocity containing ``drive_impulse0`` [rad/s or m/s].
        drive_impulse0: Total drive impulse applied so far this step [N*m*s or N*s].
        drive_impulse: Requested total drive impulse [N*m*s or N*s].
        response: Joint velocity change per unit impulse [rad/s/(N*m*s) or m/s/(N*s)].
        max_joint_vel: ``maxActuatorVelocity`` [rad/s or m/s] (``inf`` allowed).
        max_impulse: ``maxEffort * dt`` [N*m*s or N*s].
        speed_impulse_gradient: ``speedEffortGradient / dt`` [(rad/s)/(N*m*s) or (m/s)/(N*s)].
        velocity_dependent_resistance: ``velocityDependentResistance * dt`` [N*m*s/rad or N*s/m].
        dtype: Float dtype to compute in (torch or NumPy); default: that of the first float tensor
            argument, else float32 (PhysX's precision).
        physx_exact: Reproduce PhysX's arithmetic bit for bit (default: the effort cap kept, no NaN).

    Returns:
        The clamped total impulse [N*m*s or N*s], a tensor of the broadcast shape on the device of
        the first tensor argument (``.numpy()`` / ``numpy.asarray`` read it on the CPU).
    """
    values = (
        joint_vel0,
        drive_impulse0,
        drive_impulse,
        response,
        max_joint_vel,
        max_impulse,
        speed_impulse_gradient,
        velocity_dependent_resistance,
    )
    v0, x0, x, r, max_v, max_x, grad, resist = _impulse_tensors(values, dtype, "clamp_drive_impulse")
    return _clamp_drive_impulse_tensors(v0, x0, x, r, max_v, max_x, grad, resist, exact=bool(physx_exact))


@functools.cache
def _compiled_port() -> Callable[..., torch.Tensor]:
    import torch

    return torch.compile(_clamp_drive_impulse_tensors)  # type: ignore[no-any-return]


def fused_clamp_drive_impulse(
    joint_vel0: Any,
    drive_impulse0: Any,
    drive_impulse: Any,
    response: Any,
    max_joint_vel: Any,
    max_impulse: Any,
    speed_impulse_gradient: Any,
    velocity_dependent_resistance: Any,
    *,
    dtype: Any = None,
    physx_exact: bool = False,
) -> torch.Tensor:
    """:func:`clamp_drive_impulse` fused into one kernel by ``torch.compile``: same arguments, same numbers.

    Eager PyTorch runs the port as about a hundred separate elementwise operations; Inductor fuses
    them into one loop (C++ on the CPU, Triton on CUDA), which is what makes the implicit clamp
    cheap at RL scale. The first call for a new dtype, device, rank or mode compiles (about a
    minute on two CPU cores; PyTorch caches the result on disk), so use it in long runs, not one-off
    calls. It needs what ``torch.compile`` needs (a C++ compiler for the CPU backend). The arguments,
    their units and the result are those of :func:`clamp_drive_impulse`.
    """
    values = (
        joint_vel0,
        drive_impulse0,
        drive_impulse,
        response,
        max_joint_vel,
        max_impulse,
        speed_impulse_gradient,
        velocity_dependent_resistance,
    )
    tensors = [t.contiguous() for t in _impulse_tensors(values, dtype, "fused_clamp_drive_impulse")]
    return _compiled_port()(*tensors, exact=bool(physx_exact))


def _limit_buffers(
    v: torch.Tensor, max_e: torch.Tensor, max_v: torch.Tensor, resist: torch.Tensor, grad: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """``(L, spare)``: the limit in ``[0, max_effort]`` or NaN (where ``v`` is, or it is 0), a free buffer.

    All arguments have one (broadcast) shape; both results are fresh buffers of it (no autograd).
    The terms ``max_effort - R*|v|`` and ``(v_max - |v|)/G`` are NaN where they do not bind: ``R = 0``
    at an infinite speed (``0*inf``), ``v_max = inf`` there (``inf - inf``), ``G = 0`` at
    ``|v| = v_max`` (``0/0``). A NaN term becomes ``+inf``, so the smaller of the others is the limit
    and an infinite velocity gives the limit at infinite speed; the NaN velocity alone is carried by
    ``clamp_max(|v|, 0)`` (0, or NaN where ``v`` is). ``torch.minimum`` rather than ``torch.fmin``,
    which is a scalar loop on the CPU (12x slower).
    """
    import torch

    speed = v.abs()  # fresh full-size buffers, reused in place: at RL scale these ops are memory-bound
    limit = torch.addcmul(max_e, resist, speed, value=-1.0)
    floor = speed.clamp_max(0.0)
    line = torch.sub(max_v, speed, out=speed).div_(grad)
    for term in (limit, line):
        term.nan_to_num_(nan=math.inf, posinf=math.inf, neginf=-math.inf)
    torch.minimum(limit, line, out=limit)
    return torch.clamp(limit, floor, max_e, out=limit), speed


def _limit_tracked(
    v: torch.Tensor, max_e: torch.Tensor, max_v: torch.Tensor, resist: torch.Tensor, grad: torch.Tensor
) -> torch.Tensor:
    """:func:`_limit_buffers`'s ``L``, the same numbers, out of place and with finite gradients.

    Each term is differentiated only where it binds at a finite velocity; beyond ``v_max`` with
    ``G = 0`` and at a NaN or infinite velocity the limit is a constant (the numbers of
    :func:`_limit_buffers`), so no ``0 * inf`` or NaN reaches a gradient.
    """
    import torch

    with torch.no_grad():
        plain, _ = _limit_buffers(*torch.broadcast_tensors(v, max_e, max_v, resist, grad))
    finite = torch.isfinite(v)
    speed = torch.where(finite, v, 0.0).abs()
    limit = torch.addcmul(max_e, resist, speed, value=-1.0)
    live = (grad > 0.0) & (max_v < math.inf)  # the speed line, where it can bind
    line = (torch.where(live, max_v, 0.0) - speed) / torch.where(live, grad, 1.0)
    limit = torch.where(live, torch.fmin(limit, line), limit).clamp_min(0.0)
    over = (grad == 0.0) & (speed > max_v)  # no gradient beyond the speed limit
    return torch.where(finite & ~over, limit, plain)


def effort_limit(params: EnvelopeTensors, velocity: Any) -> torch.Tensor:
    """Largest |effort| at ``velocity``: ``min(max_effort - R|v|, (v_max - |v|)/G)`` clipped at 0.

    ``G = 0`` drops the second term and gives 0 where ``|v| > v_max``, as the reference does. A NaN
    velocity gives 0; an infinite one the limit at infinite speed (0 when ``R > 0`` or ``v_max`` is
    finite, else ``max_effort``). Autograd works through it.

    Args:
        params: The envelope parameters (their dtype and device are the computation's).
        velocity: Joint velocity [rad/s or m/s], broadcast with the parameters; a tensor must have
            the parameters' dtype.

    Returns:
        The limit [N*m or N], broadcast shape, the parameters' dtype.
    """
    import torch

    params = check_params(params)
    (v,) = state_tensors(params, velocity=velocity)
    views = broadcast_states("effort_limit", params, velocity=v)
    if records_grad(params, v):
        return torch.nan_to_num(_limit_tracked(v, *params.as_tuple()), nan=0.0, posinf=math.inf)
    limit, _ = _limit_buffers(*views)
    return limit.nan_to_num_(nan=0.0, posinf=math.inf, neginf=-math.inf)


def clamp_effort(params: EnvelopeTensors, effort: Any, velocity: Any) -> torch.Tensor:
    """Explicit clamp: ``clip(effort, -L(v), L(v))`` with :func:`effort_limit` at the current velocity.

    A NaN effort or velocity gives 0 (the drive lets go), an infinite effort +-L(v), an infinite
    velocity the limit at infinite speed: the rule of every backend. Autograd works through it:
    d(result)/d(effort) is 1 inside ``[-L, L]``, 0 where clipped (1/2 on the bound itself, as
    ``torch.clamp`` has it) and 0 at a NaN, and the gradients are finite wherever the velocity is.
    When no tensor requires grad (or under ``torch.no_grad``/``inference_mode``) it runs in place on
    fresh buffers, without host syncs.

    Args:
        params: The envelope parameters.
        effort: Requested effort [N*m or N]; a tensor must have the parameters' dtype.
        velocity: Current joint velocity [rad/s or m/s]; the same.

    Returns:
        Clamped effort [N*m or N], broadcast shape, the parameters' dtype; never NaN.

    Raises:
        InputError: ``params`` not an :class:`EnvelopeTensors`, a tensor of another dtype, or
            shapes that do not broadcast.
    """
    import torch

    params = check_params(params)
    tau, v = state_tensors(params, effort=effort, velocity=velocity)
    tau_b, *views = broadcast_states("clamp_effort", params, effort=tau, velocity=v)
    if records_grad(params, tau, v):
        limit = _limit_tracked(v, *params.as_tuple())
        clamped = torch.clamp(tau, 0.0 - limit, limit)
        return torch.nan_to_num(clamped, nan=0.0, posinf=math.inf, neginf=-math.inf)
    limit, spare = _limit_buffers(*views)
    # -L as 0 - L: where L = 0 both bounds are +0.0, so a nonzero effort gives +0.0 there (torch.clamp
    # picks the sign of a zero tie by SIMD lane), as NumPy and Warp do
    lower = torch.sub(_zero(limit.dtype, limit.device), limit, out=spare)
    clamped = torch.clamp(tau_b, lower, limit, out=limit)  # NaN: effort or L
    return clamped.nan_to_num_(nan=0.0, posinf=math.inf, neginf=-math.inf)  # a NaN: the drive lets go


def clamp_effort_implicit(
    params: EnvelopeTensors,
    requested_effort: Any,
    velocity: Any,
    response: Any,
    dt: float,
    applied_effort: Any = 0.0,
) -> torch.Tensor:
    """PhysX's implicit clamp in effort units: :func:`clamp_drive_impulse` with ``x = effort*dt``.

    Guarded like the core: ``|result| <= max_effort`` and no NaN for every finite input.

    Args:
        params: The envelope parameters.
        requested_effort: Requested total actuator effort [N*m or N].
        velocity: Joint velocity that already contains ``applied_effort`` [rad/s or m/s].
        response: Joint velocity change per unit joint impulse [rad/s/(N*m*s) or m/s/(N*s)],
            ``>= 0``: a negative number or NumPy array is refused; a tensor is not read (that would
            sync with the device), a negative value in it gives the guarded result, as in Warp.
        dt: Time step [s], ``> 0``.
        applied_effort: Total actuator effort already applied this step [N*m or N].

    Tensors must have the parameters' dtype (see :func:`clamp_effort`).

    Returns:
        Clamped total effort [N*m or N], broadcast shape, the parameters' dtype.

    Raises:
        InputError: a bad ``dt``, ``params``, dtype or shape, or a negative ``response`` on the host.
    """
    import torch

    params = check_params(params)
    step = check_time_step(dt)
    refuse_negative_response(response, device_array=torch.Tensor)
    tau, v, r, applied = state_tensors(
        params,
        requested_effort=requested_effort,
        velocity=velocity,
        response=response,
        applied_effort=applied_effort,
    )
    broadcast_states(
        "clamp_effort_implicit", params, requested_effort=tau, velocity=v, response=r, applied_effort=applied
    )
    return implicit_effort_tensors(tau, v, applied, r, *params.as_tuple(), step)


def implicit_effort_tensors(
    tau: torch.Tensor,
    v: torch.Tensor,
    applied: torch.Tensor,
    r: torch.Tensor,
    max_e: torch.Tensor,
    max_v: torch.Tensor,
    resist: torch.Tensor,
    grad: torch.Tensor,
    step: float,
) -> torch.Tensor:
    """:func:`clamp_effort_implicit`'s arithmetic on checked tensors of one dtype (eager or compiled).

    The one place that turns the impulse port into efforts; ``torch_clip`` compiles it for the
    explicit actuators' end-of-step clip.
    """
    import torch

    impulse = _clamp_drive_impulse_tensors(
        *torch.broadcast_tensors(
            v, applied * step, tau * step, r, max_v, max_e * step, grad / step, resist * step
        )
    )
    # (x*dt)/dt can round one ulp above x or max_effort: the clamp grows neither
    magnitude = torch.minimum(torch.fmin((impulse / step).abs(), tau.abs()), max_e)  # a NaN request: 0
    return torch.copysign(magnitude, impulse)

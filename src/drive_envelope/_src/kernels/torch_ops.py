"""The envelope on PyTorch tensors: batched, device-agnostic, no Python loops over DOFs.

Every function imports ``torch`` on call. Inputs are tensors, NumPy arrays or scalars; they
broadcast together and land on the device of the first tensor given (the CPU when there is none).

:func:`clamp_drive_impulse` is the PhysX ``clampDriveImpulse`` port, select for select like the
NumPy reference (``PxMax(a, b) = a > b ? a : b``, absolute epsilon ``2^-23``, ``FLT_MAX``
sentinels), so float32 tensors give PhysX's float32 numbers.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from drive_envelope._src.envelope.clamp import PX_EPS_F32, PX_MAX_F32
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import torch

__all__ = [
    "clamp_drive_impulse",
    "clamp_effort",
    "clamp_effort_implicit",
    "effort_limit",
    "fused_clamp_drive_impulse",
    "resolve_dtype",
]


def resolve_dtype(dtype: Any, *values: object) -> torch.dtype:
    """The torch float dtype to compute in: ``dtype``, else that of the first float tensor, else float32.

    Args:
        dtype: ``None``, a torch float dtype, or a NumPy float dtype (``numpy.float32``/``float64``).
        values: The arguments, searched for a floating tensor when ``dtype`` is None.
    """
    import torch

    if dtype is None:
        for value in values:
            if isinstance(value, torch.Tensor) and value.is_floating_point():
                return value.dtype
        return torch.float32
    if isinstance(dtype, torch.dtype):
        if not dtype.is_floating_point:
            raise InputError(f"dtype: expected a float dtype, got {dtype}")
        return dtype
    try:
        name = np.dtype(dtype).name
    except TypeError:
        raise InputError(
            f"dtype: expected a float dtype (numpy.float32, torch.float64, ...), got {dtype!r}"
        ) from None
    mapping = {"float16": torch.float16, "float32": torch.float32, "float64": torch.float64}
    if name not in mapping:
        raise InputError(f"dtype: expected a float dtype (numpy.float32, torch.float64, ...), got {dtype!r}")
    return mapping[name]


def _device(values: tuple[object, ...]) -> torch.device:
    import torch

    for value in values:
        if isinstance(value, torch.Tensor):
            return value.device
    return torch.device("cpu")


def _tensors(values: tuple[object, ...], dtype: Any) -> list[torch.Tensor]:
    """All ``values`` as tensors of one float dtype on one device (no copy when they already are)."""
    import torch

    kind = resolve_dtype(dtype, *values)
    device = _device(values)
    return [torch.as_tensor(v, dtype=kind, device=device) for v in values]


def _pmax(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """``PxMax(float)`` = ``selectMax``: ``a > b ? a : b`` (a NaN in ``b`` survives)."""
    import torch

    return torch.where(a > b, a, b)


def _pmin(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """``PxMin(float)`` = ``selectMin``: ``a < b ? a : b`` (a NaN in ``b`` survives)."""
    import torch

    return torch.where(a < b, a, b)


def _bounds_positive(
    dev: torch.Tensor, max_v: torch.Tensor, denom1: torch.Tensor, denom2: torch.Tensor, impulse: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """``computeBoundsForPositiveImpulse``: feasible [lower, upper] for a positive request."""
    import torch

    big = torch.full_like(dev, PX_MAX_F32)
    zero = torch.zeros_like(dev)
    bound1 = (dev - max_v) / denom1
    bound2 = (dev + max_v) / denom2
    gap = dev - max_v
    # denom1 ~ 0: the lower curve is a yes/no test on (dev - max_v)
    flat_lower = torch.where(gap.abs() < PX_EPS_F32, -big, torch.where(gap > 0.0, big, -big))
    rising = denom1 >= 0.0
    lower = torch.where(rising, _pmax(zero, bound1), zero)
    upper = torch.where(rising, _pmin(bound2, impulse), _pmin(_pmin(bound1, bound2), impulse))
    flat = denom1.abs() < PX_EPS_F32
    lower = torch.where(flat, _pmax(zero, flat_lower), lower)
    upper = torch.where(flat, bound2, upper)
    ignored = denom2.abs() < PX_EPS_F32
    return torch.where(ignored, -big, lower), torch.where(ignored, big, upper)


def _bounds_negative(
    dev: torch.Tensor, max_v: torch.Tensor, denom1: torch.Tensor, denom2: torch.Tensor, impulse: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """``computeBoundsForNegativeImpulse``: feasible [lower, upper] for a negative or zero request."""
    import torch

    big = torch.full_like(dev, PX_MAX_F32)
    zero = torch.zeros_like(dev)
    bound1 = (dev - max_v) / denom1
    bound2 = (dev + max_v) / denom2
    gap = dev + max_v
    flat_upper = torch.where(gap.abs() < PX_EPS_F32, big, torch.where(gap > 0.0, big, -big))
    rising = denom2 >= 0.0
    lower = torch.where(rising, _pmax(bound1, impulse), _pmax(_pmax(bound1, bound2), impulse))
    upper = torch.where(rising, _pmin(zero, bound2), zero)
    flat = denom2.abs() < PX_EPS_F32
    lower = torch.where(flat, bound1, lower)
    upper = torch.where(flat, _pmin(zero, flat_upper), upper)
    ignored = denom1.abs() < PX_EPS_F32
    return torch.where(ignored, -big, lower), torch.where(ignored, big, upper)


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
) -> torch.Tensor:
    """PhysX ``clampDriveImpulse`` on tensors, the core's signature and argument order.

    See :func:`drive_envelope.clamp_drive_impulse` for the meaning of each argument.

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

    Returns:
        The clamped total impulse [N*m*s or N*s], a tensor of the broadcast shape on the device of
        the first tensor argument (``.numpy()`` / ``numpy.asarray`` read it on the CPU).
    """
    import torch

    tensors = _tensors(
        (
            joint_vel0,
            drive_impulse0,
            drive_impulse,
            response,
            max_joint_vel,
            max_impulse,
            speed_impulse_gradient,
            velocity_dependent_resistance,
        ),
        dtype,
    )
    return _clamp_drive_impulse_tensors(*torch.broadcast_tensors(*tensors))


def _clamp_drive_impulse_tensors(
    v0: torch.Tensor,
    x0: torch.Tensor,
    x: torch.Tensor,
    r: torch.Tensor,
    max_v: torch.Tensor,
    max_x: torch.Tensor,
    grad: torch.Tensor,
    resist: torch.Tensor,
) -> torch.Tensor:
    """The port proper, on tensors of one shape, dtype and device (what ``torch.compile`` fuses)."""
    import torch

    dev = x0 * r - v0
    positive = x > 0.0
    # eq. 2 (speed-effort line), per sign of the request
    pos_lo, pos_hi = _bounds_positive(dev, max_v, r - grad, r + grad, x)
    neg_lo, neg_hi = _bounds_negative(dev, max_v, r + grad, r - grad, x)
    lo1, hi1 = torch.where(positive, pos_lo, neg_lo), torch.where(positive, pos_hi, neg_hi)
    # eq. 1 (effort-speed line) as |v| <= max_x/R - (1/R)|x|; R = 0 is the plain box |x| <= max_x
    has_resistance = resist != 0.0
    safe = torch.where(has_resistance, resist, torch.ones_like(resist))
    inv_r, max_v_r = 1.0 / safe, max_x / safe
    pos_lo2, pos_hi2 = _bounds_positive(dev, max_v_r, r - inv_r, r + inv_r, x)
    neg_lo2, neg_hi2 = _bounds_negative(dev, max_v_r, r + inv_r, r - inv_r, x)
    lo2 = torch.where(has_resistance, torch.where(positive, pos_lo2, neg_lo2), -max_x)
    hi2 = torch.where(has_resistance, torch.where(positive, pos_hi2, neg_hi2), max_x)
    lower = _pmax(lo1, lo2)
    upper = _pmin(hi1, hi2)
    clamped = _pmin(upper, _pmax(lower, x))  # PxClamp(x, lower, upper)
    return torch.where(lower > upper, torch.zeros_like(x), clamped)


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
) -> torch.Tensor:
    """:func:`clamp_drive_impulse` fused into one kernel by ``torch.compile``: same arguments, same numbers.

    Eager PyTorch runs the port as about a hundred separate elementwise operations; Inductor fuses
    them into one loop (C++ on the CPU, Triton on CUDA), which is what makes the implicit clamp
    cheap at RL scale. The first call for a new dtype, device or rank compiles (about a minute on
    two CPU cores; PyTorch caches the result on disk), so use it in long runs, not one-off calls.
    It needs what ``torch.compile`` needs (a C++ compiler for the CPU backend).

    Args:
        joint_vel0: Joint velocity containing ``drive_impulse0`` [rad/s or m/s].
        drive_impulse0: Total drive impulse applied so far this step [N*m*s or N*s].
        drive_impulse: Requested total drive impulse [N*m*s or N*s].
        response: Joint velocity change per unit impulse [rad/s/(N*m*s) or m/s/(N*s)].
        max_joint_vel: ``maxActuatorVelocity`` [rad/s or m/s] (``inf`` allowed).
        max_impulse: ``maxEffort * dt`` [N*m*s or N*s].
        speed_impulse_gradient: ``speedEffortGradient / dt`` [(rad/s)/(N*m*s) or (m/s)/(N*s)].
        velocity_dependent_resistance: ``velocityDependentResistance * dt`` [N*m*s/rad or N*s/m].
        dtype: As in :func:`clamp_drive_impulse`.

    Returns:
        The clamped total impulse [N*m*s or N*s], as :func:`clamp_drive_impulse`.
    """
    import torch

    tensors = _tensors(
        (
            joint_vel0,
            drive_impulse0,
            drive_impulse,
            response,
            max_joint_vel,
            max_impulse,
            speed_impulse_gradient,
            velocity_dependent_resistance,
        ),
        dtype,
    )
    return _compiled_port()(*(t.contiguous() for t in torch.broadcast_tensors(*tensors)))


def effort_limit(
    velocity: Any,
    max_effort: Any,
    max_actuator_velocity: Any = math.inf,
    velocity_dependent_resistance: Any = 0.0,
    speed_effort_gradient: Any = 0.0,
    *,
    dtype: Any = None,
) -> torch.Tensor:
    """Largest |effort| at ``velocity``: ``min(max_effort - R|v|, (v_max - |v|)/G)`` clipped at 0.

    ``G = 0`` drops the second term and gives 0 where ``|v| > v_max`` (the division by zero gives
    ``-inf`` there and ``fmin`` skips the ``0/0`` NaN at ``|v| = v_max``), as the reference does.

    Args:
        velocity: Joint velocity [rad/s or m/s].
        max_effort: [N*m or N], per DOF or scalar.
        max_actuator_velocity: [rad/s or m/s] (``inf`` allowed).
        velocity_dependent_resistance: R [N*m*s/rad or N*s/m].
        speed_effort_gradient: G [(rad/s)/(N*m) or (m/s)/N].
        dtype: Float dtype; default as in :func:`clamp_drive_impulse`.

    Returns:
        The limit [N*m or N], broadcast shape.
    """
    import torch

    v, max_e, max_v, resist, grad = torch.broadcast_tensors(
        *_tensors(
            (
                velocity,
                max_effort,
                max_actuator_velocity,
                velocity_dependent_resistance,
                speed_effort_gradient,
            ),
            dtype,
        )
    )
    speed = v.abs()  # a fresh full-size buffer: the in-place ops below reuse it
    limit = torch.addcmul(max_e, resist, speed, value=-1.0)
    # in place where possible: at RL scale these ops are memory-bound and allocations cost as much
    speed_line = torch.sub(max_v, speed, out=speed).div_(grad)
    return torch.fmin(limit, speed_line, out=limit).clamp_min_(0.0)


def clamp_effort(
    effort: Any,
    velocity: Any,
    max_effort: Any,
    max_actuator_velocity: Any = math.inf,
    velocity_dependent_resistance: Any = 0.0,
    speed_effort_gradient: Any = 0.0,
    *,
    dtype: Any = None,
) -> torch.Tensor:
    """Explicit clamp: ``clip(effort, -L(v), L(v))`` with :func:`effort_limit` at the current velocity.

    Args:
        effort: Requested effort [N*m or N].
        velocity: Current joint velocity [rad/s or m/s].
        max_effort: [N*m or N], per DOF or scalar.
        max_actuator_velocity: [rad/s or m/s] (``inf`` allowed).
        velocity_dependent_resistance: R [N*m*s/rad or N*s/m].
        speed_effort_gradient: G [(rad/s)/(N*m) or (m/s)/N].
        dtype: Float dtype; default as in :func:`clamp_drive_impulse`.

    Returns:
        Clamped effort [N*m or N], broadcast shape.
    """
    import torch

    kind = resolve_dtype(dtype, effort, velocity, max_effort)
    device = _device((effort, velocity, max_effort))
    limit = effort_limit(
        velocity,
        max_effort,
        max_actuator_velocity,
        velocity_dependent_resistance,
        speed_effort_gradient,
        dtype=kind,
    )
    tau = torch.as_tensor(effort, dtype=kind, device=device)
    clamped = torch.minimum(tau, limit)  # minimum/maximum propagate NaN, like numpy.clip
    return torch.maximum(clamped, limit.neg_(), out=clamped)  # limit is a fresh buffer


def clamp_effort_implicit(
    requested_effort: Any,
    velocity: Any,
    response: Any,
    dt: float,
    max_effort: Any,
    max_actuator_velocity: Any = math.inf,
    velocity_dependent_resistance: Any = 0.0,
    speed_effort_gradient: Any = 0.0,
    *,
    applied_effort: Any = 0.0,
    dtype: Any = None,
) -> torch.Tensor:
    """PhysX's implicit clamp in effort units: :func:`clamp_drive_impulse` with ``x = effort*dt``.

    Args:
        requested_effort: Requested total actuator effort [N*m or N].
        velocity: Joint velocity that already contains ``applied_effort`` [rad/s or m/s].
        response: Joint velocity change per unit joint impulse [rad/s/(N*m*s) or m/s/(N*s)].
        dt: Time step [s], ``> 0``.
        max_effort: [N*m or N], per DOF or scalar.
        max_actuator_velocity: [rad/s or m/s] (``inf`` allowed).
        velocity_dependent_resistance: R [N*m*s/rad or N*s/m].
        speed_effort_gradient: G [(rad/s)/(N*m) or (m/s)/N].
        applied_effort: Total actuator effort already applied this step [N*m or N].
        dtype: Float dtype; default as in :func:`clamp_drive_impulse`.

    Returns:
        Clamped total effort [N*m or N], broadcast shape.
    """
    if (
        isinstance(dt, bool)
        or not isinstance(dt, (int, float, np.floating))
        or not 0.0 < float(dt) < math.inf
    ):
        raise InputError(f"dt: expected a time step > 0 and finite [s], got {dt!r}")
    step = float(dt)
    tau, v, r, applied, max_e, max_v, resist, grad = _tensors(
        (
            requested_effort,
            velocity,
            response,
            applied_effort,
            max_effort,
            max_actuator_velocity,
            velocity_dependent_resistance,
            speed_effort_gradient,
        ),
        dtype,
    )
    impulse = clamp_drive_impulse(
        v, applied * step, tau * step, r, max_v, max_e * step, grad / step, resist * step
    )
    return impulse / step

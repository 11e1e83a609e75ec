"""Launch wrappers of the Warp kernels over struct-of-arrays buffers (``N`` DOFs, per-DOF parameters).

Scalars are validated on the host before any array is built (:meth:`EnvelopeArrays.from_envelopes`,
:meth:`EnvelopeArrays.from_numpy`); an :class:`EnvelopeArrays` built from existing Warp arrays, and
every launch, check shapes, dtypes and devices only (Newton's validation contract: reading array
contents back would force a device-to-host copy).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.clamp import CLAMP_DRIVE_IMPULSE_ARGS
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.warp_funcs import build, warp_module

__all__ = [
    "EnvelopeArrays",
    "clamp_drive_impulse",
    "clamp_effort",
    "clamp_effort_implicit",
    "copy",
    "effort_limit",
]


def _is_warp_array(value: object) -> bool:
    return bool(isinstance(value, warp_module().array))


@dataclass(frozen=True, kw_only=True, slots=True)
class EnvelopeArrays:
    """Per-DOF envelope parameters of ``N`` DOFs as Warp float32 arrays of shape ``(N,)``, one device.

    Build it with :meth:`from_envelopes` or :meth:`from_numpy` (which validate the values); the
    constructor itself checks shapes, dtypes and devices only.
    """

    max_effort: Any
    """``maxEffort`` per DOF [N*m or N], ``wp.array(dtype=float32)`` of shape ``(N,)``."""
    max_actuator_velocity: Any
    """``maxActuatorVelocity`` per DOF [rad/s or m/s] (``inf``: no speed limit)."""
    velocity_dependent_resistance: Any
    """``velocityDependentResistance`` per DOF [N*m*s/rad or N*s/m]."""
    speed_effort_gradient: Any
    """``speedEffortGradient`` per DOF [(rad/s)/(N*m) or (m/s)/N]."""

    def __post_init__(self) -> None:
        wp = warp_module()
        arrays = [getattr(self, name) for name in ENVELOPE_FIELDS]
        for name, array in zip(ENVELOPE_FIELDS, arrays, strict=True):
            if not _is_warp_array(array) or array.dtype != wp.float32 or array.ndim != 1:
                raise InputError(f"EnvelopeArrays.{name}: expected a 1-D wp.array of float32, got {array!r}")
        if len({a.shape for a in arrays}) != 1:
            shapes = ", ".join(f"{n}={a.shape}" for n, a in zip(ENVELOPE_FIELDS, arrays, strict=True))
            raise InputError(f"EnvelopeArrays: shapes differ ({shapes}); expected one shape (N,)")
        if len({str(a.device) for a in arrays}) != 1:
            raise InputError("EnvelopeArrays: the four arrays are on different devices; expected one device")

    @property
    def count(self) -> int:
        """Number of DOFs ``N``."""
        return int(self.max_effort.shape[0])

    @property
    def device(self) -> Any:
        """The Warp device holding the arrays."""
        return self.max_effort.device

    @classmethod
    def from_envelopes(
        cls,
        envelopes: PerformanceEnvelope | Sequence[PerformanceEnvelope],
        *,
        count: int | None = None,
        device: Any = None,
    ) -> EnvelopeArrays:
        """Pack envelopes (already validated) into per-DOF arrays.

        Args:
            envelopes: One envelope per DOF, or a single envelope repeated ``count`` times.
            count: Number of DOFs when ``envelopes`` is a single envelope.
            device: Warp device (default: Warp's current device).
        """
        if isinstance(envelopes, PerformanceEnvelope):
            if count is None or count < 1:
                raise InputError(
                    f"count: expected a number of DOFs >= 1 for a single envelope, got {count!r}"
                )
            envelopes = [envelopes] * count
        values = {name: [getattr(env, name) for env in envelopes] for name in ENVELOPE_FIELDS}
        return cls._upload(values, device)

    @classmethod
    def from_numpy(
        cls,
        *,
        max_effort: npt.ArrayLike,
        max_actuator_velocity: npt.ArrayLike = math.inf,
        velocity_dependent_resistance: npt.ArrayLike = 0.0,
        speed_effort_gradient: npt.ArrayLike = 0.0,
        count: int | None = None,
        device: Any = None,
    ) -> EnvelopeArrays:
        """Validate per-DOF SI values (scalars broadcast) on the host, then upload them.

        Args:
            max_effort: [N*m or N], ``>= 0``, finite.
            max_actuator_velocity: [rad/s or m/s], ``>= 0`` (``inf`` allowed).
            velocity_dependent_resistance: [N*m*s/rad or N*s/m], ``>= 0``, finite.
            speed_effort_gradient: [(rad/s)/(N*m) or (m/s)/N], ``>= 0``, finite.
            count: Number of DOFs when every value is a scalar.
            device: Warp device (default: Warp's current device).

        Raises:
            InputError: a negative, NaN or (except ``max_actuator_velocity``) infinite value, or
                shapes that do not broadcast to ``(N,)``.
        """
        given = {
            "max_effort": max_effort,
            "max_actuator_velocity": max_actuator_velocity,
            "velocity_dependent_resistance": velocity_dependent_resistance,
            "speed_effort_gradient": speed_effort_gradient,
        }
        raw = {name: np.asarray(value, dtype=np.float64) for name, value in given.items()}
        try:
            shape = np.broadcast_shapes(*(a.shape for a in raw.values()), (count,) if count else ())
        except ValueError:
            shapes = ", ".join(f"{n}={a.shape}" for n, a in raw.items())
            raise InputError(f"EnvelopeArrays.from_numpy: shapes do not broadcast ({shapes})") from None
        if len(shape) != 1:
            raise InputError(
                f"EnvelopeArrays.from_numpy: expected per-DOF values of shape (N,), got shape {shape}"
            )
        for name, array in raw.items():
            bad = np.isnan(array) | (array < 0.0)
            if name != "max_actuator_velocity":
                bad |= np.isinf(array)
            if np.any(bad):
                value = array[bad].flat[0]
                expected = ">= 0" if name == "max_actuator_velocity" else ">= 0 and finite"
                raise InputError(f"EnvelopeArrays.from_numpy: {name} = {value!r}; expected {expected}")
        return cls._upload({n: np.broadcast_to(a, shape) for n, a in raw.items()}, device)

    @classmethod
    def _upload(cls, values: dict[str, Any], device: Any) -> EnvelopeArrays:
        wp = warp_module()
        arrays = {
            name: wp.array(np.ascontiguousarray(value, dtype=np.float32), dtype=wp.float32, device=device)
            for name, value in values.items()
        }
        return cls(**arrays)

    def as_inputs(self) -> list[Any]:
        """The four arrays in kernel order (``max_effort, max_actuator_velocity, R, G``)."""
        return [getattr(self, name) for name in ENVELOPE_FIELDS]


def _as_array(value: object, count: int, device: Any, where: str) -> Any:
    """A float32 Warp array of shape ``(count,)`` on ``device``: Warp arrays are checked, others uploaded."""
    wp = warp_module()
    if _is_warp_array(value):
        array: Any = value
        if array.dtype != wp.float32 or array.shape != (count,):
            raise InputError(f"{where}: expected a wp.array of float32 and shape ({count},), got {array!r}")
        if str(array.device) != str(device):
            raise InputError(f"{where}: array on {array.device}, expected device {device}")
        return array
    host = np.asarray(value, dtype=np.float32)
    try:
        host = np.broadcast_to(host.reshape(-1) if host.size == count else host, (count,))
    except ValueError:
        raise InputError(f"{where}: shape {host.shape} does not broadcast to ({count},)") from None
    return wp.array(np.ascontiguousarray(host), dtype=wp.float32, device=device)


def _output(out: Any, count: int, device: Any) -> Any:
    wp = warp_module()
    if out is None:
        return wp.empty(count, dtype=wp.float32, device=device)
    return _as_array(out, count, device, "out")


def effort_limit(params: EnvelopeArrays, velocity: Any, *, out: Any = None) -> Any:
    """Largest |effort| per DOF at ``velocity``: ``min(max_effort - R|v|, (v_max - |v|)/G)``, clipped at 0.

    Args:
        params: Per-DOF envelopes (``N`` DOFs).
        velocity: Joint velocity [rad/s or m/s], ``(N,)`` Warp array, NumPy array or scalar.
        out: Optional float32 ``(N,)`` Warp array to write into.

    Returns:
        The limit [N*m or N], float32 Warp array ``(N,)`` on ``params.device``.
    """
    wp, k = warp_module(), build()
    n, device = params.count, params.device
    result = _output(out, n, device)
    inputs = [_as_array(velocity, n, device, "velocity"), *params.as_inputs()]
    wp.launch(k.effort_limit_kernel, dim=n, inputs=inputs, outputs=[result], device=device)
    return result


def clamp_effort(params: EnvelopeArrays, effort: Any, velocity: Any, *, out: Any = None) -> Any:
    """Explicit clamp per DOF: ``clip(effort, -L(v), L(v))`` at the current velocity.

    Args:
        params: Per-DOF envelopes (``N`` DOFs).
        effort: Requested effort [N*m or N], ``(N,)`` Warp array, NumPy array or scalar.
        velocity: Current joint velocity [rad/s or m/s].
        out: Optional float32 ``(N,)`` Warp array to write into (may be ``effort`` itself).

    Returns:
        Clamped effort [N*m or N], float32 Warp array ``(N,)``.
    """
    wp, k = warp_module(), build()
    n, device = params.count, params.device
    result = _output(out, n, device)
    inputs = [
        _as_array(effort, n, device, "effort"),
        _as_array(velocity, n, device, "velocity"),
        *params.as_inputs(),
    ]
    wp.launch(k.clamp_effort_kernel, dim=n, inputs=inputs, outputs=[result], device=device)
    return result


def _check_dt(dt: float) -> float:
    if (
        isinstance(dt, bool)
        or not isinstance(dt, (int, float, np.floating))
        or not (0.0 < float(dt) < math.inf)
    ):
        raise InputError(f"dt: expected a time step > 0 and finite [s], got {dt!r}")
    return float(dt)


def clamp_effort_implicit(
    params: EnvelopeArrays,
    requested_effort: Any,
    velocity: Any,
    response: Any,
    dt: float,
    applied_effort: Any = 0.0,
    *,
    out: Any = None,
) -> Any:
    """PhysX's implicit clamp per DOF, in effort units (the batched core ``clamp_effort_implicit``).

    Args:
        params: Per-DOF envelopes (``N`` DOFs).
        requested_effort: Requested total actuator effort [N*m or N].
        velocity: Joint velocity that already contains ``applied_effort`` [rad/s or m/s].
        response: Joint velocity change per unit joint impulse [rad/s/(N*m*s) or m/s/(N*s)].
        dt: Time step [s], ``> 0``.
        applied_effort: Total actuator effort already applied this step [N*m or N].
        out: Optional float32 ``(N,)`` Warp array to write into.

    Returns:
        Clamped total effort [N*m or N], float32 Warp array ``(N,)``.
    """
    wp, k = warp_module(), build()
    step = _check_dt(dt)
    n, device = params.count, params.device
    result = _output(out, n, device)
    inputs = [
        _as_array(requested_effort, n, device, "requested_effort"),
        _as_array(velocity, n, device, "velocity"),
        _as_array(response, n, device, "response"),
        _as_array(applied_effort, n, device, "applied_effort"),
        step,
        *params.as_inputs(),
    ]
    wp.launch(k.clamp_effort_implicit_kernel, dim=n, inputs=inputs, outputs=[result], device=device)
    return result


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
    dtype: npt.DTypeLike = np.float32,
) -> Any:
    """PhysX ``clampDriveImpulse`` on Warp, the core's signature and argument order.

    Arguments are Warp float32 arrays (one device, one shape ``(N,)``), NumPy arrays or scalars;
    they broadcast together. The device is that of the Warp arrays given, else Warp's current
    device. See :func:`drive_envelope.clamp_drive_impulse` for the meaning and units.

    Args:
        joint_vel0: Joint velocity containing ``drive_impulse0`` [rad/s or m/s].
        drive_impulse0: Total drive impulse applied so far this step [N*m*s or N*s].
        drive_impulse: Requested total drive impulse [N*m*s or N*s].
        response: Joint velocity change per unit impulse [rad/s/(N*m*s) or m/s/(N*s)].
        max_joint_vel: ``maxActuatorVelocity`` [rad/s or m/s] (``inf`` allowed).
        max_impulse: ``maxEffort * dt`` [N*m*s or N*s].
        speed_impulse_gradient: ``speedEffortGradient / dt`` [(rad/s)/(N*m*s) or (m/s)/(N*s)].
        velocity_dependent_resistance: ``velocityDependentResistance * dt`` [N*m*s/rad or N*s/m].
        dtype: Only ``numpy.float32``: Warp computes in float32, as PhysX does.

    Returns:
        The clamped impulse [N*m*s or N*s]: a float32 Warp array of the broadcast shape, ``(1,)``
        when every argument is a scalar (``numpy.asarray`` or ``.numpy()`` reads it).
    """
    wp, k = warp_module(), build()
    if np.dtype(dtype) != np.float32:
        raise InputError(f"dtype: the Warp backend computes in float32 like PhysX, got {np.dtype(dtype)}")
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
    devices = {str(v.device): v.device for v in values if _is_warp_array(v)}
    if len(devices) > 1:
        raise InputError(f"clamp_drive_impulse: Warp arrays on several devices ({', '.join(devices)})")
    device = next(iter(devices.values())) if devices else wp.get_device()
    shapes = [tuple(v.shape) if _is_warp_array(v) else np.shape(v) for v in values]
    try:
        shape = np.broadcast_shapes(*shapes)
    except ValueError:
        listed = ", ".join(f"{n}={s}" for n, s in zip(CLAMP_DRIVE_IMPULSE_ARGS, shapes, strict=True))
        raise InputError(f"clamp_drive_impulse: shapes do not broadcast ({listed})") from None
    n = int(np.prod(shape, dtype=np.int64))
    inputs = [_as_array(v, n, device, name) for v, name in zip(values, CLAMP_DRIVE_IMPULSE_ARGS, strict=True)]
    result = wp.empty(n, dtype=wp.float32, device=device)
    if n:
        wp.launch(k.clamp_drive_impulse_kernel, dim=n, inputs=inputs, outputs=[result], device=device)
    # Warp has no 0-d arrays: all-scalar arguments give shape (1,)
    return result.reshape(shape) if len(shape) > 1 else result


def copy(src: Any, dst: Any) -> None:
    """``dst[:] = src`` with a one-line kernel: the bandwidth baseline of the benchmarks."""
    wp, k = warp_module(), build()
    wp.launch(k.copy_kernel, dim=src.shape[0], inputs=[src], outputs=[dst], device=src.device)

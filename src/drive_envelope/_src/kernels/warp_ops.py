"""Launch wrappers of the Warp kernels over struct-of-arrays buffers (``N`` DOFs, per-DOF parameters).

Scalars are validated on the host before any array is built (:meth:`EnvelopeArrays.from_envelopes`,
:meth:`EnvelopeArrays.from_values`); an :class:`EnvelopeArrays` built from existing Warp arrays, and
every launch, check shapes, dtypes and devices only (Newton's validation contract: reading array
contents back would force a device-to-host copy). The kernels live in
:mod:`drive_envelope._src.kernels.warp_funcs`, which imports Warp; this module imports it on first
use, so importing it stays free of Warp.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.clamp import CLAMP_DRIVE_IMPULSE_ARGS, check_time_step
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.envelope_values import envelope_columns, read_envelope_values
from drive_envelope._src.validation import broadcast_shape, refuse_negative_response


def _warp() -> ModuleType:
    """The ``warp`` module (imported on first use)."""
    import warp

    return warp


def _funcs() -> ModuleType:
    """The kernel module (imports Warp)."""
    from drive_envelope._src.kernels import warp_funcs

    return warp_funcs


def _is_warp_array(value: object) -> bool:
    return bool(isinstance(value, _warp().array))


@dataclass(frozen=True, kw_only=True, slots=True)
class EnvelopeArrays:
    """Per-DOF envelope parameters of ``N`` DOFs as Warp float32 arrays of shape ``(N,)``, one device.

    Build it with :meth:`from_envelopes` or :meth:`from_values` (which validate the values); the
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
        wp = _warp()
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
            count: Number of DOFs when ``envelopes`` is a single envelope (required then; 0 gives
                empty arrays, and every launch on them returns an empty result).
            device: Warp device (default: Warp's current device).
        """
        if isinstance(envelopes, PerformanceEnvelope) and count is None:
            raise InputError("EnvelopeArrays.from_envelopes: count: expected a number of DOFs >= 0, got None")
        return cls._upload(envelope_columns(envelopes, count, "EnvelopeArrays.from_envelopes"), device)

    @classmethod
    def from_values(
        cls,
        *,
        max_effort: Any,
        max_actuator_velocity: Any = math.inf,
        velocity_dependent_resistance: Any = 0.0,
        speed_effort_gradient: Any = 0.0,
        count: int | None = None,
        device: Any = None,
    ) -> EnvelopeArrays:
        """Validate per-DOF values (scalars broadcast) on the host, then upload them.

        Each value is an SI number, a sequence or NumPy array of them, or a string with units
        (``"inf"``, ``"300 rpm"``) read like every other user value.

        Args:
            max_effort: [N*m or N], ``>= 0``, finite.
            max_actuator_velocity: [rad/s or m/s], ``>= 0`` (``inf`` allowed).
            velocity_dependent_resistance: [N*m*s/rad or N*s/m], ``>= 0``, finite.
            speed_effort_gradient: [(rad/s)/(N*m) or (m/s)/N], ``>= 0``, finite.
            count: Number of DOFs when every value is a scalar (``>= 0``).
            device: Warp device (default: Warp's current device).

        Raises:
            InputError: a negative, NaN or (except ``max_actuator_velocity``) infinite value, a
                wrong unit, a bad ``count``, or shapes that do not broadcast to ``(N,)``.
        """
        where = "EnvelopeArrays.from_values"
        if count is not None and (isinstance(count, bool) or not isinstance(count, int) or count < 0):
            raise InputError(f"{where}: count: expected a number of DOFs >= 0, got {count!r}")
        given = (max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient)
        raw = read_envelope_values(dict(zip(ENVELOPE_FIELDS, given, strict=True)), where)
        try:
            shape = np.broadcast_shapes(*(a.shape for a in raw.values()), () if count is None else (count,))
        except ValueError:
            shapes = ", ".join(f"{n}={a.shape}" for n, a in raw.items())
            raise InputError(f"{where}: shapes do not broadcast ({shapes})") from None
        if len(shape) != 1:
            raise InputError(f"{where}: expected per-DOF values of shape (N,), got shape {shape}")
        return cls._upload({n: np.broadcast_to(a, shape) for n, a in raw.items()}, device)

    @classmethod
    def _upload(cls, values: dict[str, Any], device: Any) -> EnvelopeArrays:
        wp = _warp()
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
    wp = _warp()
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
    if out is None:
        wp = _warp()
        return wp.empty(count, dtype=wp.float32, device=device)
    if not _is_warp_array(out):
        # uploading it, as inputs are, would write the result into a copy: the caller's array
        # would keep its old values
        raise InputError(
            f"out: expected a float32 Warp array of shape ({count},) to write into, got a "
            f"{type(out).__module__}.{type(out).__name__}; pass a wp.array, or no out and use the result"
        )
    return _as_array(out, count, device, "out")


def _check_params(params: object) -> EnvelopeArrays:
    if not isinstance(params, EnvelopeArrays):
        raise InputError(f"params: expected an EnvelopeArrays, got {type(params).__name__}")
    return params


def _launch(kernel: Any, n: int, inputs: list[Any], result: Any, device: Any) -> None:
    """Launch ``kernel`` over ``n`` DOFs into ``result``; no launch at all for ``n = 0``."""
    if n:
        _warp().launch(kernel, dim=n, inputs=inputs, outputs=[result], device=device)


def _launch_per_dof(kernel: Any, params: object, out: Any, *scalars: Any, **states: Any) -> Any:
    """Launch ``kernel`` on ``params``, the per-DOF ``states`` (in order) and ``scalars``, into ``out``.

    The kernel's arguments are the four envelope arrays, the states, the scalars, the result.
    """
    params = _check_params(params)
    n, device = params.count, params.device
    result = _output(out, n, device)
    arrays = [_as_array(value, n, device, name) for name, value in states.items()]
    _launch(kernel, n, [*params.as_inputs(), *arrays, *scalars], result, device)
    return result


def effort_limit(params: EnvelopeArrays, velocity: Any, *, out: Any = None) -> Any:
    """Largest |effort| per DOF at ``velocity``: ``min(max_effort - R|v|, (v_max - |v|)/G)``, clipped at 0.

    Args:
        params: Per-DOF envelopes (``N`` DOFs).
        velocity: Joint velocity [rad/s or m/s], ``(N,)`` Warp array, NumPy array or scalar.
        out: Optional float32 ``(N,)`` Warp array to write into.

    Returns:
        The limit [N*m or N], float32 Warp array ``(N,)`` on ``params.device``: 0 at a NaN
        velocity, the limit at infinite speed at an infinite one (``docs/kernels.md``).
    """
    return _launch_per_dof(_funcs()._effort_limit_kernel, params, out, velocity=velocity)


def clamp_effort(params: EnvelopeArrays, effort: Any, velocity: Any, *, out: Any = None) -> Any:
    """Explicit clamp per DOF: ``clip(effort, -L(v), L(v))`` at the current velocity.

    Args:
        params: Per-DOF envelopes (``N`` DOFs).
        effort: Requested effort [N*m or N], ``(N,)`` Warp array, NumPy array or scalar.
        velocity: Current joint velocity [rad/s or m/s].
        out: Optional float32 ``(N,)`` Warp array to write into (may be ``effort`` itself).

    Returns:
        Clamped effort [N*m or N], float32 Warp array ``(N,)``; a NaN effort or velocity gives 0.
    """
    return _launch_per_dof(_funcs()._clamp_effort_kernel, params, out, effort=effort, velocity=velocity)


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

    Guarded like the core: ``|result| <= max_effort`` for every finite input, never NaN.

    Args:
        params: Per-DOF envelopes (``N`` DOFs).
        requested_effort: Requested total actuator effort [N*m or N].
        velocity: Joint velocity that already contains ``applied_effort`` [rad/s or m/s].
        response: Joint velocity change per unit joint impulse [rad/s/(N*m*s) or m/s/(N*s)],
            ``>= 0``: a negative value given on the host (a number, a NumPy array) is refused, one
            in a Warp array is not read (no device copy) and gives the guarded result.
        dt: Time step [s], ``> 0``.
        applied_effort: Total actuator effort already applied this step [N*m or N].
        out: Optional float32 ``(N,)`` Warp array to write into.

    Returns:
        Clamped total effort [N*m or N], float32 Warp array ``(N,)``.

    Raises:
        InputError: a bad ``dt``, shape, dtype or device, or a negative ``response`` on the host.
    """
    _check_params(params)  # before dt, as every backend checks them
    step = check_time_step(dt)
    refuse_negative_response(response, device_array=_warp().array)
    kernel = _funcs()._clamp_effort_implicit_kernel
    states = {"requested_effort": requested_effort, "velocity": velocity, "response": response}
    return _launch_per_dof(kernel, params, out, step, **states, applied_effort=applied_effort)


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
    physx_exact: bool = False,
) -> Any:
    """PhysX ``clampDriveImpulse`` on Warp, the core's signature and argument order.

    Arguments are Warp float32 arrays (one device, one shape ``(N,)``), NumPy arrays or scalars;
    they broadcast together. The device is that of the Warp arrays given, else Warp's current
    device. See :func:`drive_envelope.clamp_drive_impulse` for the meaning, the units and the two
    modes.

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
        physx_exact: Reproduce PhysX's arithmetic bit for bit (default: the effort cap kept).

    Returns:
        The clamped impulse [N*m*s or N*s]: a float32 Warp array of the broadcast shape, ``(1,)``
        when every argument is a scalar (``numpy.asarray`` or ``.numpy()`` reads it).
    """
    wp = _warp()
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
    shape = broadcast_shape("clamp_drive_impulse", CLAMP_DRIVE_IMPULSE_ARGS, shapes)
    n = int(np.prod(shape, dtype=np.int64))
    inputs = [_as_array(v, n, device, name) for v, name in zip(values, CLAMP_DRIVE_IMPULSE_ARGS, strict=True)]
    result = wp.empty(n, dtype=wp.float32, device=device)
    _launch(_funcs()._clamp_drive_impulse_kernel, n, [*inputs, bool(physx_exact)], result, device)
    # Warp has no 0-d arrays: all-scalar arguments give shape (1,)
    return result.reshape(shape) if len(shape) > 1 else result


def copy(src: Any, dst: Any) -> None:
    """``dst[:] = src`` with a one-line kernel: the bandwidth baseline of the benchmarks."""
    _warp().launch(_funcs()._copy_kernel, dim=src.shape[0], inputs=[src], outputs=[dst], device=src.device)

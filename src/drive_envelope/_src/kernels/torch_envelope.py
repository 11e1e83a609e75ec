"""``EnvelopeTensors``: the envelope parameters as four torch tensors, beside Warp's ``EnvelopeArrays``.

Values are validated on the host when built from envelopes or values; the constructor itself only
checks that the four are float tensors of one dtype and one device whose shapes broadcast (a
``(num_envs, num_joints)`` layout, a ``(1, num_joints)`` row, a ``(N,)`` column or 0-d scalars).
torch is imported on first use. The checks of the states the ops get live here too: a tensor must
have the parameters' dtype, shapes must broadcast; both read ``.dtype`` and ``.shape`` only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.envelope_values import envelope_columns, read_envelope_values

if TYPE_CHECKING:
    import torch


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
        name = ""  # not a dtype at all: the same message
    mapping = {"float16": torch.float16, "float32": torch.float32, "float64": torch.float64}
    if name not in mapping:
        raise InputError(f"dtype: expected a float dtype (numpy.float32, torch.float64, ...), got {dtype!r}")
    return mapping[name]


def _host(value: object) -> object:
    """A tensor's values as a NumPy array (validation reads them once, on the host); others as given.

    ``detach()`` first: the check reads values only, so it records nothing on the autograd graph.
    """
    import torch

    if isinstance(value, torch.Tensor):
        return value.detach().cpu().numpy()
    return value


@dataclass(frozen=True, kw_only=True, slots=True)
class EnvelopeTensors:
    """The four envelope parameters as torch tensors of one float dtype on one device.

    Shapes broadcast together and with the states the ops get, e.g. ``(num_envs, num_joints)`` or
    ``(1, num_joints)``. Build it with :meth:`from_envelopes` or :meth:`from_values`, which validate
    the values; the constructor checks dtypes, devices and shapes only.
    """

    max_effort: Any
    """``maxEffort`` [N*m or N], a float tensor."""
    max_actuator_velocity: Any
    """``maxActuatorVelocity`` [rad/s or m/s] (``inf``: no speed limit)."""
    velocity_dependent_resistance: Any
    """``velocityDependentResistance`` [N*m*s/rad or N*s/m]."""
    speed_effort_gradient: Any
    """``speedEffortGradient`` [(rad/s)/(N*m) or (m/s)/N]."""

    def __post_init__(self) -> None:
        import torch

        tensors = [getattr(self, name) for name in ENVELOPE_FIELDS]
        for name, tensor in zip(ENVELOPE_FIELDS, tensors, strict=True):
            if not isinstance(tensor, torch.Tensor) or not tensor.is_floating_point():
                raise InputError(f"EnvelopeTensors.{name}: expected a float torch.Tensor, got {tensor!r}")
        if len({t.dtype for t in tensors}) != 1 or len({t.device for t in tensors}) != 1:
            kinds = ", ".join(
                f"{n}={t.dtype} on {t.device}" for n, t in zip(ENVELOPE_FIELDS, tensors, strict=True)
            )
            raise InputError(f"EnvelopeTensors: expected one dtype and one device, got {kinds}")
        try:
            torch.broadcast_shapes(*(t.shape for t in tensors))
        except RuntimeError:
            shapes = ", ".join(f"{n}={tuple(t.shape)}" for n, t in zip(ENVELOPE_FIELDS, tensors, strict=True))
            raise InputError(f"EnvelopeTensors: shapes do not broadcast ({shapes})") from None

    @property
    def dtype(self) -> torch.dtype:
        """The float dtype of the four tensors."""
        return self.max_effort.dtype  # type: ignore[no-any-return]

    @property
    def device(self) -> torch.device:
        """The device of the four tensors."""
        return self.max_effort.device  # type: ignore[no-any-return]

    @property
    def shape(self) -> tuple[int, ...]:
        """The broadcast shape of the four tensors."""
        import torch

        return tuple(torch.broadcast_shapes(*(t.shape for t in self.as_tuple())))

    def as_tuple(self) -> tuple[Any, Any, Any, Any]:
        """``(max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient)``."""
        return (
            self.max_effort,
            self.max_actuator_velocity,
            self.velocity_dependent_resistance,
            self.speed_effort_gradient,
        )

    @classmethod
    def from_envelopes(
        cls,
        envelopes: PerformanceEnvelope | Sequence[PerformanceEnvelope],
        *,
        count: int | None = None,
        device: Any = "cpu",
        dtype: Any = None,
    ) -> EnvelopeTensors:
        """Pack envelopes (already validated) into tensors.

        Args:
            envelopes: One envelope per DOF (tensors of shape ``(N,)``), or a single envelope: 0-d
                tensors that broadcast against any state, or ``(count,)`` when ``count`` is given.
            count: Number of DOFs for a single envelope, ``>= 0`` (0: an empty batch).
            device: Torch device.
            dtype: Float dtype (torch or NumPy; default float32): the ops compute in it, return it
                and refuse state tensors of any other dtype.
        """
        return cls._build(envelope_columns(envelopes, count, "EnvelopeTensors.from_envelopes"), device, dtype)

    @classmethod
    def from_values(
        cls,
        *,
        max_effort: Any,
        max_actuator_velocity: Any = math.inf,
        velocity_dependent_resistance: Any = 0.0,
        speed_effort_gradient: Any = 0.0,
        device: Any = "cpu",
        dtype: Any = None,
    ) -> EnvelopeTensors:
        """Validate values of any shapes that broadcast together, then build the tensors.

        Each value is an SI number, a sequence, NumPy array or tensor of them (a tensor is read back
        once to be checked), or a string with units (``"inf"``, ``"300 rpm"``). A float tensor is
        kept, not copied: already of ``dtype`` on ``device``, it is the field itself (``is`` the
        tensor given, its autograd graph included); else it is moved with ``Tensor.to``, which
        autograd records, so gradients reach the tensor given either way.

        Args:
            max_effort: [N*m or N], ``>= 0``, finite.
            max_actuator_velocity: [rad/s or m/s], ``>= 0`` (``inf`` allowed).
            velocity_dependent_resistance: [N*m*s/rad or N*s/m], ``>= 0``, finite.
            speed_effort_gradient: [(rad/s)/(N*m) or (m/s)/N], ``>= 0``, finite.
            device: Torch device.
            dtype: Float dtype (torch or NumPy; default float32).

        Raises:
            InputError: a negative, NaN or (except ``max_actuator_velocity``) infinite value, a
                wrong unit, or shapes that do not broadcast.
        """
        fields = (max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient)
        given = dict(zip(ENVELOPE_FIELDS, fields, strict=True))
        where = "EnvelopeTensors.from_values"
        values = read_envelope_values({n: _host(v) for n, v in given.items()}, where)
        try:
            np.broadcast_shapes(*(a.shape for a in values.values()))
        except ValueError:
            shapes = ", ".join(f"{n}={a.shape}" for n, a in values.items())
            raise InputError(f"{where}: shapes do not broadcast ({shapes})") from None
        return cls._build(values, device, dtype, given)

    @classmethod
    def _build(
        cls, values: dict[str, Any], device: Any, dtype: Any, given: dict[str, Any] | None = None
    ) -> EnvelopeTensors:
        """The tensors of the validated ``values``; a float tensor in ``given`` is used itself."""
        import torch

        kind = resolve_dtype(dtype)
        target = torch.device(device)
        tensors = {}
        for name, array in values.items():
            value = None if given is None else given[name]
            if isinstance(value, torch.Tensor) and value.is_floating_point():
                tensors[name] = value.to(dtype=kind, device=target)  # itself when already so: graph kept
            else:
                tensors[name] = torch.as_tensor(np.array(array), dtype=kind, device=target)
        return cls(**tensors)


# -- the states the ops get: their dtype and shapes, checked on .dtype and .shape only ---------------


def check_params(params: object) -> EnvelopeTensors:
    """``params`` if it is an :class:`EnvelopeTensors`, else an InputError naming its type."""
    if not isinstance(params, EnvelopeTensors):
        raise InputError(f"params: expected an EnvelopeTensors, got {type(params).__name__}")
    return params


def _dtype_error(name: str, got: torch.dtype, kind: torch.dtype) -> InputError:
    if got.is_floating_point:
        return InputError(
            f"{name}: a {got} tensor, but the envelope tensors are {kind}; pass {kind} or build "
            f"EnvelopeTensors with dtype={got}"
        )
    return InputError(f"{name}: expected a floating {kind} tensor (the envelope tensors' dtype), got {got}")


def state_tensors(params: EnvelopeTensors, **values: object) -> list[torch.Tensor]:
    """The states as tensors of the parameters' dtype on their device.

    The dtype rule of the effort-level ops: a tensor must have the parameters' dtype (any other is
    refused, so that no precision and no gradient is lost in a silent cast); a number, list or
    NumPy array is read in that dtype, as Warp reads host values in float32. Only ``.dtype`` is
    read (no sync).
    """
    import torch

    kind, device = params.dtype, params.device
    tensors = []
    for name, value in values.items():
        if isinstance(value, torch.Tensor):
            if value.dtype != kind:
                raise _dtype_error(name, value.dtype, kind)
            tensors.append(value if value.device == device else value.to(device))
        else:
            tensors.append(torch.as_tensor(value, dtype=kind, device=device))
    return tensors


def broadcast_states(where: str, params: EnvelopeTensors, **states: torch.Tensor) -> list[torch.Tensor]:
    """``torch.broadcast_tensors(*states, *params)`` (views); shapes that do not broadcast: InputError."""
    import torch

    try:
        return list(torch.broadcast_tensors(*states.values(), *params.as_tuple()))
    except RuntimeError:
        shapes = ", ".join(f"{n}={tuple(t.shape)}" for n, t in states.items())
        raise InputError(
            f"{where}: shapes do not broadcast (params={params.shape}, {shapes}); expected shapes that "
            "broadcast together"
        ) from None


def records_grad(params: EnvelopeTensors, *states: torch.Tensor) -> bool:
    """Whether autograd records this call (a state or a parameter requires grad, grad mode on)."""
    import torch

    if not torch.is_grad_enabled():
        return False
    return any(t.requires_grad for t in states) or any(t.requires_grad for t in params.as_tuple())

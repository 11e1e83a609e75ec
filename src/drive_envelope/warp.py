"""The envelope on NVIDIA Warp (extra ``warp``): ``@wp.func`` building blocks and batched launches.

float32 throughout, like the engines, with PhysX's float rules (absolute epsilon ``2^-23``,
``FLT_MAX`` sentinels, ``PxMax``/``PxMin`` select semantics for NaN). Importing this module does not
import Warp; the first use of any name does.

Building blocks to call inside your own ``@wp.kernel`` (all arguments ``wp.float32``, SI):

* ``effort_limit_func(velocity, max_effort, max_actuator_velocity, velocity_dependent_resistance,
  speed_effort_gradient)`` -> largest |effort| [N*m or N] at that velocity;
* ``clamp_effort_func(effort, velocity, <the four parameters>)`` -> explicit clamp [N*m or N];
* ``clamp_drive_impulse_func(<PhysX clampDriveImpulse arguments>)`` -> clamped impulse [N*m*s or N*s];
* ``clamp_effort_implicit_func(requested_effort, velocity, response, applied_effort, dt,
  <the four parameters>)`` -> implicit clamp in effort units [N*m or N].

Launch wrappers over struct-of-arrays buffers: :class:`EnvelopeArrays` (per-DOF parameters, shape
``(N,)``), :func:`effort_limit`, :func:`clamp_effort`, :func:`clamp_effort_implicit`, and
:func:`clamp_drive_impulse` with the core's signature. Example::

    import warp as wp
    from drive_envelope import PerformanceEnvelope
    from drive_envelope.warp import EnvelopeArrays, clamp_effort_func, clamp_effort

    params = EnvelopeArrays.from_envelopes(PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=8.0,
                                                               speed_effort_gradient=0.5), count=4096)
    clamped = clamp_effort(params, effort, velocity)      # wp.array (N,), float32

    @wp.kernel
    def my_kernel(tau: wp.array(dtype=float), qd: wp.array(dtype=float)):
        i = wp.tid()
        tau[i] = clamp_effort_func(tau[i], qd[i], 12.0, 8.0, 0.0, 0.5)
"""

from __future__ import annotations

from typing import Any

from drive_envelope._src.kernels.warp_ops import (
    EnvelopeArrays,
    clamp_drive_impulse,
    clamp_effort,
    clamp_effort_implicit,
    effort_limit,
)

__all__ = [
    "EnvelopeArrays",
    "clamp_drive_impulse",
    "clamp_drive_impulse_func",
    "clamp_effort",
    "clamp_effort_func",
    "clamp_effort_implicit",
    "clamp_effort_implicit_func",
    "effort_limit",
    "effort_limit_func",
]

# Created by __getattr__ on first access (annotation only: the module stays free of Warp until then)
clamp_drive_impulse_func: Any
clamp_effort_func: Any
clamp_effort_implicit_func: Any
effort_limit_func: Any

_FUNCS = ("clamp_drive_impulse_func", "clamp_effort_func", "clamp_effort_implicit_func", "effort_limit_func")


def __getattr__(name: str) -> Any:
    """Create the ``@wp.func`` building blocks on first access (this imports Warp)."""
    if name in _FUNCS:
        from drive_envelope._src.kernels.warp_funcs import build

        try:
            return getattr(build(), name)
        except ModuleNotFoundError as exc:
            raise ImportError(f"{name} needs Warp: pip install 'drive-envelope[warp]'") from exc
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

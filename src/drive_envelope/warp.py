"""The envelope on NVIDIA Warp (extra ``warp``): ``@wp.func`` building blocks and batched launches.

float32 launches, like the engines, with PhysX's float rules (absolute epsilon ``2^-23`` on the
denominators, ``FLT_MAX`` sentinels and ``PxMax``/``PxMin`` select semantics where PhysX's
arithmetic is asked for). Importing this module does not import Warp; the first use of a
building block or a launch does.

Building blocks to call inside your own ``@wp.kernel``: generic (``wp.float32`` or ``wp.float64``,
one type per call), SI, the four envelope parameters first as everywhere in the library:

* ``effort_limit_func(max_effort, max_actuator_velocity, velocity_dependent_resistance,
  speed_effort_gradient, velocity)`` -> largest |effort| [N*m or N] at that velocity;
* ``clamp_effort_func(<the four parameters>, effort, velocity)`` -> explicit clamp [N*m or N];
* ``clamp_effort_implicit_func(<the four parameters>, requested_effort, velocity, response, dt,
  applied_effort)`` -> implicit clamp in effort units [N*m or N], the effort cap kept;
* ``clamp_drive_impulse_func(<PhysX clampDriveImpulse arguments>, physx_exact=False)`` -> clamped
  impulse [N*m*s or N*s].

Launch wrappers over struct-of-arrays buffers: :class:`EnvelopeArrays` (per-DOF parameters, shape
``(N,)``), :func:`effort_limit`, :func:`clamp_effort`, :func:`clamp_effort_implicit` (each takes the
parameters first), and :func:`clamp_drive_impulse` with the core's signature. Example::

    import warp as wp
    from drive_envelope import PerformanceEnvelope
    from drive_envelope.warp import EnvelopeArrays, clamp_effort_func, clamp_effort

    params = EnvelopeArrays.from_envelopes(PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=8.0,
                                                               speed_effort_gradient=0.5), count=4096)
    clamped = clamp_effort(params, effort, velocity)      # wp.array (N,), float32

    @wp.kernel
    def my_kernel(tau: wp.array(dtype=float), qd: wp.array(dtype=float)):
        i = wp.tid()
        tau[i] = clamp_effort_func(12.0, 8.0, 0.0, 0.5, tau[i], qd[i])
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

# Loaded by __getattr__ on first access (annotation only: the module stays free of Warp until then)
clamp_drive_impulse_func: Any
clamp_effort_func: Any
clamp_effort_implicit_func: Any
effort_limit_func: Any

_FUNCS = ("clamp_drive_impulse_func", "clamp_effort_func", "clamp_effort_implicit_func", "effort_limit_func")


def __getattr__(name: str) -> Any:
    """Load the ``@wp.func`` building blocks on first access (this imports Warp)."""
    if name in _FUNCS:
        try:
            from drive_envelope._src.kernels import warp_funcs
        except ModuleNotFoundError as exc:
            raise ImportError(f"{name} needs Warp: pip install 'drive-envelope[warp]'") from exc
        return getattr(warp_funcs, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

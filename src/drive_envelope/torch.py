"""The envelope on PyTorch tensors (extra ``torch``): batched, device-agnostic ops.

Device-agnostic (CPU or CUDA tensors), no Python loops over DOFs; importing this module does not
import torch (each function does). ``EnvelopeTensors`` holds the four envelope parameters as
tensors of any shapes that broadcast (e.g. ``(num_envs, num_joints)``); ``effort_limit(params,
velocity)``, ``clamp_effort(params, effort, velocity)`` and ``clamp_effort_implicit(params,
requested_effort, velocity, response, dt, applied_effort=0.0)`` take it first, with Warp's names.
``clamp_drive_impulse`` has the core's signature (PhysX argument order, ``physx_exact=True``
reproduces PhysX's float32 numbers on float32 tensors, the default keeps the effort cap); NumPy
arrays and scalars are accepted too, and ``.numpy()`` reads the result back on the CPU. Eager
PyTorch runs that port as about a hundred elementwise operations; ``fused_clamp_drive_impulse``
(same signature, same numbers) fuses them with ``torch.compile`` for RL-scale loops (the first call
compiles, about a minute). Example::

    from drive_envelope import PerformanceEnvelope
    from drive_envelope.torch import EnvelopeTensors, clamp_effort_implicit

    params = EnvelopeTensors.from_values(max_effort=[12.0, 8.0], max_actuator_velocity="300 rpm",
                                         speed_effort_gradient=0.5, device="cuda:0")
    effort = clamp_effort_implicit(params, requested, qd, response, dt=0.005)   # (num_envs, 2)

An explicit actuator's clip is ``clip_effort(params, effort, velocity, response, dt,
clip="end_of_step")``: PhysX's implicit clamp at the end-of-step velocity (the default of the Isaac
Lab and mjlab actuators), or ``clip="start_of_step"``, the limit at the velocity the step starts
from (``CLIP_RULES``); ``FreeVelocity`` estimates the velocity a step would end with without the
actuator's effort from the last step (loads, gravity, the other joints), and ``FreeVelocity.clip``
does the estimate, the clip and the record in one call. ``fused=True`` runs the end-of-step clip as
one ``torch.compile`` kernel (the same formula; eager where compiling fails), ``fused=None`` does so
from ``FUSE_MIN_ELEMENTS`` elements (the actuators' choice); the default is the eager port.

The Isaac Lab actuator built on these ops is ``drive_envelope.isaaclab.PerformanceEnvelopeActuator``
(a real ``isaaclab.actuators.IdealPDActuator``); its envelope tensors are ``EnvelopeTensors``.
"""

from __future__ import annotations

from drive_envelope._src.kernels.torch_clip import CLIP_RULES, FUSE_MIN_ELEMENTS, FreeVelocity, clip_effort
from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors
from drive_envelope._src.kernels.torch_ops import (
    clamp_drive_impulse,
    clamp_effort,
    clamp_effort_implicit,
    effort_limit,
    fused_clamp_drive_impulse,
)

__all__ = [
    "CLIP_RULES",
    "EnvelopeTensors",
    "FUSE_MIN_ELEMENTS",
    "FreeVelocity",
    "clamp_drive_impulse",
    "clamp_effort",
    "clamp_effort_implicit",
    "clip_effort",
    "effort_limit",
    "fused_clamp_drive_impulse",
]

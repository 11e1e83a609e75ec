"""The explicit actuator's clip on tensors: PhysX's rule at the end of the step, or the start-of-step clip.

An explicit actuator (Isaac Lab's, mjlab's) computes a PD request in torch and sends it to the
simulation as a joint effort. Two ways to limit it by the envelope, named by :data:`CLIP_RULES`:

* ``"end_of_step"`` (the default): PhysX's implicit clamp, :func:`clamp_effort_implicit` (the
  torch port of ``clamp_drive_impulse``), evaluated at the velocity the joint will end the step with
  under the effort, ``v_free + response*dt*effort``. The effort keeps the request's sign and never
  exceeds it; a request that would carry the joint past the speed line is cut to the one that ends
  on it; a braking request above the line is given whole if it brings the velocity back inside
  within the step, else the drive lets go. It needs each DOF's unit response and ``dt``.
* ``"start_of_step"``: the envelope's effort limit at the velocity the step starts from
  (:func:`clamp_effort`), what a plain explicit actuator does. No effort is feasible above the speed
  line there, so after one step that ends beyond the line (a stiff PD from rest does) the drive can
  neither stop the overshoot nor brake: on a 0.05 kg*m^2 joint at dt = 5 ms it runs away to 16-42 rad
  (issue 22).

``v_free`` is the velocity the step would end with without the actuator's effort: the current
velocity plus what gravity, loads, contacts and the other joints add. PhysX has it inside its solver;
an explicit actuator does not, so :class:`FreeVelocity` estimates it from the last step: the velocity
change the actuator's own effort does not explain, ``d = v - v_prev - response*dt*effort_prev``, is
taken to repeat (exact for a constant load, one step behind a changing one).

Cost: eager PyTorch runs the end-of-step clip as about a hundred elementwise operations (68x
Isaac Lab's DCMotor on 4096 x 12 CPU tensors). :func:`end_of_step_effort` with ``fused=True``
runs the same arithmetic (``torch_ops.implicit_effort_tensors``, the free-velocity estimate in
front) as one ``torch.compile`` kernel; ``fused=None`` (the actuators' choice) does so from
:data:`FUSE_MIN_ELEMENTS` elements, where the compile (seconds to a minute, once per process, dtype
and rank; PyTorch caches it on disk) pays for itself. Where ``torch.compile`` fails (no C++
compiler, an unsupported platform) it warns once and stays eager.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from drive_envelope._src.envelope.clamp import check_time_step
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.torch_envelope import (
    EnvelopeTensors,
    broadcast_states,
    check_params,
    records_grad,
    state_tensors,
)
from drive_envelope._src.kernels.torch_ops import (
    clamp_effort,
    clamp_effort_implicit,
    implicit_effort_tensors,
)
from drive_envelope._src.validation import refuse_negative_response

if TYPE_CHECKING:
    import torch

FUSE_MIN_ELEMENTS = 4096
"""``fused=None`` compiles the end-of-step clip from this many elements (RL scale); below, eager."""

CLIP_RULES = ("end_of_step", "start_of_step")
"""The explicit clip rules: PhysX's clamp at the end-of-step velocity (default), or the limit at the start."""


def check_clip(clip: object, where: str) -> str:
    """``clip`` if it names a rule of :data:`CLIP_RULES`, else a one-line InputError naming ``where``."""
    if not isinstance(clip, str) or clip not in CLIP_RULES:
        raise InputError(f"{where}: clip = {clip!r}; expected one of {', '.join(map(repr, CLIP_RULES))}")
    return clip


def clip_effort(
    params: EnvelopeTensors,
    effort: Any,
    velocity: Any,
    response: Any = None,
    dt: float | None = None,
    *,
    clip: str = "end_of_step",
    fused: bool | None = False,
) -> torch.Tensor:
    """An explicit actuator's effort limited by the envelope with the rule ``clip`` (:data:`CLIP_RULES`).

    Args:
        params: The envelope parameters.
        effort: The requested effort (the PD law) [N*m or N].
        velocity: ``"end_of_step"``: the velocity the step would end with without this effort
            (the current velocity when nothing else acts; :class:`FreeVelocity` estimates it)
            [rad/s or m/s]. ``"start_of_step"``: the current velocity.
        response: Each DOF's unit response, ``1/effective_inertia`` or ``(M^-1)_ii``
            [1/(kg*m^2) or 1/kg], ``>= 0``; needed by ``"end_of_step"`` only.
        dt: The physics time step [s]; needed by ``"end_of_step"`` only.
        clip: ``"end_of_step"`` (PhysX's rule) or ``"start_of_step"``.
        fused: ``"end_of_step"`` only: True runs it as one ``torch.compile`` kernel (the first call
            compiles; eager where that fails), None does so from :data:`FUSE_MIN_ELEMENTS`
            elements, False (default) runs the eager port (NumPy's numbers to the bit in float64).

    Returns:
        The effort to apply [N*m or N], broadcast shape, the parameters' dtype; never NaN.

    Raises:
        InputError: an unknown ``clip``, a missing or bad ``response`` or ``dt`` for ``"end_of_step"``,
            or what :func:`clamp_effort_implicit` refuses.
    """
    if check_clip(clip, "clip_effort") == "start_of_step":
        return clamp_effort(params, effort, velocity)
    if response is None or dt is None:
        raise InputError(
            "clip_effort: clip='end_of_step' needs response [1/(kg*m^2) or 1/kg] and dt [s]; "
            "pass both, or clip='start_of_step'"
        )
    return end_of_step_effort(params, effort, velocity, response, dt, fused=fused)


def _end_of_step_tensors(
    tau: torch.Tensor,
    v: torch.Tensor,
    v_prev: torch.Tensor,
    e_prev: torch.Tensor,
    known: torch.Tensor,
    r: torch.Tensor,
    max_e: torch.Tensor,
    max_v: torch.Tensor,
    resist: torch.Tensor,
    grad: torch.Tensor,
    step: Any,
) -> torch.Tensor:
    """The free-velocity estimate and the implicit clamp at it, on tensors of one shape (compiled whole).

    ``v_free = v + (v - v_prev - r*dt*e_prev)`` where ``known`` (bool, or 0/1: a step was recorded) is
    nonzero, else ``v``. ``step`` is a float or a tensor that broadcasts [s].
    """
    import torch

    free = torch.where(
        known != 0, v + (v - v_prev - r * step * e_prev), v
    )  # v itself (its zero's sign) if not
    return implicit_effort_tensors(tau, free, torch.zeros_like(tau), r, max_e, max_v, resist, grad, step)


@functools.cache
def _compiled() -> Callable[..., torch.Tensor]:
    import torch

    return torch.compile(_end_of_step_tensors)  # type: ignore[no-any-return]


_COMPILE_FAILED: list[str] = []  # the first failure's message: from then on every call is eager


def _run_fused(tensors: list[torch.Tensor], step: Any) -> torch.Tensor | None:
    """The compiled kernel's result, or None where torch.compile does not work here (warned once)."""
    if _COMPILE_FAILED:
        return None
    try:
        return _compiled()(*tensors, step)
    except Exception as exc:  # a missing C++ toolchain or an unsupported platform: fall back, say so once
        _COMPILE_FAILED.append(f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}")
        warnings.warn(
            f"end-of-step clip: torch.compile failed ({_COMPILE_FAILED[0]}); running eager PyTorch "
            "(the same numbers, about 10x the cost)",
            RuntimeWarning,
            stacklevel=3,
        )
        return None


def end_of_step_law(
    params: EnvelopeTensors,
    effort: torch.Tensor,
    velocity: torch.Tensor,
    response: torch.Tensor,
    step: Any,
    history: tuple[torch.Tensor, torch.Tensor, torch.Tensor],
    *,
    fused: bool | None = None,
) -> torch.Tensor:
    """:func:`end_of_step_effort` without its checks, for an actuator's control law on its own buffers.

    Every tensor has the parameters' shape, dtype and device, checked once when the actuator was
    built (no host work per call, so it runs inside a fused mjlab group and a CUDA graph).

    Args:
        params: The envelope parameters.
        effort: The requested effort [N*m or N].
        velocity: Current velocity [rad/s or m/s].
        response: Unit response [1/(kg*m^2) or 1/kg].
        step: The physics time step [s], a float or a tensor.
        history: ``(v_prev [rad/s or m/s], effort_prev [N*m or N], known)`` as in
            :func:`end_of_step_effort`; ``known`` may be 0/1 floats.
        fused: As in :func:`end_of_step_effort` (None: by size).

    Returns:
        The effort to apply [N*m or N].
    """
    v_prev, e_prev, known = history
    max_e, max_v, resist, grad = params.as_tuple()
    if fused if fused is not None else effort.numel() >= FUSE_MIN_ELEMENTS:
        tensors = [effort, velocity, v_prev, e_prev, known, response, max_e, max_v, resist, grad]
        out = _run_fused([t.contiguous() for t in tensors], step)
        if out is not None:
            return out
    return _end_of_step_tensors(
        effort, velocity, v_prev, e_prev, known, response, max_e, max_v, resist, grad, step
    )


def end_of_step_effort(
    params: EnvelopeTensors,
    effort: Any,
    velocity: Any,
    response: Any,
    dt: float,
    *,
    history: tuple[Any, Any, Any] | None = None,
    fused: bool | None = False,
) -> torch.Tensor:
    """PhysX's clamp at the end-of-step velocity, eager or as one compiled kernel (the same formula).

    Args:
        params: The envelope parameters.
        effort: The requested effort (the PD law) [N*m or N].
        velocity: With ``history``: the current velocity; without: the free end-of-step velocity
            [rad/s or m/s].
        response: Each DOF's unit response [1/(kg*m^2) or 1/kg], ``>= 0``.
        dt: The physics time step [s].
        history: ``(v_prev [rad/s or m/s], effort_prev [N*m or N], known)``: the free velocity is
            ``v + (v - v_prev - response*dt*effort_prev)`` where ``known`` (bool, broadcast) is true.
        fused: True: ``torch.compile`` (eager where it fails); False: eager; None: fused from
            :data:`FUSE_MIN_ELEMENTS` elements. Autograd always runs eager.

    Returns:
        The effort to apply [N*m or N], broadcast shape, the parameters' dtype; never NaN.

    Raises:
        InputError: a bad ``dt``, ``params``, dtype or shape, or a negative ``response`` on the host.
    """
    import torch

    params = check_params(params)
    step = check_time_step(dt)
    refuse_negative_response(response, device_array=torch.Tensor)
    if history is None:
        v_prev, e_prev, known = 0.0, 0.0, torch.zeros((), dtype=torch.bool, device=params.device)
    else:
        v_prev, e_prev, known = history
    tau, v, r, vp, ep = state_tensors(
        params, effort=effort, velocity=velocity, response=response, v_prev=v_prev, effort_prev=e_prev
    )
    views = broadcast_states(
        "clip_effort", params, effort=tau, velocity=v, response=r, v_prev=vp, effort_prev=ep
    )
    use = fused if fused is not None else views[0].numel() >= FUSE_MIN_ELEMENTS
    if use and not records_grad(params, tau, v, r, vp, ep):
        tau_b, v_b, r_b, vp_b, ep_b, *envelope = (t.contiguous() for t in views)
        flags = torch.broadcast_to(known.to(device=params.device, dtype=torch.bool), tau_b.shape)
        out = _run_fused([tau_b, v_b, vp_b, ep_b, flags.contiguous(), r_b, *envelope], step)
        if out is not None:
            return out
    if history is None:  # the eager port itself: NumPy's numbers to the bit
        return clamp_effort_implicit(params, tau, v, r, step)
    known = known.to(device=params.device, dtype=torch.bool)
    return _end_of_step_tensors(tau, v, vp, ep, known, r, *params.as_tuple(), step)


class FreeVelocity:
    """Estimates each DOF's end-of-step velocity without the actuator's effort, from the last step.

    ``predict(v)`` returns ``v + d`` with ``d = v - v_prev - response*dt*effort_prev``, the velocity
    change of the last step that the actuator's own effort does not explain (loads, gravity,
    contacts, the other joints; also an error in ``response``); ``record(effort)`` stores the effort
    sent. An environment without a previous step (the first, or after :meth:`reset`) gets ``d = 0``.
    All tensors are ``(num_envs, num_joints)``, updated in place (no host syncs).
    """

    def __init__(self, like: Any) -> None:
        """Zero history shaped, typed and placed like the tensor ``like``."""
        import torch

        self._velocity = torch.zeros_like(like)
        self._effort = torch.zeros_like(like)
        self._velocity_now = torch.zeros_like(like)
        self._valid = torch.zeros(
            like.shape[:1] + (1,) * (like.dim() - 1), dtype=torch.bool, device=like.device
        )

    def predict(self, velocity: Any, response: Any, dt: float) -> torch.Tensor:
        """The free end-of-step velocity [rad/s or m/s] from the current one and the stored step.

        Args:
            velocity: Current joint velocity [rad/s or m/s].
            response: Unit response [1/(kg*m^2) or 1/kg], as used in the last step.
            dt: Physics time step [s].
        """
        import torch

        step = check_time_step(dt)
        self._velocity_now.copy_(velocity)
        change = velocity - self._velocity - response * step * self._effort
        return velocity + torch.where(self._valid, change, torch.zeros_like(change))

    def record(self, effort: Any) -> None:
        """Store the effort sent this step [N*m or N] (with the velocity :meth:`predict` saw)."""
        self._velocity.copy_(self._velocity_now)
        self._effort.copy_(effort)
        self._valid.fill_(True)

    def clip(
        self,
        params: EnvelopeTensors,
        effort: Any,
        velocity: Any,
        response: Any,
        dt: float,
        *,
        fused: bool | None = None,
    ) -> torch.Tensor:
        """:meth:`predict`, the end-of-step clip at the free velocity, and :meth:`record`, in one call.

        The estimate and the clamp run as one compiled kernel where ``fused`` says so
        (:func:`end_of_step_effort`; None: from :data:`FUSE_MIN_ELEMENTS` elements).

        Args:
            params: The envelope parameters.
            effort: The requested effort [N*m or N].
            velocity: Current joint velocity [rad/s or m/s].
            response: Unit response [1/(kg*m^2) or 1/kg].
            dt: Physics time step [s].
            fused: As in :func:`end_of_step_effort` (True, False, or None: by size).

        Returns:
            The effort to apply [N*m or N] (also stored for the next step's estimate).
        """
        applied = end_of_step_effort(
            params,
            effort,
            velocity,
            response,
            dt,
            history=(self._velocity, self._effort, self._valid),
            fused=fused,
        )
        self._velocity.copy_(velocity)
        self._effort.copy_(applied)
        self._valid.fill_(True)
        return applied

    def reset(self, env_ids: Any = None) -> None:
        """Forget the history of these environments (all when None): their next ``d`` is 0."""
        if env_ids is None:
            self._valid.fill_(False)
        else:
            self._valid[env_ids] = False

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
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from drive_envelope._src.envelope.clamp import check_time_step
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.torch_envelope import EnvelopeTensors
from drive_envelope._src.kernels.torch_ops import clamp_effort, clamp_effort_implicit

if TYPE_CHECKING:
    import torch

__all__ = ["CLIP_RULES", "FreeVelocity", "check_clip", "clip_effort"]

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
    return clamp_effort_implicit(params, effort, velocity, response, dt)


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

    def reset(self, env_ids: Any = None) -> None:
        """Forget the history of these environments (all when None): their next ``d`` is 0."""
        if env_ids is None:
            self._valid.fill_(False)
        else:
            self._valid[env_ids] = False

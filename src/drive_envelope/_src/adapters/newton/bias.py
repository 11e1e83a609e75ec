# mypy: disable-error-code="index"
# (Warp kernel bodies index wp.array values, which Warp's type stubs do not declare indexable)
"""``BiasForce``: gravity and Coriolis forces for the implicit envelope clamp's end-of-step prediction.

In implicit mode Newton's actuator predicts the end-of-step velocity as ``qd + A (p - dt b)``, where
``b`` is the ``bias_force`` of ``Actuator.step`` (the manipulator equation's ``tau = M qdd + b``)
and ``p`` the actuator's impulse. Without ``b`` the prediction ignores every other force, so the
clamp bounds the effort at a velocity the step does not reach: on a gravity pendulum the effort
ends above the envelope's limit at the real end-of-step velocity. :class:`BiasForce` computes
``b = g(q) + C(q, qd) qd`` with Newton's ``eval_inverse_dynamics_passive`` into arrays it owns, once
per step, before ``actuator.step(..., bias_force=bias.compute(state))``.

Forces it does not include, because Newton's inverse dynamics does not: joint damping, joint
springs and limits, contacts, body forces and joint forces from outside the actuators. A known
one (a joint-space load ``e`` you add to ``joint_f``) enters as ``b - e``: pass it as ``external``.
"""

from __future__ import annotations

import functools
from typing import Any

from drive_envelope._src.errors import InputError


@functools.cache
def _kernels() -> Any:
    """The summing kernel, defined once per process (imports Warp)."""
    import warp as wp

    @wp.kernel(enable_backward=False)
    def _bias_kernel(
        gravity: wp.array[wp.float32],
        coriolis: wp.array[wp.float32],
        external: wp.array[wp.float32],
        out: wp.array[wp.float32],
    ):
        """out[i] = gravity[i] + coriolis[i] - external[i] (``coriolis``/``external`` may be absent)."""
        i = wp.tid()
        value = gravity[i]
        if coriolis:
            value = value + coriolis[i]
        if external:
            value = value - external[i]
        out[i] = value

    return _bias_kernel


class BiasForce:
    """The manipulator equation's bias ``b = g(q) + C(q, qd) qd`` per DOF, for ``Actuator.step``.

    Example (implicit envelope clamp under gravity)::

        bias = BiasForce(model)
        for _ in range(steps):
            control.joint_f.zero_()
            response.refresh(state)
            actuator.step(state, control, dt=dt, bias_force=bias.compute(state))
            solver.step(state, next_state, control, None, dt)
            state, next_state = next_state, state

    ``state.body_q`` must match ``state.joint_q`` (Newton's solvers keep it so; after writing
    ``joint_q`` yourself, call ``newton.eval_fk`` first).
    """

    def __init__(self, model: Any, *, coriolis: bool = True) -> None:
        """Allocate the arrays on the model's device.

        Args:
            model: A finalized ``newton.Model``.
            coriolis: Include the Coriolis and centrifugal forces ``C(q, qd) qd`` (default), or only
                gravity.
        """
        import newton
        import warp as wp

        if not isinstance(model, newton.Model):
            hint = "; call builder.finalize() first" if isinstance(model, newton.ModelBuilder) else ""
            raise InputError(
                f"BiasForce: model: expected a finalized newton.Model, got {type(model).__name__}{hint}"
            )
        count = int(model.joint_dof_count)
        if count < 1:
            raise InputError("BiasForce: the model has no joint DOFs")
        self.model = model
        self.gravity = wp.zeros(count, dtype=wp.float32, device=model.device)
        """``g(q)`` [N or N*m] of the last :meth:`compute`, ``(joint_dof_count,)``."""
        self.coriolis = wp.zeros(count, dtype=wp.float32, device=model.device) if coriolis else None
        """``C(q, qd) qd`` [N or N*m] of the last :meth:`compute`, or None when not computed."""
        self.bias_force = wp.zeros(count, dtype=wp.float32, device=model.device)
        """The bias ``b`` [N or N*m], ``(joint_dof_count,)``: what :meth:`compute` returns."""

    def compute(self, state: Any, external: Any = None) -> Any:
        """Evaluate ``b`` at ``state`` and return :attr:`bias_force` (overwritten in place).

        Args:
            state: The ``newton.State`` the actuator steps from.
            external: Optional joint-space load from outside the actuators (a float32 Warp array
                indexed like ``joint_qd``) [N or N*m]; it enters as ``b - external``.

        Returns:
            :attr:`bias_force`, a ``wp.array`` of float32 to pass as ``bias_force``.
        """
        import newton
        import warp as wp

        if not isinstance(state, newton.State):
            raise InputError(f"BiasForce.compute: state: expected a newton.State, got {type(state).__name__}")
        if external is not None and (not isinstance(external, wp.array) or external.dtype != wp.float32):
            got = type(external).__name__
            if isinstance(external, wp.array):
                got = f"a wp.array of {getattr(external.dtype, '__name__', external.dtype)}"
            raise InputError(
                "BiasForce.compute: external: expected None or a float32 wp.array indexed like joint_qd, "
                f"got {got}"
            )
        if external is not None and external.shape != self.bias_force.shape:
            raise InputError(
                f"BiasForce.compute: external has shape {external.shape}, expected {self.bias_force.shape}"
            )
        newton.eval_inverse_dynamics_passive(
            self.model, state, gravity_force=self.gravity, coriolis_force=self.coriolis
        )
        wp.launch(
            _kernels(),
            dim=self.bias_force.shape[0],
            inputs=[self.gravity, self.coriolis, external],
            outputs=[self.bias_force],
            device=self.model.device,
        )
        return self.bias_force

# mypy: disable-error-code="index,valid-type,arg-type"
# (Warp kernel bodies index wp.array values, annotate with Warp types and pass wp.tid()'s index,
# which mypy does not follow)
"""PhysX's PGS and TGS drive iteration for an isolated Newton DOF, as a Warp kernel.

Newton's actuator API cannot run PhysX's iteration (``clamp.py`` says why: a clamping stage is one
function of the whole step's predicted velocity). The test stand does not need it to: it computes
the drive's effort itself, before Newton's solver step, as PhysX's articulation solver does for one
DOF, and hands it to ``SolverFeatherstone`` as joint effort (``joint_f``). Per step, with the
joint's response ``r = 1/(I + armature)`` read from Newton's own mass matrix
(``JointSpaceResponse.inverse_blocks``), the loads ``u = applied - b`` (``b = g(q) - external``,
:class:`~drive_envelope._src.adapters.newton.bias.BiasForce`) and PhysX's implicit drive law
(``computeImplicitDriveParams`` / ``computeDriveImpulse``) and ``clampDriveImpulse`` on the total
actuator impulse (drive + applied), the applied effort's impulse taken back out:

* PGS: ``v = qd + r*u*dt``; ``position_iterations`` sweeps ``x += clamp(x + J(x, v)) - x``,
  ``v += r*delta``; positions move with that velocity; then ``max(1, velocity_iterations)`` more
  sweeps (PhysX runs at least one) give the reported velocity.
* TGS: ``N = position_iterations`` substeps of ``h = dt/N``, each ``v += r*u*h``, then the
  substep's own impulse ``clamp(J(0, v, moved, elapsed))`` with budget ``max_effort*h``, gradient
  ``G/h`` and resistance ``R*h`` (PhysX's per-step clamp), ``moved += v*h``; then
  ``velocity_iterations`` sweeps re-clamp the step's total ``x`` at the current velocity, no new
  request.

The effort Newton gets is ``x/dt + applied + external``: Featherstone then reaches the same
end-of-step velocity (``v1 = qd + dt*(joint_f - g)/M``, to float32). It integrates positions with
``q1 = q + dt*v1``; PhysX with the velocity of the position sweeps (PGS) or per substep (TGS). The
kernel returns the difference, ``shift = moved - dt*v1``, which :func:`shift_positions` adds after
the step, as the MuJoCo plugin does. Everything is float64 inside; Newton's state is float32.

This module imports Warp at the top; only the Newton stand imports it, lazily.
"""

from typing import Any

import warp as wp  # noqa: TID253  (a kernel module, imported lazily, as warp_funcs)

from drive_envelope._src.kernels.warp_funcs import clamp_drive_impulse_func, implicit_drive_params

PARAMS = ("stiffness", "damping", "max_effort", "max_actuator_velocity",
          "velocity_dependent_resistance", "speed_effort_gradient")  # fmt: skip
"""Columns of the kernel's float64 parameter row, SI (the envelope's spec names)."""

wp.set_module_options({"fuse_fp": False})  # round as NumPy does: the reference is float64 NumPy


@wp.func
def _clamp_total(
    velocity: wp.float64,
    applied0: wp.float64,
    request: wp.float64,
    external: wp.float64,
    response: wp.float64,
    params: wp.array2d[wp.float64],
    i: int,
    limited: int,
    timestep: wp.float64,
):
    """PhysX's clampDriveImpulse on the total actuator impulse, minus the applied effort's [N*m*s or N*s].

    Over ``timestep`` the budget is ``max_effort*timestep``, the gradient ``G/timestep`` and the
    resistance ``R*timestep``; an unlimited drive (``limited == 0``) keeps its request.
    """
    if limited == 0:
        return request
    total = clamp_drive_impulse_func(
        velocity,
        applied0 + external,
        request + external,
        response,
        params[i, 3],
        params[i, 2] * timestep,
        params[i, 5] / timestep,
        params[i, 4] * timestep,
    )
    return total - external


@wp.func
def _drive_request(
    accumulated: wp.float64,
    velocity: wp.float64,
    moved: wp.float64,
    elapsed: wp.float64,
    stiffness: wp.float64,
    damping: wp.float64,
    error: wp.float64,
    target_velocity: wp.float64,
    response: wp.float64,
    step: wp.float64,
    dt: wp.float64,
    acceleration: int,
    tgs: int,
):
    """PhysX's computeDriveImpulse of computeImplicitDriveParams' law [N*m*s or N*s].

    The coefficients are :func:`~drive_envelope._src.kernels.warp_funcs.implicit_drive_params`,
    the one Warp form of the law (MJWarp's articulation iteration uses it too).
    """
    constant, bias, per_velocity, per_accumulated, per_elapsed = implicit_drive_params(
        stiffness, damping, error, target_velocity, response, step, dt, acceleration, tgs
    )
    return (
        accumulated * per_accumulated
        + velocity * per_velocity
        + constant
        - moved * bias
        + elapsed * per_elapsed
    )


@wp.kernel(enable_backward=False)
def _physx_drive_kernel(
    joint_q: wp.array[wp.float32],
    joint_qd: wp.array[wp.float32],
    inverse_blocks: wp.array3d[wp.float32],
    bias: wp.array[wp.float32],
    external: wp.array[wp.float32],
    target_q: wp.array[wp.float32],
    target_qd: wp.array[wp.float32],
    applied: wp.array[wp.float32],
    params: wp.array2d[wp.float64],
    flags: wp.array2d[wp.int32],
    dt: wp.float64,
    joint_f: wp.array[wp.float32],
    effort: wp.array[wp.float64],
    shift: wp.array[wp.float64],
):
    """One step of PhysX's drive iteration on isolated DOF i (the module docstring has the rule).

    ``flags[i]`` = [tgs, position_iterations, velocity_iterations, acceleration drive, drive on,
    envelope limited]; ``inverse_blocks[i, 0, 0]`` = 1/(I + armature) of DOF i's one-DOF articulation.
    Writes ``joint_f[i] = x/dt + applied + external``, ``effort[i] = x/dt + applied`` (the actuator
    effort PhysX reports) and ``shift[i]`` = PhysX's position minus ``q + dt*v1``.
    """
    i = wp.tid()
    zero = wp.float64(0.0)
    tgs = flags[i, 0]
    iterations = flags[i, 1]
    velocity_iterations = flags[i, 2]
    acceleration = flags[i, 3]
    active = flags[i, 4]
    limited = flags[i, 5]
    r = wp.float64(inverse_blocks[i, 0, 0])
    stiffness = params[i, 0]
    damping = params[i, 1]
    error = wp.float64(target_q[i]) - wp.float64(joint_q[i])
    vt = wp.float64(target_qd[i])
    effort_in = wp.float64(applied[i])
    load = effort_in - wp.float64(bias[i])  # applied + external - g(q): every load on the joint
    v = wp.float64(joint_qd[i])
    x = zero
    moved = zero
    if tgs == 0:
        v = v + r * load * dt
        # the position sweeps, then at least one velocity sweep (PhysX's PGS): the same sweep
        for sweep in range(iterations + wp.max(1, velocity_iterations)):
            if active != 0:
                request = _drive_request(x, v, zero, zero, stiffness, damping, error, vt, r, dt, dt,
                                         acceleration, 0)  # fmt: skip
                delta = _clamp_total(v, x, request, effort_in * dt, r, params, i, limited, dt) - x
                x = x + delta
                v = v + r * delta
            if sweep == iterations - 1:
                moved = v * dt  # PGS moves the joint with the position sweeps' velocity
    else:
        h = dt / wp.float64(iterations)
        elapsed = zero
        for _it in range(iterations):
            v = v + r * load * h  # applyTgsSubstepForces
            if active != 0:
                request = _drive_request(zero, v, moved, elapsed, stiffness, damping, error, vt, r, h,
                                         dt, acceleration, 1)  # fmt: skip
                delta = _clamp_total(v, zero, request, effort_in * h, r, params, i, limited, h)
                x = x + delta
                v = v + r * delta
            moved = moved + v * h  # updateDeltaMotion
            elapsed = elapsed + h
        for _it in range(velocity_iterations):
            if active != 0:  # the velocity sweep re-clamps the step's total, no new request
                delta = _clamp_total(v, x, x, effort_in * dt, r, params, i, limited, dt) - x
                x = x + delta
                v = v + r * delta
    drive_effort = x / dt + effort_in
    effort[i] = drive_effort
    joint_f[i] = wp.float32(drive_effort + wp.float64(external[i]))
    shift[i] = moved - dt * v


@wp.kernel(enable_backward=False)
def _shift_kernel(joint_q: wp.array[wp.float32], shift: wp.array[wp.float64]):
    """joint_q[i] += shift[i]: Newton's ``q + dt*v1`` moved to PhysX's position."""
    i = wp.tid()
    joint_q[i] = wp.float32(wp.float64(joint_q[i]) + shift[i])


def launch_drive(
    state: Any, control: Any, inverse_blocks: Any, bias: Any, external: Any, params: Any, flags: Any,
    dt: float, effort: Any, shift: Any,
) -> None:  # fmt: skip
    """Launch :func:`_physx_drive_kernel` over the DOFs: ``control.joint_f`` gets the drive's effort.

    Args:
        state: The ``newton.State`` at the start of the step (``joint_q``, ``joint_qd``).
        control: The ``newton.Control``: targets, ``joint_act`` (applied effort [N*m or N]), and
            ``joint_f``, written.
        inverse_blocks: ``JointSpaceResponse.inverse_blocks`` after ``refresh(state)`` [1/(kg*m^2) or 1/kg].
        bias: ``BiasForce.compute(state, external=external)``: ``g(q) - external`` [N*m or N].
        external: The joint's external effort (not actuator effort) [N*m or N].
        params: float64 ``(n, 6)`` rows of :data:`PARAMS` (SI).
        flags: int32 ``(n, 6)`` rows (see :func:`_physx_drive_kernel`).
        dt: The step [s].
        effort: float64 ``(n,)``, written: the actuator effort [N*m or N].
        shift: float64 ``(n,)``, written: the position correction [rad or m].
    """
    wp.launch(
        _physx_drive_kernel,
        dim=params.shape[0],
        inputs=[
            state.joint_q,
            state.joint_qd,
            inverse_blocks,
            bias,
            external,
            control.joint_target_q,
            control.joint_target_qd,
            control.joint_act,
            params,
            flags,
            wp.float64(dt),
        ],
        outputs=[control.joint_f, effort, shift],
        device=params.device,
    )


def shift_positions(state: Any, shift: Any) -> None:
    """Add the kernel's ``shift`` to ``state.joint_q`` (after the solver step) [rad or m]."""
    wp.launch(_shift_kernel, dim=shift.shape[0], inputs=[state.joint_q, shift], device=shift.device)

# mypy: disable-error-code="index,valid-type,operator,assignment,misc,arg-type,attr-defined,return-value"
# (Warp function bodies index wp.array values and annotate with Warp types, which mypy does not follow)
"""PhysX's articulation iteration over one world's drives (solver ``"pgs"`` / ``"tgs"``) in Warp.

``plugin/mujoco/articulation.cc`` line for line, on the kernel's rows (the drives) and its
``A = (M + h*D')^-1`` over them: each drive a velocity row in Gauss-Seidel sweeps from the root to
the leaves, its response ``A_ii``, its clamped impulse moving every drive through ``A``'s column.
The drive law is PhysX's ``computeImplicitDriveParams`` / ``computeDriveImpulse``; the clamp the
library's one Warp clamp. PGS: the loads once, ``position_iterations`` sweeps, then at least one
velocity sweep. TGS: per substep the loads over the substep and each drive's substep impulse
clamped against ``max_effort*substep``, then ``velocity_iterations`` sweeps that re-clamp the step's
total.

TGS applies the velocity-dependent bias (``-qfrc_bias`` minus the weights' ``J'*m*g``) once before
the first substep, as PhysX does, and the other loads per substep. One difference from the C
plugin, said in docs/mjwarp.md: MJWarp integrates positions with the end-of-step velocity (the
plugin moves them to PhysX's integration after MuJoCo's step; MJWarp has no hook after its
integrator).
"""

import warp as wp  # noqa: TID253 (imported only by kernels.py, itself imported lazily)

from drive_envelope._src.adapters.mjwarp.solve import IntWork, Layout, Work, _finite, propagate
from drive_envelope._src.kernels.warp_funcs import clamp_drive_impulse_func, implicit_drive_params

wp.set_module_options({"fuse_fp": False})

PGS = 1
"""Solver code of PhysX's PGS in the model's ``drive_envelope_solver`` numeric."""
TGS = 2
"""Solver code of TGS."""

_PASS_PGS = wp.constant(0)
_PASS_SUBSTEP = wp.constant(1)
_PASS_VELOCITY = wp.constant(2)


@wp.func
def _visit(
    work: Work, iwork: IntWork, lay: Layout, w: int, r: int, mode: int, span: wp.float64, elapsed: wp.float64
):
    """One drive of one sweep: PhysX's drive block of ``solveInternalJointConstraintRecursive``."""
    iwork[lay.solves, w] = iwork[lay.solves, w] + 1
    if iwork[lay.active + r, w] != 0:
        p = lay.prm + 6 * r
        d = lay.desc + 5 * r
        v = work[lay.v + r, w]
        applied = work[lay.x + r, w]
        if mode == _PASS_SUBSTEP:
            applied = wp.float64(0.0)  # a TGS substep clamps its own impulse (PhysX's isPerStep)
        external = work[lay.ff + r, w] * span  # the joint force: effort that counts, not driven
        request = applied
        if mode != _PASS_VELOCITY:
            request = (
                applied * work[d + 3, w]
                + v * work[d + 2, w]
                + work[d, w]
                - work[lay.moved + r, w] * work[d + 1, w]
                + elapsed * work[d + 4, w]
            )
        clamped = (
            clamp_drive_impulse_func(
                v,
                applied + external,
                request + external,
                work[lay.a + r * lay.n + r, w],
                work[p + 1, w],
                work[p, w] * span,
                work[p + 3, w] / span,
                work[p + 2, w] * span,
            )
            - external
        )
        delta = clamped - applied
        if _finite(delta):
            work[lay.x + r, w] = work[lay.x + r, w] + delta
            propagate(work, lay, w, r, delta)


@wp.func
def articulation(
    work: Work,
    iwork: IntWork,
    lay: Layout,
    accel: wp.array[wp.int32],
    w: int,
    h: wp.float64,
    kind: int,
    position_iterations: int,
    velocity_iterations: int,
):
    """PhysX's PGS (kind 1) or TGS (kind 2) over the drives; writes each effort, returns the sweeps."""
    n = lay.n
    zero = wp.float64(0.0)
    tgs = kind == TGS
    step = h
    if tgs:
        step = h / wp.float64(position_iterations)
    for r in range(n):
        work[lay.x + r, w] = zero
        work[lay.moved + r, w] = zero
        if iwork[lay.active + r, w] != 0:
            # computeImplicitDriveParams with the row's response and the span the spring integrates over
            p = lay.prm + 6 * r
            d = lay.desc + 5 * r
            constant, bias, per_velocity, per_accumulated, per_elapsed = implicit_drive_params(
                work[p + 4, w],
                work[p + 5, w],
                work[lay.err + r, w],
                work[lay.tvel + r, w],
                work[lay.a + r * n + r, w],
                step,
                h,
                accel[r],
                wp.where(tgs, 1, 0),
            )
            work[d, w] = constant
            work[d + 1, w] = bias
            work[d + 2, w] = per_velocity
            work[d + 3, w] = per_accumulated
            work[d + 4, w] = per_elapsed
    for r in range(n):
        work[lay.v + r, w] = work[lay.vfree + r, w]
    for r in range(n):
        if iwork[lay.active + r, w] != 0:
            propagate(work, lay, w, r, work[lay.ff + r, w] * h)
    sweeps = wp.int32(0)  # a dynamic variable: Warp refuses to mutate a literal in loops
    if not tgs:
        velocity = wp.max(velocity_iterations, 1)  # PhysX's PGS always runs a last velocity sweep
        for _it in range(position_iterations + velocity):
            for r in range(n):
                _visit(work, iwork, lay, w, r, _PASS_PGS, h, zero)
            sweeps += wp.int32(1)
    else:
        # the velocity-dependent bias acts before the first substep, the other loads over each
        for r in range(n):
            start = work[lay.qvel + r, w] + work[lay.bias + r, w]
            work[lay.rest + r, w] = (work[lay.v + r, w] - start) / wp.float64(position_iterations)
            work[lay.v + r, w] = start
        elapsed = zero
        for _it in range(position_iterations):
            for r in range(n):
                work[lay.v + r, w] = work[lay.v + r, w] + work[lay.rest + r, w]
            for r in range(n):
                _visit(work, iwork, lay, w, r, _PASS_SUBSTEP, step, elapsed)
            for r in range(n):
                work[lay.moved + r, w] = work[lay.moved + r, w] + work[lay.v + r, w] * step
            elapsed += step
            sweeps += wp.int32(1)
        for _it in range(velocity_iterations):
            for r in range(n):
                _visit(work, iwork, lay, w, r, _PASS_VELOCITY, h, elapsed)
            sweeps += wp.int32(1)
    for r in range(n):
        effort = zero
        if iwork[lay.active + r, w] != 0:
            effort = (work[lay.x + r, w] + work[lay.ff + r, w] * h) / h
            if not _finite(effort):
                effort = zero
        work[lay.effort + r, w] = effort
    return sweeps

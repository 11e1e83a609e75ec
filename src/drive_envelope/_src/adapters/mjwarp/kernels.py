# mypy: disable-error-code="index,valid-type,operator,assignment,misc,arg-type,attr-defined,return-value"
# (Warp kernel bodies index wp.array values and annotate with Warp types, which mypy does not follow)
"""The MJWarp drive kernels: one thread per world, the C plugin's per-step law (``coupled.cc``).

``_smooth_force_kernel`` sums the forces MJWarp has at actuation time that the drives must see
coming: ``f = qfrc_passive - qfrc_bias + qfrc_applied`` + actuator-level gravity compensation +
every other actuator's force (``J'*xfrc_applied`` is added after it by MJWarp's own
``xfrc_accumulate``). ``_drive_kernel`` then, per world:

1. reads each drive's six numbers (``actuator_dynprm`` of its effort actuator, per world) and its
   inputs (delayed controls from MJWarp's history buffer, ``ctrlrange``, MuJoCo's bad-control rule);
2. factors ``M + h*D'`` (``D'`` the joint damping the integrator treats implicitly) as MuJoCo's
   ``mj_factorI`` does, ``M + h*D' = L' D L``, in MuJoCo's sparse layout;
3. forms ``A = Z' D^-1 Z`` with ``Z = L^-T [e_dof of each drive]`` and the free end-of-step
   velocity ``vfree = qvel + h*(M + h*D')^-1 f`` over the driven DOFs;
4. gives each drive the unclamped law ``w = c - alpha*v1`` (PhysX's implicit PD drive) and runs the
   coupled solve (:func:`.solve.solve_drives`);
   or, with the model's solver setting ``"pgs"``/``"tgs"``, PhysX's articulation iteration
   (:func:`.articulation.articulation`);
5. writes each drive's effort to ``actuator_force`` of its effort actuator (its other actuators 0).
"""

import warp as wp

from drive_envelope._src.adapters.mjwarp.articulation import articulation
from drive_envelope._src.adapters.mjwarp.solve import IntWork, Layout, Work, solve_drives

wp.set_module_options({"fuse_fp": False})

_vec10 = wp.types.vector(length=10, dtype=wp.float32)  # MJWarp's actuator_dynprm entries
_BOUND = wp.constant(wp.float64(1e12))  # largest number a slot may hold [SI]
_MAXVAL = wp.constant(wp.float64(1e10))  # MuJoCo's mjMAXVAL: a larger control is bad
_MINVAL = wp.constant(wp.float64(1e-15))  # MuJoCo's mjMINVAL
_INF = wp.constant(wp.float64(float("inf")))


@wp.struct
class DriveArrays:
    """The drive table on the device: :class:`.structure.DriveTable`'s arrays by their names (int32)."""

    dof: wp.array[wp.int32]
    qpos: wp.array[wp.int32]
    actuator: wp.array[wp.int32]
    inputs: wp.array[wp.int32]  # this and the other (ndrive, 3) tables flattened: 3 per drive
    acceleration: wp.array[wp.int32]
    enabled: wp.array[wp.int32]
    input_enabled: wp.array[wp.int32]
    delayed: wp.array[wp.int32]
    outputs: wp.array[wp.int32]
    native: wp.array[wp.int32]
    damping_adr: wp.array[wp.int32]
    damping_num: wp.array[wp.int32]
    damping_actuator: wp.array[wp.int32]


@wp.kernel(enable_backward=False)
def _smooth_force_kernel(
    dof_jntid: wp.array[int],
    jnt_actgravcomp: wp.array[int],
    native: wp.array[wp.int32],
    gravity: bool,
    qfrc_passive: wp.array2d[float],
    qfrc_bias: wp.array2d[float],
    qfrc_applied: wp.array2d[float],
    qfrc_gravcomp: wp.array2d[float],
    actuator_force: wp.array2d[float],
    moment_rownnz: wp.array2d[int],
    moment_rowadr: wp.array2d[int],
    moment_colind: wp.array2d[int],
    actuator_moment: wp.array2d[float],
    force: wp.array2d[float],
):
    """force[w] = passive - bias + applied + gravcomp (actuator level) + sum_a moment_a*force_a.

    The sum runs over the other actuators (``native``): the drives see their forces coming.
    """
    w = wp.tid()
    for i in range(force.shape[1]):
        f = qfrc_passive[w, i] - qfrc_bias[w, i] + qfrc_applied[w, i]
        if gravity and jnt_actgravcomp[dof_jntid[i]] != 0:
            f += qfrc_gravcomp[w, i]
        force[w, i] = f
    for k in range(native.shape[0]):
        a = native[k]
        fa = actuator_force[w, a]
        if fa != 0.0:
            adr = moment_rowadr[w, a]
            for j in range(moment_rownnz[w, a]):
                force[w, moment_colind[w, adr + j]] += actuator_moment[w, adr + j] * fa


@wp.kernel(enable_backward=False)
def _weight_kernel(
    body_mass: wp.array2d[float],
    opt_gravity: wp.array[wp.vec3],
    gravity: bool,
    weight: wp.array2d[wp.spatial_vector],
):
    """weight[w, b] = (m_b*g, 0): each body's weight as MJWarp's body wrenches (force, torque)."""
    w, b = wp.tid()
    g = wp.vec3(0.0)
    if gravity:
        g = opt_gravity[w % opt_gravity.shape[0]] * body_mass[w % body_mass.shape[0], b]
    weight[w, b] = wp.spatial_vector(g, wp.vec3(0.0))


@wp.kernel(enable_backward=False)
def _bias_force_kernel(
    qfrc_bias: wp.array2d[float], gravity_force: wp.array2d[float], bias: wp.array2d[float]
):
    """bias[w] = -qfrc_bias - J'*m*g: the smooth force's velocity-dependent part (TGS: applied once)."""
    w, i = wp.tid()
    bias[w, i] = -qfrc_bias[w, i] - gravity_force[w, i]


@wp.func
def _slot(value: wp.float32, unlimited: bool):
    """A dynprm number widened to float64: (value, valid); -1 is inf where ``unlimited``."""
    x = wp.float64(value)
    if unlimited and x == wp.float64(-1.0):
        return _INF, True
    return x, x >= wp.float64(0.0) and x <= _BOUND


@wp.func
def _control(
    ctrl: wp.array2d[float],
    delayed: wp.array2d[float],
    actuator_ctrladr: wp.array[int],
    actuator_ctrllimited: wp.array[bool],
    actuator_ctrlrange: wp.array2d[wp.vec2],
    clampctrl: bool,
    w: int,
    actuator: int,
    row: int,
):
    """An input's control as native actuators read it: delayed (``row`` >= 0), then clamped to ctrlrange."""
    adr = actuator_ctrladr[actuator]
    u = wp.float64(ctrl[w, adr])
    if row >= 0:
        u = wp.float64(delayed[row, w])
    if clampctrl and actuator_ctrllimited[adr]:
        bounds = actuator_ctrlrange[w % actuator_ctrlrange.shape[0], adr]
        u = wp.clamp(u, wp.float64(bounds[0]), wp.float64(bounds[1]))
    return u


@wp.func
def _bad(u: wp.float64) -> bool:
    """MuJoCo's mju_isBad: NaN or |u| > 1e10."""
    return not (wp.abs(u) <= _MAXVAL)


@wp.func
def _damping_derivative(
    dof_damping: wp.array2d[float],
    dof_dampingpoly: wp.array2d[wp.vec2],
    actuator_damping: wp.array2d[float],
    actuator_dampingpoly: wp.array2d[wp.vec2],
    actuator_gear: wp.array2d[wp.spatial_vector],
    drives: DriveArrays,
    qvel: wp.array2d[float],
    w: int,
    i: int,
):
    """d(damping force)/d(qvel) of DOF i [N*m*s/rad or N*s/m]: D + 2*p0*|v| + 3*p1*v^2 (mjd_xPolyForce).

    D and (p0, p1) are the DOF's and its joint's actuators' (``damping * gear^2``), as MuJoCo sums them.
    """
    damping = wp.float64(dof_damping[w % dof_damping.shape[0], i])
    poly = dof_dampingpoly[w % dof_dampingpoly.shape[0], i]
    p0 = wp.float64(poly[0])
    p1 = wp.float64(poly[1])
    for k in range(drives.damping_num[i]):
        a = drives.damping_actuator[drives.damping_adr[i] + k]
        gear = wp.float64(actuator_gear[w % actuator_gear.shape[0], a][0])
        scale = gear * gear
        damping += wp.float64(actuator_damping[w % actuator_damping.shape[0], a]) * scale
        apoly = actuator_dampingpoly[w % actuator_dampingpoly.shape[0], a]
        p0 += wp.float64(apoly[0]) * scale
        p1 += wp.float64(apoly[1]) * scale
    speed = wp.abs(wp.float64(qvel[w, i]))
    return damping + wp.float64(2.0) * p0 * speed + wp.float64(3.0) * p1 * speed * speed


@wp.func
def _factor(
    work: Work, lay: Layout, M_rownnz: wp.array[int], M_rowadr: wp.array[int], M_colind: wp.array[int], w: int
):
    """Factor the matrix at ``lay.mh`` in place as M = L' D L (MuJoCo's mj_factorI), 1/D to ``lay.dinv``.

    Rows from the leaves: row k's entries up to column i are row i's pattern (a DOF's ancestors),
    so row i -= L(k, i)/D_k * row k over its own length.
    """
    for k in range(lay.nv - 1, -1, -1):
        start = M_rowadr[k]
        diag = start + M_rownnz[k] - 1
        dk = work[lay.mh + diag, w]
        if dk < _MINVAL:
            dk = _MINVAL
        inverse = wp.float64(1.0) / dk
        work[lay.dinv + k, w] = inverse
        for adr in range(diag - 1, start - 1, -1):
            i = M_colind[adr]
            scale = -work[lay.mh + adr, w] * inverse
            row = M_rowadr[i]
            for j in range(M_rownnz[i]):
                work[lay.mh + row + j, w] = work[lay.mh + row + j, w] + scale * work[lay.mh + start + j, w]
        for adr in range(start, diag):
            work[lay.mh + adr, w] = work[lay.mh + adr, w] * inverse


@wp.func
def _back_substitute(
    work: Work,
    lay: Layout,
    M_rownnz: wp.array[int],
    M_rowadr: wp.array[int],
    M_colind: wp.array[int],
    w: int,
    b: int,
    top: int,
):
    """Solve L' z = b in place for the vector at ``b`` (nonzero at DOFs <= ``top`` only)."""
    for k in range(top, -1, -1):
        zk = work[b + k, w]
        if zk != wp.float64(0.0):
            start = M_rowadr[k]
            for adr in range(start, start + M_rownnz[k] - 1):
                i = M_colind[adr]
                work[b + i, w] = work[b + i, w] - work[lay.mh + adr, w] * zk


@wp.func
def _dot_dinv(work: Work, lay: Layout, w: int, u: int, v: int, top: int) -> wp.float64:
    """The product u' D^-1 v over DOFs 0..top."""
    total = wp.float64(0.0)
    for k in range(top + 1):
        total += work[u + k, w] * work[lay.dinv + k, w] * work[v + k, w]
    return total


@wp.func
def _read_requests(
    actuator_dynprm: wp.array2d[_vec10],
    actuator_ctrladr: wp.array[int],
    actuator_ctrllimited: wp.array[bool],
    actuator_ctrlrange: wp.array2d[wp.vec2],
    drives: DriveArrays,
    clampctrl: bool,
    qpos: wp.array2d[float],
    ctrl: wp.array2d[float],
    delayed: wp.array2d[float],
    lay: Layout,
    work: Work,
    iwork: IntWork,
    w: int,
) -> bool:
    """Each drive's numbers and inputs into the scratch; returns whether any drive gives effort.

    A drive in a disabled group, or whose numbers are not valid (each in [0, 1e12], -1 = no limit
    for the first two, slots 6..9 zero), gives 0; a disabled input contributes 0; one bad control
    (NaN, > 1e10) anywhere zeroes every input, as MuJoCo zeroes every control.
    """
    zero = wp.float64(0.0)
    any_active = wp.bool(False)
    bad = wp.bool(False)
    for k in range(lay.n):
        iwork[lay.active + k, w] = 0
        work[lay.effort + k, w] = zero
        if drives.enabled[k] != 0:
            prm = actuator_dynprm[w % actuator_dynprm.shape[0], drives.actuator[k]]
            ok = wp.bool(True)
            for s in range(6):
                value, good = _slot(prm[s], s < 2)
                ok = ok and good
                work[lay.prm + 6 * k + s, w] = value
            for s in range(6, 10):
                ok = ok and prm[s] == wp.float32(0.0)
            if ok:
                u0, u1, u2 = zero, zero, zero
                for s in range(3):
                    a = drives.inputs[3 * k + s]
                    if a >= 0 and drives.input_enabled[3 * k + s] != 0:
                        u = _control(
                            ctrl,
                            delayed,
                            actuator_ctrladr,
                            actuator_ctrllimited,
                            actuator_ctrlrange,
                            clampctrl,
                            w,
                            a,
                            drives.delayed[3 * k + s],
                        )
                        bad = bad or _bad(u)
                        if s == 0:
                            u0 = u
                        elif s == 1:
                            u1 = u
                        else:
                            u2 = u
                work[lay.err + k, w] = u0 - wp.float64(qpos[w, drives.qpos[k]])
                work[lay.tvel + k, w] = u1
                work[lay.ff + k, w] = u2
                iwork[lay.active + k, w] = 1
                any_active = True
    for i in range(ctrl.shape[1]):
        bad = bad or _bad(wp.float64(ctrl[w, i]))
    if bad:
        for k in range(lay.n):
            work[lay.err + k, w] = -wp.float64(qpos[w, drives.qpos[k]])
            work[lay.tvel + k, w] = zero
            work[lay.ff + k, w] = zero
    return any_active


@wp.func
def _prepare(work: Work, iwork: IntWork, lay: Layout, accel: wp.array[wp.int32], w: int, h: wp.float64):
    """Each drive's unclamped law w = c - alpha*v1: J = b - a*v1 (force) or (b - a*v1)/r (acceleration).

    a = h*(h*k + c), b = h*k*(q* - q) + h*c*v*, plus the feed-forward impulse ff*h in c.
    """
    for r in range(lay.n):
        c = wp.float64(0.0)
        alpha = wp.float64(0.0)
        if iwork[lay.active + r, w] != 0:
            p = lay.prm + 6 * r
            reff = work[lay.a + r * lay.n + r, w]
            stiffness = work[p + 4, w]
            damping = work[p + 5, w]
            a = h * (h * stiffness + damping)
            b = h * stiffness * work[lay.err + r, w] + h * damping * work[lay.tvel + r, w]
            c = work[lay.ff + r, w] * h
            if accel[r] != 0:
                c += b / reff
                alpha = a / reff
            elif reff > wp.float64(0.0):
                c += b
                alpha = a
        work[lay.c + r, w] = c
        work[lay.alpha + r, w] = alpha


@wp.kernel(enable_backward=False)
def _drive_kernel(
    opt_timestep: wp.array[float],
    M_rownnz: wp.array[int],
    M_rowadr: wp.array[int],
    M_colind: wp.array[int],
    actuator_dynprm: wp.array2d[_vec10],
    actuator_ctrladr: wp.array[int],
    actuator_ctrllimited: wp.array[bool],
    actuator_ctrlrange: wp.array2d[wp.vec2],
    dof_damping: wp.array2d[float],
    dof_dampingpoly: wp.array2d[wp.vec2],
    actuator_damping: wp.array2d[float],
    actuator_dampingpoly: wp.array2d[wp.vec2],
    actuator_gear: wp.array2d[wp.spatial_vector],
    drives: DriveArrays,
    clampctrl: bool,
    implicit_damping: bool,
    track: bool,
    solver_kind: int,
    position_iterations: int,
    velocity_iterations: int,
    lay: Layout,
    qpos: wp.array2d[float],
    qvel: wp.array2d[float],
    ctrl: wp.array2d[float],
    M: wp.array2d[float],
    delayed: wp.array2d[float],
    force: wp.array2d[float],
    bias: wp.array2d[float],
    work: Work,
    iwork: IntWork,
    stats: wp.array2d[wp.int32],
    actuator_force: wp.array2d[float],
):
    """actuator_force[w, effort actuator of drive k] = tau_k, the coupled implicit solve of every drive.

    tau = clamp of PhysX's implicit PD law at the end-of-step velocity v1 = vfree + h*A*tau, all drives
    at once (A = (M + h*D')^-1 over the driven DOFs); the drives' other actuators get 0.
    """
    w = wp.tid()
    n = lay.n
    accel = drives.acceleration
    h = wp.float64(opt_timestep[w % opt_timestep.shape[0]])
    iterations = wp.int32(0)
    iwork[lay.solves, w] = 0
    valid = h > wp.float64(0.0) and h - h == wp.float64(0.0)
    active = False
    if valid:
        active = _read_requests(
            actuator_dynprm,
            actuator_ctrladr,
            actuator_ctrllimited,
            actuator_ctrlrange,
            drives,
            clampctrl,
            qpos,
            ctrl,
            delayed,
            lay,
            work,
            iwork,
            w,
        )
    if active:
        for i in range(M.shape[1]):
            work[lay.mh + i, w] = wp.float64(M[w, i])
        if implicit_damping:
            for i in range(lay.nv):
                diag = M_rowadr[i] + M_rownnz[i] - 1
                deriv = _damping_derivative(
                    dof_damping,
                    dof_dampingpoly,
                    actuator_damping,
                    actuator_dampingpoly,
                    actuator_gear,
                    drives,
                    qvel,
                    w,
                    i,
                )
                work[lay.mh + diag, w] = work[lay.mh + diag, w] + h * deriv
        _factor(work, lay, M_rownnz, M_rowadr, M_colind, w)
        for i in range(lay.nv):
            work[lay.y + i, w] = wp.float64(force[w, i])
        _back_substitute(work, lay, M_rownnz, M_rowadr, M_colind, w, lay.y, lay.nv - 1)
        for r in range(n):
            z = lay.z + r * lay.nv
            dof = drives.dof[r]
            for i in range(dof + 1):
                work[z + i, w] = wp.float64(0.0)
            work[z + dof, w] = wp.float64(1.0)
            _back_substitute(work, lay, M_rownnz, M_rowadr, M_colind, w, z, dof)
            work[lay.vfree + r, w] = wp.float64(qvel[w, dof]) + h * _dot_dinv(work, lay, w, z, lay.y, dof)
        for r in range(n):
            for s in range(r, n):
                entry = _dot_dinv(work, lay, w, lay.z + r * lay.nv, lay.z + s * lay.nv, drives.dof[r])
                work[lay.a + r * n + s, w] = entry
                work[lay.a + s * n + r, w] = entry
        if solver_kind == 0:
            _prepare(work, iwork, lay, accel, w, h)
            iterations = solve_drives(work, iwork, lay, accel, w, h)
        else:  # PhysX's PGS or TGS iteration (drive_envelope_solver numeric)
            for r in range(n):
                work[lay.qvel + r, w] = wp.float64(qvel[w, drives.dof[r]])
                work[lay.bias + r, w] = wp.float64(0.0)
            if solver_kind == 2:  # TGS: the bias's share of vfree, applied before the substeps
                for i in range(lay.nv):
                    work[lay.y + i, w] = wp.float64(bias[w, i])
                _back_substitute(work, lay, M_rownnz, M_rowadr, M_colind, w, lay.y, lay.nv - 1)
                for r in range(n):
                    z = lay.z + r * lay.nv
                    work[lay.bias + r, w] = h * _dot_dinv(work, lay, w, z, lay.y, drives.dof[r])
            iterations = articulation(
                work, iwork, lay, accel, w, h, solver_kind, position_iterations, velocity_iterations
            )
    for k in range(n):
        for s in range(3):
            a = drives.outputs[3 * k + s]
            if a >= 0:
                actuator_force[w, a] = 0.0
        if iwork[lay.active + k, w] != 0:
            actuator_force[w, drives.actuator[k]] = wp.float32(work[lay.effort + k, w])
    if track:
        stats[w, 0] = iterations
        stats[w, 1] = iwork[lay.solves, w]

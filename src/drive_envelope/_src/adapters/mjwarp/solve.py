# mypy: disable-error-code="index,valid-type,operator,assignment,misc,arg-type,attr-defined,return-value"
# (Warp function bodies index wp.array values and annotate with Warp types, which mypy does not follow)
"""The coupled drive solve of one world, as ``@wp.func`` blocks: ``plugin/mujoco/solve.cc`` in Warp.

One thread per world runs it in float64 (MJWarp's float32 state is widened exactly): the same
algorithm, constants and convergence tests as the C plugin, so the two are reviewed line by line.
The one difference is where joint damping goes: the C plugin factors ``M`` and carries each damped
DOF as an extra row, here the kernel factors ``M + h*D'`` (the matrix MJWarp's Euler step
inverts), so the rows are the drives alone and every damping impulse is already in ``A``; both
reach the same fixed point.

Per-world scratch lives in two buffers, ``work`` (float64) and ``iwork`` (int32), shaped
``(slot, nworld)`` so that neighbouring worlds read neighbouring addresses; :class:`Layout` holds
the slot offsets. The clamp is the library's one Warp clamp, ``clamp_drive_impulse_func``.
"""

import warp as wp

from drive_envelope._src.kernels.warp_funcs import clamp_drive_impulse_func, implicit_drive_impulse

# x*r - v0 must round twice, as in the clamp's other backends (see kernels/warp_funcs.py)
wp.set_module_options({"fuse_fp": False})

MAX_NEWTON = 8
"""At most this many Newton steps per step (the C plugin's kMaxNewton)."""
MAX_SWEEPS = 50
"""Then at most this many Gauss-Seidel sweeps (kMaxSweeps)."""
MAX_FLIPS = 2
"""A drive that switches between letting go and a nonzero effort this often lets go (kMaxFlips)."""

_TOL = wp.constant(wp.float64(1e-12))  # converged: no velocity moves by more than 1e-12*(1 + |v|)
_MARGIN = wp.constant(wp.float64(1e-9))  # "inside": relative margin of the linear solve's answer
_MINVAL = wp.constant(wp.float64(1e-15))  # MuJoCo's mjMINVAL: smallest pivot
_STEP = wp.constant(wp.float64(1e-7))  # relative step of a clamped row's measured slope
_MAX_NEWTON = wp.constant(MAX_NEWTON)
_MAX_SWEEPS = wp.constant(MAX_SWEEPS)
_MAX_FLIPS = wp.constant(MAX_FLIPS)

Work = wp.array2d[wp.float64]
"""The float64 scratch of every world, ``work[slot, world]`` (the slots: :class:`Layout`)."""
IntWork = wp.array2d[wp.int32]
"""The int32 scratch, ``iwork[slot, world]``."""


@wp.struct
class Layout:
    """Slot offsets of one world's scratch in ``work`` (float64) and ``iwork`` (int32)."""

    n: int  # drives
    nv: int  # DOFs
    mh: int  # M + h*D' in MuJoCo's sparse layout, factored in place into L (nC slots)
    dinv: int  # 1/D of the factorization (nv)
    y: int  # L^-T f (nv)
    z: int  # Z = L^-T [e_dof of each drive] (n*nv)
    a: int  # A = Z' D^-1 Z, the block of (M + h*D')^-1 over the driven DOFs (n*n)
    q: int  # matrix of the linear solves (n*n)
    vfree: int  # end-of-step velocity without drives (n)
    c: int  # constant of each drive's unclamped law w = c - alpha*v1 (n)
    alpha: int  # its slope (n)
    x: int  # each drive's total impulse (n)
    v: int  # the end-of-step velocities they give (n)
    rest: int  # velocity without the drive's own impulse (n)
    slope: int  # Newton slopes (n)
    b: int  # right-hand side of the linear solves (n; not "rhs": Warp names its operator argument so)
    gx: int  # each drive's own solve (n)
    effort: int  # each drive's effort (n)
    prm: int  # six numbers per drive, -1 turned into inf (6n)
    err: int  # position target - qpos (n)
    tvel: int  # velocity target (n)
    ff: int  # feed-forward effort (n)
    desc: int  # pgs/tgs: PhysX's implicit drive law per drive, 5 numbers (5n)
    moved: int  # pgs/tgs: displacement since the step began (n)
    qvel: int  # pgs/tgs: velocity at the start of the step (n)
    bias: int  # tgs: h*(M + h*D')^-1 times the velocity-dependent bias, per drive (n)
    active: int  # iwork: 1 when the drive gives effort this step (n)
    released: int  # iwork: last own solve was 0 (-1: none yet) (n)
    flips: int  # iwork: switches between 0 and nonzero (n)
    stale: int  # iwork: Gauss-Seidel must solve the drive again (n)
    clamped: int  # iwork: the envelope changed the request (n)
    free: int  # iwork: rows of the linear solve (n)
    fixed: int  # iwork: rows with w = c (n)
    solves: int  # iwork: drive solves (clamp evaluations) this step (1)


@wp.func
def _finite(x: wp.float64) -> bool:
    """False for NaN and +-inf (x - x is NaN for both)."""
    return x - x == wp.float64(0.0)


@wp.func
def _cholesky_solve(work: Work, q: int, b: int, m: int, w: int) -> bool:
    """Solve q*x = b in place (b becomes x), q symmetric positive definite m x m, row-major at ``q``.

    Right-looking Cholesky; the diagonal keeps 1/L_kk. False if q is not positive definite.
    """
    for k in range(m):
        pivot = work[q + k * m + k, w]
        if not (pivot > _MINVAL) or not _finite(pivot):
            return False
        inverse = wp.float64(1.0) / wp.sqrt(pivot)
        work[q + k * m + k, w] = inverse
        for i in range(k + 1, m):
            work[q + i * m + k, w] = work[q + i * m + k, w] * inverse
        for i in range(k + 1, m):
            lik = work[q + i * m + k, w]
            for j in range(k + 1, i + 1):
                work[q + i * m + j, w] = work[q + i * m + j, w] - lik * work[q + j * m + k, w]
    for i in range(m):  # L*y = b
        bi = work[b + i, w]
        for j in range(i):
            bi = bi - work[q + i * m + j, w] * work[b + j, w]
        work[b + i, w] = bi * work[q + i * m + i, w]
    for i in range(m - 1, -1, -1):  # L'*x = y
        bi = work[b + i, w] * work[q + i * m + i, w]
        work[b + i, w] = bi
        for j in range(i):
            work[b + j, w] = work[b + j, w] - work[q + i * m + j, w] * bi
    return True


@wp.func
def _lu_solve(work: Work, a: int, b: int, n: int, w: int) -> bool:
    """Solve a*x = b in place (b becomes x), a general n x n row-major at ``a``; partial pivoting.

    False if a is singular.
    """
    for k in range(n):
        best = k
        for i in range(k + 1, n):
            if wp.abs(work[a + i * n + k, w]) > wp.abs(work[a + best * n + k, w]):
                best = i
        if not (wp.abs(work[a + best * n + k, w]) > _MINVAL):
            return False
        if best != k:
            for j in range(n):
                t = work[a + k * n + j, w]
                work[a + k * n + j, w] = work[a + best * n + j, w]
                work[a + best * n + j, w] = t
            t = work[b + k, w]
            work[b + k, w] = work[b + best, w]
            work[b + best, w] = t
        inverse = wp.float64(1.0) / work[a + k * n + k, w]
        for i in range(k + 1, n):
            factor = work[a + i * n + k, w] * inverse
            if factor != wp.float64(0.0):
                for j in range(k + 1, n):
                    work[a + i * n + j, w] = work[a + i * n + j, w] - factor * work[a + k * n + j, w]
                work[b + i, w] = work[b + i, w] - factor * work[b + k, w]
    for i in range(n - 1, -1, -1):
        bi = work[b + i, w]
        for j in range(i + 1, n):
            bi = bi - work[a + i * n + j, w] * work[b + j, w]
        work[b + i, w] = bi / work[a + i * n + i, w]
    return True


@wp.func
def _inside(work: Work, lay: Layout, w: int, r: int, dt: wp.float64, x: wp.float64, v: wp.float64):
    """Whether (x, v) lies inside drive r's envelope by a relative 1e-9: the clamp returns x unchanged."""
    p = lay.prm + 6 * r
    ax = wp.abs(x)
    av = wp.abs(v)
    xmax = work[p, w] * dt
    vmax = work[p + 1, w]
    effort_ok = wp.isinf(xmax) or xmax - work[p + 2, w] * dt * av - ax > _MARGIN * xmax
    speed_ok = wp.isinf(vmax) or vmax - work[p + 3, w] / dt * ax - av > _MARGIN * vmax
    return effort_ok and speed_ok


@wp.func
def _row_solve(
    work: Work,
    iwork: IntWork,
    lay: Layout,
    accel: wp.array[wp.int32],
    w: int,
    r: int,
    rest: wp.float64,
    dt: wp.float64,
    hold: bool,
):
    """Drive r's own solve at the velocity ``rest`` the others give it: PD impulse, then the clamp.

    Returns (impulse x [N*m*s or N*s], effort [N*m or N], 1 if the envelope changed the request).
    The clamp is on the TOTAL actuator impulse (drive + ff) at the end-of-step velocity. With
    ``hold``, a drive that switched MAX_FLIPS times lets go (0), as in Newton.
    """
    iwork[lay.solves, w] = iwork[lay.solves, w] + 1
    zero = wp.float64(0.0)
    response = work[lay.a + r * lay.n + r, w]
    if iwork[lay.active + r, w] == 0 or (hold and iwork[lay.flips + r, w] >= _MAX_FLIPS):
        return zero, zero, 0
    p = lay.prm + 6 * r
    ff = work[lay.ff + r, w] * dt
    v0 = rest + response * ff
    request = ff + implicit_drive_impulse(
        work[p + 4, w],
        work[p + 5, w],
        work[lay.err + r, w],
        v0,
        work[lay.tvel + r, w],
        response,
        dt,
        accel[r],
    )
    x = clamp_drive_impulse_func(
        v0, ff, request, response, work[p + 1, w], work[p, w] * dt, work[p + 3, w] / dt, work[p + 2, w] * dt
    )
    # NaN or overflowing states: the drive lets go instead of writing NaN; and (x*dt)/dt can round
    # one ulp above the request: the clamp never grows a request, nor may we
    effort = zero
    if _finite(x):
        effort = x / dt
    limit = wp.abs(request / dt)
    if not (wp.abs(effort) < limit):
        effort = wp.where(effort < zero, -limit, limit)
    if not _finite(effort):
        effort = zero
    if not _finite(x):
        x = zero
    return x, effort, wp.where(x != request, 1, 0)


@wp.func
def _track(work: Work, iwork: IntWork, lay: Layout, w: int, r: int, x: wp.float64, effort: wp.float64):
    """Record drive r's result; count its switches between letting go (0) and an effort (the latch)."""
    if iwork[lay.active + r, w] == 0:
        return
    zero = wp.where(x == wp.float64(0.0), 1, 0)
    last = iwork[lay.released + r, w]
    if last >= 0 and zero != last:
        iwork[lay.flips + r, w] = iwork[lay.flips + r, w] + 1
    iwork[lay.released + r, w] = zero
    work[lay.effort + r, w] = effort


@wp.func
def propagate(work: Work, lay: Layout, w: int, r: int, impulse: wp.float64):
    """An impulse on drive r moves every drive's velocity through A's column r (A is symmetric)."""
    if impulse != wp.float64(0.0) and _finite(impulse):
        for s in range(lay.n):
            work[lay.v + s, w] = work[lay.v + s, w] + work[lay.a + r * lay.n + s, w] * impulse


@wp.func
def _velocities(work: Work, lay: Layout, w: int):
    """The end-of-step velocities of the (finite) impulses: v = vfree + A*x."""
    for r in range(lay.n):
        work[lay.v + r, w] = work[lay.vfree + r, w]
    for r in range(lay.n):
        propagate(work, lay, w, r, work[lay.x + r, w])


@wp.func
def _linear_guess(work: Work, iwork: IntWork, lay: Layout, w: int):
    """Every drive's unclamped law at once: (diag(1/alpha) + A) x = c/alpha - vfree, into ``x``.

    Drives with alpha ~ 0 keep x = c; a failed factorization falls back to one Jacobi step from vfree
    (Newton and the sweeps then correct it, so it only costs iterations).
    """
    n = lay.n
    m = wp.int32(0)
    nfixed = wp.int32(0)
    for r in range(n):
        work[lay.x + r, w] = work[lay.c + r, w]
        if work[lay.alpha + r, w] * work[lay.a + r * n + r, w] > wp.float64(1e-12):
            iwork[lay.free + m, w] = r
            m += 1
        else:
            iwork[lay.fixed + nfixed, w] = r
            nfixed += 1
    if m > 0:
        for i in range(m):
            r = iwork[lay.free + i, w]
            alpha = work[lay.alpha + r, w]
            rhs = work[lay.c + r, w] / alpha - work[lay.vfree + r, w]
            for f in range(nfixed):
                s = iwork[lay.fixed + f, w]
                rhs = rhs - work[lay.a + r * n + s, w] * work[lay.c + s, w]
            work[lay.b + i, w] = rhs
            for j in range(m):
                work[lay.q + i * m + j, w] = work[lay.a + r * n + iwork[lay.free + j, w], w]
            work[lay.q + i * m + i, w] = work[lay.q + i * m + i, w] + wp.float64(1.0) / alpha
        if _cholesky_solve(work, lay.q, lay.b, m, w):
            for i in range(m):
                work[lay.x + iwork[lay.free + i, w], w] = work[lay.b + i, w]
        else:
            for r in range(n):
                work[lay.x + r, w] = work[lay.c + r, w] - work[lay.alpha + r, w] * work[lay.vfree + r, w]
    for r in range(n):
        if not _finite(work[lay.x + r, w]):
            work[lay.x + r, w] = wp.float64(0.0)


@wp.func
def _newton(work: Work, iwork: IntWork, lay: Layout, accel: wp.array[wp.int32], w: int, dt: wp.float64):
    """Newton's method on x_r = G_r(rest_r(x)), G_r a drive's own solve; returns (converged, steps).

    G_r is piecewise linear: slope -alpha/(1 + alpha*A_rr) where the clamp did not bind, else
    measured (two more clamp evaluations). Each step solves (I - diag(slope)*A_off) x = G -
    slope*(rest - vfree) by LU.
    """
    n = lay.n
    for it in range(_MAX_NEWTON):
        residual = wp.float64(0.0)
        for r in range(n):
            response = work[lay.a + r * n + r, w]
            held = work[lay.x + r, w]
            rest = work[lay.v + r, w] - response * held
            work[lay.rest + r, w] = rest
            gx, effort, clamped = _row_solve(work, iwork, lay, accel, w, r, rest, dt, True)
            work[lay.gx + r, w] = gx
            iwork[lay.clamped + r, w] = clamped
            _track(work, iwork, lay, w, r, gx, effort)
            moved = wp.abs(gx - held) * response / (wp.float64(1.0) + wp.abs(work[lay.v + r, w]))
            residual = wp.max(residual, moved)
        if not (residual > _TOL):
            for r in range(n):
                work[lay.x + r, w] = work[lay.gx + r, w]
            _velocities(work, lay, w)
            return True, it + 1
        for r in range(n):
            response = work[lay.a + r * n + r, w]
            alpha = work[lay.alpha + r, w]
            slope = wp.float64(0.0)  # let go: nothing responds (damping is inside A)
            if iwork[lay.flips + r, w] < _MAX_FLIPS:
                if iwork[lay.clamped + r, w] == 0:
                    slope = -alpha / (wp.float64(1.0) + alpha * response)
                else:  # the slope on the side where it is smaller (away from a kink)
                    rest = work[lay.rest + r, w]
                    step = _STEP * (wp.float64(1.0) + wp.abs(rest))
                    up, _e_up, _c_up = _row_solve(work, iwork, lay, accel, w, r, rest + step, dt, True)
                    down, _e_down, _c_down = _row_solve(work, iwork, lay, accel, w, r, rest - step, dt, True)
                    rise = (up - work[lay.gx + r, w]) / step
                    fall = (work[lay.gx + r, w] - down) / step
                    slope = wp.where(wp.abs(rise) < wp.abs(fall), rise, fall)
            work[lay.slope + r, w] = slope
        for r in range(n):
            slope = work[lay.slope + r, w]
            for s in range(n):
                entry = -slope * work[lay.a + r * n + s, w]
                if s == r:
                    entry = wp.float64(1.0)
                work[lay.q + r * n + s, w] = entry
            rest = work[lay.rest + r, w]
            work[lay.b + r, w] = work[lay.gx + r, w] - slope * (rest - work[lay.vfree + r, w])
        if not _lu_solve(work, lay.q, lay.b, n, w):
            return False, it + 1
        for r in range(n):
            if not _finite(work[lay.b + r, w]):
                return False, it + 1
        for r in range(n):
            work[lay.x + r, w] = work[lay.b + r, w]
        _velocities(work, lay, w)
    return False, _MAX_NEWTON


@wp.func
def _gauss_seidel(
    work: Work, iwork: IntWork, lay: Layout, accel: wp.array[wp.int32], w: int, dt: wp.float64, hold: bool
):
    """Gauss-Seidel over the drives in DOF order from where Newton left; returns (sweeps, settled).

    A drive is solved again when another's update moved its velocity by more than 1e-12*(1 + |v|);
    it stops after a sweep that solved no drive (settled) or after MAX_SWEEPS. Without ``hold`` no
    drive is held let go, and a drive switching more than MAX_FLIPS times ends the sweeps (a cycle).
    """
    n = lay.n
    for r in range(n):
        iwork[lay.stale + r, w] = 1
    sweeps = wp.int32(0)
    while sweeps < _MAX_SWEEPS:
        if not hold:
            cycling = wp.bool(False)
            for r in range(n):
                cycling = cycling or iwork[lay.flips + r, w] > _MAX_FLIPS
            if cycling:
                return sweeps, False
        solved = wp.bool(False)
        for r in range(n):
            if iwork[lay.stale + r, w] != 0:
                iwork[lay.stale + r, w] = 0
                solved = True
                response = work[lay.a + r * n + r, w]
                held = work[lay.x + r, w]
                rest = work[lay.v + r, w] - response * held  # velocity without this drive's impulse
                gx, effort, _clamped = _row_solve(work, iwork, lay, accel, w, r, rest, dt, hold)
                _track(work, iwork, lay, w, r, gx, effort)
                delta = gx - held
                work[lay.x + r, w] = gx
                work[lay.v + r, w] = rest + response * gx
                if delta != wp.float64(0.0) and _finite(delta):
                    for s in range(n):
                        dv = work[lay.a + r * n + s, w] * delta
                        if s != r and dv != wp.float64(0.0):
                            vs = work[lay.v + s, w] + dv
                            work[lay.v + s, w] = vs
                            if wp.abs(dv) > _TOL * (wp.float64(1.0) + wp.abs(vs)):
                                iwork[lay.stale + s, w] = 1
        if not solved:
            return sweeps, True
        sweeps += 1
    return sweeps, False


@wp.func
def _held_let_go(work: Work, iwork: IntWork, lay: Layout, accel: wp.array[wp.int32], w: int, dt: wp.float64):
    """Whether each drive Newton held let go (MAX_FLIPS switches) lets go by its own solve too (HeldLetGo)."""
    for r in range(lay.n):
        if iwork[lay.active + r, w] != 0 and iwork[lay.flips + r, w] >= _MAX_FLIPS:
            rest = work[lay.v + r, w] - work[lay.a + r * lay.n + r, w] * work[lay.x + r, w]
            own, _effort, _clamped = _row_solve(work, iwork, lay, accel, w, r, rest, dt, False)
            if own != wp.float64(0.0):
                return False
    return True


@wp.func
def solve_drives(work: Work, iwork: IntWork, lay: Layout, accel: wp.array[wp.int32], w: int, dt: wp.float64):
    """Every drive's effort into ``work[lay.effort]``; returns the iterations (0: the linear solve sufficed).

    The linear solve of the unclamped laws; if every drive is inside its envelope by 1e-9 that is
    the answer, else Newton steps, then Gauss-Seidel sweeps if Newton has not converged.
    """
    n = lay.n
    _linear_guess(work, iwork, lay, w)
    _velocities(work, lay, w)
    outside = wp.bool(False)
    for r in range(n):
        iwork[lay.released + r, w] = -1
        iwork[lay.flips + r, w] = 0
        if iwork[lay.active + r, w] != 0:
            x = work[lay.x + r, w]
            outside = outside or not _inside(work, lay, w, r, dt, x, work[lay.v + r, w])
            work[lay.effort + r, w] = x / dt
        else:
            work[lay.x + r, w] = wp.float64(0.0)
    if not outside:
        return 0
    converged, steps = _newton(work, iwork, lay, accel, w, dt)
    if converged and _held_let_go(work, iwork, lay, accel, w, dt):
        return steps
    if not converged:
        sweeps, _settled = _gauss_seidel(work, iwork, lay, accel, w, dt, True)
        return steps + sweeps
    # Newton held a drive let go that its own solve would drive: Gauss-Seidel without holding, from
    # Newton's answer (kept in gx and slope, unused by the sweeps) if the sweeps do not settle
    for r in range(n):
        work[lay.gx + r, w] = work[lay.x + r, w]
        work[lay.slope + r, w] = work[lay.effort + r, w]
        iwork[lay.released + r, w] = -1
        iwork[lay.flips + r, w] = 0
    sweeps, settled = _gauss_seidel(work, iwork, lay, accel, w, dt, False)
    if not settled:
        for r in range(n):
            work[lay.x + r, w] = work[lay.gx + r, w]
            work[lay.effort + r, w] = work[lay.slope + r, w]
    return steps + sweeps

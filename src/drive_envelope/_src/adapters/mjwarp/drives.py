"""The MJWarp ``act_bias`` callback that gives every envelope drive the plugin's law each step.

MJWarp runs ``Model.callback.act_bias(m, d)`` inside ``fwd_actuation``, after the built-in
actuator forces (``forcerange`` applied) and before they become ``qfrc_actuator``: at that point
``M`` (``fwd_position``), ``qfrc_passive`` and ``qfrc_bias`` (``fwd_velocity``) are the step's, so
the drives see what MJWarp will integrate. Each call launches, for all worlds at once: MJWarp's
``read_ctrl`` for each delayed input, the smooth-force kernel, MJWarp's ``xfrc_accumulate``, and
the drive kernel (one thread per world). Scratch is allocated per call, as MJWarp's own
integrators allocate theirs, and every branch below depends on the model's flags only: the call
makes no host synchronization and records into a CUDA graph.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from drive_envelope._src.adapters.mjwarp.structure import DriveTable


def implicit_damping(disableflags: int, integrator: int) -> bool:
    """Whether MJWarp's step integrates joint damping implicitly (solves with ``M + h*D'``).

    Euler unless ``eulerdamp`` is disabled, implicit and implicitfast; none when ``damper`` is off.
    """
    from mujoco_warp import DisableBit, IntegratorType

    if disableflags & DisableBit.DAMPER:
        return False
    euler = integrator == IntegratorType.EULER and not disableflags & DisableBit.EULERDAMP
    return euler or integrator in (IntegratorType.IMPLICIT, IntegratorType.IMPLICITFAST)


class EnvelopeDrives:
    """The drives of one MJWarp model: their static table on the device, and the step's launches.

    Installed as ``Model.callback.act_bias`` by ``drive_envelope.mjwarp.put_model`` (or ``attach``);
    call it as MJWarp does, ``drives(m, d)``.
    """

    def __init__(self, table: DriveTable, mj_model: Any, model: Any, *, specs: tuple[Any, ...] = ()) -> None:
        import warp as wp

        from drive_envelope._src.adapters.mjwarp import kernels, solve

        self.table = table
        """The drives, in DOF order (:class:`DriveTable`)."""
        self.specs = specs
        """The drives as they were given (:class:`.structure.DriveSpec`), for extending the set."""
        self.mj_model = mj_model
        """The compiled plugin-free ``mujoco.MjModel`` the MJWarp model was put from."""
        self.stats: Any = None
        """``(nworld, 2)`` int32 Warp array of (iterations, drive solves) of the last step, once enabled."""
        device = model.opt.timestep.device
        self._device = device

        self._drives = kernels.DriveArrays()
        for field in dataclasses.fields(table):  # every array of the table, flattened, by its name
            values = getattr(table, field.name)
            if isinstance(values, np.ndarray):
                flat = np.ascontiguousarray(values, dtype=np.int32).ravel()
                setattr(self._drives, field.name, wp.array(flat, dtype=wp.int32, device=device))
        n, nv = table.count, int(mj_model.nv)
        nc = int(np.sum(mj_model.M_rownnz))  # entries of M in MuJoCo's sparse layout (MJWarp's d.M)
        self._layout, self._nwork, self._niwork = _layout(solve.Layout, n, nv, nc)
        # MJWarp 3.x (MuJoCo 3, mjlab's pin) has one control per actuator and no actuator-level
        # damping: stand-ins for the fields it lacks, used when the model has none
        nu = int(mj_model.nu)
        self._fallback = {
            "actuator_ctrladr": wp.array(np.arange(nu, dtype=np.int32), dtype=int, device=device),
            "actuator_damping": wp.zeros((1, nu), dtype=wp.float32, device=device),
            "actuator_dampingpoly": wp.zeros((1, nu), dtype=wp.vec2, device=device),
        }
        self._untracked = wp.zeros((1, 2), dtype=wp.int32, device=device)
        self._no_delay = wp.zeros((1, 1), dtype=wp.float32, device=device)
        self._no_bias = wp.zeros((1, 1), dtype=wp.float32, device=device)
        self.solver_codes()  # a model with constraints = 1 is refused when it is put, not at a step

    @property
    def count(self) -> int:
        """Number of drives."""
        return self.table.count

    def track(self, nworld: int) -> Any:
        """Record each world's (iterations, drive solves) from the next step on; returns the array.

        Iterations are Newton steps plus Gauss-Seidel sweeps (0: the linear solve was inside every
        envelope), as the C plugin's ``solver_stats`` reports them. Call it before capturing a graph.
        """
        import warp as wp

        self.stats = wp.zeros((int(nworld), 2), dtype=wp.int32, device=self._device)
        return self.stats

    def _scratch(self, nworld: int) -> tuple[Any, Any]:
        """The per-world scratch, indexed [slot, world].

        World-fastest on a GPU (neighbouring threads read neighbouring addresses); on a CPU a
        transposed view of world-major rows (one thread runs one world at a time there, and that
        world's slots then share cache lines: 20 % less time at 64 worlds).
        """
        import warp as wp

        if self._device.is_cuda:
            work = wp.empty((self._nwork, nworld), dtype=wp.float64, device=self._device)
            return work, wp.empty((self._niwork, nworld), dtype=wp.int32, device=self._device)
        work = wp.empty((nworld, self._nwork), dtype=wp.float64, device=self._device)
        iwork = wp.empty((nworld, self._niwork), dtype=wp.int32, device=self._device)
        return work.transpose(), iwork.transpose()

    def solver_codes(self) -> tuple[int, int, int]:
        """(solver code, position_iterations, velocity_iterations) of ``mj_model``'s solver setting.

        Read from the host model at every call, as the C plugin reads it at every step
        (``drive_envelope.mujoco.set_solver`` on :attr:`mj_model` changes it); a CUDA graph keeps
        the values it was captured with.
        """
        from drive_envelope._src.adapters.mujoco.solver import SOLVER_NUMERIC, SOLVERS, get_solver
        from drive_envelope._src.errors import InputError

        setting = get_solver(self.mj_model)
        if setting.constraints:
            # the C plugin's loop calls MuJoCo's constraint solve inside the actuation stage; MJWarp's
            # act_bias hook has no such call per world yet: refused, never silently ignored
            raise InputError(
                f"drive_envelope.mjwarp: custom numeric {SOLVER_NUMERIC!r}[3] (constraints) = 1: not "
                "available in MJWarp (the C plugin only); expected 0: set_solver(model, 'exact')"
            )
        return SOLVERS.index(setting.solver), setting.position_iterations, setting.velocity_iterations

    def _field(self, m: Any, name: str) -> Any:
        """Model field ``name``, or its stand-in where this MJWarp version has no such field."""
        value = getattr(m, name, None)
        return self._fallback[name] if value is None else value

    def __call__(self, m: Any, d: Any) -> None:
        """Write every drive's effort into ``d.actuator_force`` (MJWarp's ``act_bias`` hook)."""
        import mujoco_warp
        import warp as wp
        from mujoco_warp import DisableBit

        from drive_envelope._src.adapters.mjwarp import kernels

        nworld, device = d.nworld, self._device
        delayed = self._no_delay
        if self.table.delayed_actuators:
            delayed = wp.empty((len(self.table.delayed_actuators), nworld), dtype=wp.float32, device=device)
            for row, actuator in enumerate(self.table.delayed_actuators):
                mujoco_warp.read_ctrl(m, d, actuator, d.time, -1, delayed[row])
        flags = int(m.opt.disableflags)
        force = wp.empty((nworld, m.nv), dtype=wp.float32, device=device)
        wp.launch(
            kernels._smooth_force_kernel,
            dim=nworld,
            inputs=[
                m.dof_jntid,
                m.jnt_actgravcomp,
                self._drives.native,
                not flags & DisableBit.GRAVITY,
                d.qfrc_passive,
                d.qfrc_bias,
                d.qfrc_applied,
                d.qfrc_gravcomp,
                d.actuator_force,
                d.moment_rownnz,
                d.moment_rowadr,
                d.moment_colind,
                d.actuator_moment,
            ],
            outputs=[force],
            device=device,
        )
        mujoco_warp.xfrc_accumulate(m, d, force)
        codes = self.solver_codes()
        bias = self._no_bias
        if codes[0] == 2:  # TGS applies the velocity-dependent bias once, the rest per substep
            from mujoco_warp._src.support import apply_ft  # J'*wrench per body, as xfrc_accumulate

            weight = wp.empty((nworld, m.nbody), dtype=wp.spatial_vector, device=device)
            wp.launch(
                kernels._weight_kernel,
                dim=(nworld, m.nbody),
                inputs=[m.body_mass, m.opt.gravity, not flags & DisableBit.GRAVITY],
                outputs=[weight],
                device=device,
            )
            gravity_force = wp.empty((nworld, m.nv), dtype=wp.float32, device=device)
            apply_ft(m, d, weight, gravity_force, False)
            bias = wp.empty((nworld, m.nv), dtype=wp.float32, device=device)
            wp.launch(
                kernels._bias_force_kernel,
                dim=(nworld, m.nv),
                inputs=[d.qfrc_bias, gravity_force],
                outputs=[bias],
                device=device,
            )
        work, iwork = self._scratch(nworld)
        tracked = self.stats is not None and self.stats.shape[0] == nworld
        wp.launch(
            kernels._drive_kernel,
            dim=nworld,
            inputs=[
                m.opt.timestep,
                m.M_rownnz,
                m.M_rowadr,
                m.M_colind,
                m.actuator_dynprm,
                self._field(m, "actuator_ctrladr"),
                m.actuator_ctrllimited,
                m.actuator_ctrlrange,
                m.dof_damping,
                m.dof_dampingpoly,
                self._field(m, "actuator_damping"),
                self._field(m, "actuator_dampingpoly"),
                m.actuator_gear,
                self._drives,
                not flags & DisableBit.CLAMPCTRL,
                implicit_damping(flags, int(m.opt.integrator)),
                tracked,
                *codes,
                self._layout,
                d.qpos,
                d.qvel,
                d.ctrl,
                d.M,
                delayed,
                force,
                bias,
                work,
                iwork,
                self.stats if tracked else self._untracked,
            ],
            outputs=[d.actuator_force],
            device=device,
        )


def _layout(layout_type: Any, n: int, nv: int, nc: int) -> tuple[Any, int, int]:
    """A :class:`.solve.Layout` for n drives, nv DOFs and nc entries of M; with the two slot counts."""
    lay = layout_type()
    lay.n, lay.nv = n, nv
    sizes = [("mh", nc), ("dinv", nv), ("y", nv), ("z", n * nv), ("a", n * n), ("q", n * n)]
    sizes += [(name, n) for name in ("vfree", "c", "alpha", "x", "v", "rest", "slope", "b", "gx", "effort")]
    sizes += [("prm", 6 * n), ("err", n), ("tvel", n), ("ff", n)]
    sizes += [("desc", 5 * n), ("moved", n), ("qvel", n), ("bias", n)]  # pgs/tgs
    offset = 0
    for name, size in sizes:
        setattr(lay, name, offset)
        offset += size
    ioffset = 0
    for name, size in [
        (name, n) for name in ("active", "released", "flips", "stale", "clamped", "free", "fixed")
    ]:
        setattr(lay, name, ioffset)
        ioffset += size
    lay.solves = ioffset
    return lay, max(offset, 1), ioffset + 1

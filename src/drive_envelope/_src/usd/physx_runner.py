"""Run test-stand stages on real PhysX (the ``ovphysx`` wheel, CPU) in a child process.

Why a child process: ovphysx fixes its device mode and loads its own OpenUSD (25.11) process-wide,
which must not meet the ``pxr`` of usd-core that authors the stage; a child also keeps PhysX's
logs, caches and any native crash away from the caller. The parent writes each stage with
:mod:`drive_envelope._src.usd.teststand_scene`, lists the jobs in a JSON file and runs
``python -m drive_envelope._src.usd.physx_runner JOBS.json RESULT.npz``; Warp's, Omniverse's and
ovphysx's caches and logs go to a temporary folder (``HOME``, ``XDG_CACHE_HOME``,
``WARP_CACHE_PATH``), never the repository or the user's home.

Per step the child writes the applied joint effort (``ARTICULATION_DOF_ACTUATION_FORCE``) and the
external load (a link torque about the joint axis, or a force along it, through
``ARTICULATION_LINK_WRENCH``), steps, and reads the joint position and velocity (SI: the tensor
API reports radians) and ``ARTICULATION_DOF_PROJECTED_JOINT_FORCE``: the joint force the solver
applied over the step projected on the DOF, which is the total actuator effort (drive + applied);
under TGS it also contains the external load, which the runner subtracts.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope.errors import DriveEnvelopeError

__all__ = ["PhysxJob", "PhysxResult", "cache_environment", "inspect_drives", "run_jobs"]

_ARTICULATION = "/World/stand"
_LINK = "/World/stand/link"
_TIMEOUT_S = 600.0


@dataclass(frozen=True, kw_only=True, slots=True)
class PhysxJob:
    """One stage to step: what the child needs besides the USD file."""

    usd_path: str
    """The stage (``.usda``) written by the parent."""
    joint: str
    """``"revolute"`` (axis Z) or ``"prismatic"`` (axis X)."""
    solver: str
    """``"pgs"`` or ``"tgs"``: under TGS PhysX's projected joint force includes the external load."""
    dt: float
    """Time step [s]."""
    steps: int
    """Number of steps."""
    initial_position: float
    """Joint position at t = 0 [rad or m]."""
    initial_velocity: float
    """Joint velocity at t = 0 [rad/s or m/s]."""
    applied_effort: float
    """Joint force commanded beside the drive, written every step [N*m or N]."""
    external_effort: float
    """Load from outside the actuator, a link wrench written every step [N*m or N] (SI; the
    child converts to stage units with ``effort_scale``)."""
    effort_scale: float = 1.0
    """SI -> stage factor for efforts (1 for SI stages)."""
    length_scale: float = 1.0
    """SI -> stage factor for lengths (1 for SI stages)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class PhysxResult:
    """Per-step samples of one job, row 0 the initial state."""

    position: npt.NDArray[np.float64]
    """Joint position [rad or m], ``steps + 1`` rows."""
    velocity: npt.NDArray[np.float64]
    """Joint velocity [rad/s or m/s]."""
    effort: npt.NDArray[np.float64]
    """Total actuator effort over each step (``effort[0] = 0``) [N*m or N]."""


def cache_environment(folder: str | os.PathLike[str]) -> dict[str, str]:
    """Environment for the child with every cache and log folder inside ``folder``."""
    env = dict(os.environ)
    root = Path(folder)
    for name in ("home", "cache", "warp"):
        (root / name).mkdir(parents=True, exist_ok=True)
    env.update(
        HOME=str(root / "home"),
        XDG_CACHE_HOME=str(root / "cache"),
        WARP_CACHE_PATH=str(root / "warp"),
        OMNI_KIT_ALLOW_ROOT="1",
    )
    return env


def _run_child(command: list[str], folder: Path) -> subprocess.CompletedProcess[str]:
    """Run the child with its caches in ``folder``; a hung PhysX becomes an error, not a hang."""
    try:
        return subprocess.run(
            command,
            capture_output=True,
            text=True,
            env=cache_environment(folder / "caches"),
            timeout=_TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        raise DriveEnvelopeError(f"PhysX (ovphysx) did not finish within {_TIMEOUT_S:g} s") from None


def run_jobs(jobs: Sequence[PhysxJob], *, workdir: str | os.PathLike[str]) -> list[PhysxResult]:
    """Step every job in one child process and return the samples, in order.

    Raises:
        DriveEnvelopeError: the child failed (its last output lines are in the message).
    """
    folder = Path(workdir)
    spec = folder / "jobs.json"
    out = folder / "result.npz"
    spec.write_text(json.dumps([asdict(job) for job in jobs]), encoding="utf-8")
    command = [sys.executable, "-m", "drive_envelope._src.usd.physx_runner", str(spec), str(out)]
    completed = _run_child(command, folder)
    if completed.returncode != 0 or not out.is_file():
        tail = "\n".join((completed.stdout + completed.stderr).strip().splitlines()[-15:])
        raise DriveEnvelopeError(f"PhysX (ovphysx) run failed with status {completed.returncode}:\n{tail}")
    with np.load(out) as data:
        return [
            PhysxResult(
                position=data[f"position_{i}"].astype(np.float64),
                velocity=data[f"velocity_{i}"].astype(np.float64),
                effort=data[f"effort_{i}"].astype(np.float64),
            )
            for i in range(len(jobs))
        ]


def inspect_drives(
    usd_path: str | os.PathLike[str], articulation: str, *, workdir: str | os.PathLike[str]
) -> dict[str, dict[str, float]]:
    """What PhysX loaded for each DOF of an articulation: ``{dof name: {max_force, stiffness, damping}}``.

    Values are PhysX's own, after its USD parsing: radians for angular DOFs, stage units for
    lengths and masses (divide by the :class:`~drive_envelope._src.usd.scale.StageUnits` factors
    for SI).

    Raises:
        DriveEnvelopeError: the child failed.
    """
    folder = Path(workdir)
    spec = folder / "inspect.json"
    out = folder / "inspect_result.json"
    spec.write_text(
        json.dumps({"inspect": os.fspath(usd_path), "articulation": articulation}), encoding="utf-8"
    )
    command = [sys.executable, "-m", "drive_envelope._src.usd.physx_runner", str(spec), str(out)]
    completed = _run_child(command, folder)
    if completed.returncode != 0 or not out.is_file():
        tail = "\n".join((completed.stdout + completed.stderr).strip().splitlines()[-15:])
        raise DriveEnvelopeError(
            f"PhysX (ovphysx) inspection failed with status {completed.returncode}:\n{tail}"
        )
    result: dict[str, dict[str, float]] = json.loads(out.read_text(encoding="utf-8"))
    return result


# -- the child ----------------------------------------------------------------------------------------


def _link_index(names: list[str]) -> int:
    """Index of the driven link among the articulation's bodies (names may be paths)."""
    leaf = _LINK.rsplit("/", 1)[-1]
    for i, name in enumerate(names):
        if str(name).rsplit("/", 1)[-1] == leaf:
            return i
    raise RuntimeError(f"link {_LINK} not among the articulation bodies {names}")


def _step_job(physx: Any, job: dict[str, Any]) -> dict[str, npt.NDArray[np.float64]]:
    """Load one stage, step it and sample it; the stage is removed afterwards."""
    from ovphysx.types import TensorType

    handle, _ = physx.add_usd(job["usd_path"])
    physx.wait_all()
    try:

        def binding(pattern: str, tensor_type: Any) -> Any:
            return physx.create_tensor_binding(pattern=pattern, tensor_type=tensor_type)

        pos = binding(_ARTICULATION, TensorType.ARTICULATION_DOF_POSITION)
        vel = binding(_ARTICULATION, TensorType.ARTICULATION_DOF_VELOCITY)
        force = binding(_ARTICULATION, TensorType.ARTICULATION_DOF_ACTUATION_FORCE)
        projected = binding(_ARTICULATION, TensorType.ARTICULATION_DOF_PROJECTED_JOINT_FORCE)
        wrench = binding(_ARTICULATION, TensorType.ARTICULATION_LINK_WRENCH)
        link_index = _link_index(list(wrench.body_names))
        buffers = {
            name: np.zeros(b.shape, dtype=np.float32)
            for name, b in (("q", pos), ("v", vel), ("f", force), ("p", projected))
        }
        length = 1.0 if job["joint"] == "revolute" else float(job["length_scale"])
        buffers["q"][:] = job["initial_position"] * length
        buffers["v"][:] = job["initial_velocity"] * length
        pos.write(buffers["q"])
        vel.write(buffers["v"])
        applied = np.full(force.shape, job["applied_effort"] * job["effort_scale"], dtype=np.float32)
        load = np.zeros(wrench.shape, dtype=np.float32)
        load[0, link_index, 5 if job["joint"] == "revolute" else 0] = (
            job["external_effort"] * job["effort_scale"]
        )
        steps = int(job["steps"])
        samples = {key: np.zeros(steps + 1) for key in ("position", "velocity", "effort")}
        pos.read(buffers["q"])
        vel.read(buffers["v"])
        samples["position"][0], samples["velocity"][0] = buffers["q"][0, 0], buffers["v"][0, 0]
        dt = float(job["dt"])
        for i in range(1, steps + 1):
            force.write(applied)
            if job["external_effort"] != 0.0:
                wrench.write(load)
            physx.step(dt, (i - 1) * dt)
            physx.wait_all()
            pos.read(buffers["q"])
            vel.read(buffers["v"])
            projected.read(buffers["p"])
            samples["position"][i] = buffers["q"][0, 0]
            samples["velocity"][i] = buffers["v"][0, 0]
            samples["effort"][i] = buffers["p"][0, 0]
        if job["solver"] == "tgs":
            # TGS (external forces every substep) reports the total generalized force on the DOF,
            # the external load included; PGS reports the joint's own force (measured, ovphysx 0.3.7)
            samples["effort"][1:] -= load[0, link_index, 5 if job["joint"] == "revolute" else 0]
        if job["joint"] == "revolute":
            samples["position"] = _unwrap(samples["position"], samples["velocity"], dt)
        # back to SI: angles are radians in every stage, lengths and efforts are in stage units
        length = 1.0 if job["joint"] == "revolute" else float(job["length_scale"])
        samples["position"] /= length
        samples["velocity"] /= length
        samples["effort"] /= float(job["effort_scale"])
        for b in (pos, vel, force, projected, wrench):
            b.destroy()
        return samples
    finally:
        physx.remove_usd(handle)
        physx.wait_all()


def _unwrap(
    position: npt.NDArray[np.float64], velocity: npt.NDArray[np.float64], dt: float
) -> npt.NDArray[np.float64]:
    """Undo PhysX's wrapping of a free revolute joint's position (a jump by a multiple of 2*pi).

    Each sample is shifted by the multiple of 2*pi that brings it closest to the previous sample
    advanced by the step's velocity; a real step never moves a joint by pi or more.
    """
    result = position.copy()
    turn = 2.0 * np.pi
    for i in range(1, result.shape[0]):
        predicted = result[i - 1] + velocity[i] * dt
        result[i] += turn * np.round((predicted - position[i]) / turn)
    return result


def _inspect(physx: Any, request: dict[str, str], out: str) -> None:
    """Write PhysX's per-DOF drive values of one articulation as JSON."""
    from ovphysx.types import TensorType

    physx.add_usd(request["inspect"])
    physx.wait_all()
    columns = {
        "max_force": TensorType.ARTICULATION_DOF_MAX_FORCE,
        "stiffness": TensorType.ARTICULATION_DOF_STIFFNESS,
        "damping": TensorType.ARTICULATION_DOF_DAMPING,
    }
    result: dict[str, dict[str, float]] = {}
    for column, tensor_type in columns.items():
        binding = physx.create_tensor_binding(pattern=request["articulation"], tensor_type=tensor_type)
        values = np.zeros(binding.shape, dtype=np.float32)
        binding.read(values)
        for j, name in enumerate(binding.dof_names):
            result.setdefault(str(name), {})[column] = float(values[0, j])
        binding.destroy()
    Path(out).write_text(json.dumps(result), encoding="utf-8")


def _main(argv: Sequence[str]) -> int:
    """Child entry point: ``physx_runner JOBS.json RESULT.npz`` (or an inspection request)."""
    spec, out = argv
    jobs = json.loads(Path(spec).read_text(encoding="utf-8"))
    import ovphysx

    ovphysx.set_log_level(ovphysx.LogLevel.ERROR)
    # one scene with one articulation: worker threads only add contention on small machines
    physx = ovphysx.PhysX(
        device="cpu", config=ovphysx.PhysXConfig(num_threads=0, disable_contact_processing=True)
    )
    if isinstance(jobs, dict):
        try:
            _inspect(physx, jobs, out)
        finally:
            physx.release()
        return 0
    arrays: dict[str, npt.NDArray[np.float64]] = {}
    try:
        for i, job in enumerate(jobs):
            for key, values in _step_job(physx, job).items():
                arrays[f"{key}_{i}"] = values
    finally:
        physx.release()
    with tempfile.NamedTemporaryFile(dir=Path(out).parent, suffix=".npz", delete=False) as tmp:
        np.savez(tmp, **arrays)  # type: ignore[arg-type]
    os.replace(tmp.name, out)
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))

"""Run test-stand stages on real PhysX (the ``ovphysx`` 0.7 wheel, CPU) in this process.

ovphysx 0.7 reads USD through ovstage, whose OpenUSD build is namespaced apart from usd-core's
``pxr``, so both live in one process (checked with usd-core 26.11 and ovstage 0.3: the stage is
authored with ``pxr`` and handed over as USDA text). The first use sets ovphysx's process-wide
state once: CPU-only mode (sticky for the process, as ovphysx defines it), the PhysX schemas
from ``physx-usd-schemas`` registered with ovstage population, log level ERROR, and every cache
(the Omniverse client cache, Warp's kernel cache, PhysX's cooked-collider cache) in
``<tmp>/drive-envelope-ovphysx-<uid>``, never the repository or the user's home.

Per step the runner writes the applied joint effort (``jointActuationForce``) and the external
load (a link wrench: a torque about the joint axis, or a force along it), steps, and reads
``jointPosition``, ``jointVelocity`` (degrees on revolute joints, converted to radians here) and
``jointProjectedForce``: the joint force the solver applied over the step, projected on the DOF.
That is the total actuator effort (drive + applied); under TGS it also contains the external
load, which the runner subtracts.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.usd.teststand_scene import JOINT_PATH, LINK_PATH
from drive_envelope.errors import DriveEnvelopeError, InputError

__all__ = ["PhysxJob", "PhysxResult", "cache_folder", "inspect_drives", "run_jobs"]

_INSPECTED = {
    "max_force": "jointMaxForce",
    "stiffness": "jointStiffness",
    "damping": "jointDamping",
    "max_actuator_velocity": "jointMaxActuatorVelocity",
    "velocity_dependent_resistance": "jointVelocityDependentResistance",
    "speed_effort_gradient": "jointSpeedEffortGradient",
}
_STATE = ("jointPosition", "jointVelocity", "jointProjectedForce")
_ORDINAL = 1  # the one ovstage ordinal each stage is populated at and PhysX reads
_ready = False  # ovphysx's process-wide set-up done


@dataclass(frozen=True, kw_only=True, slots=True)
class PhysxJob:
    """One stage to step: the authored stage and the per-step inputs."""

    usda: str
    """The stage as USDA text (authored with ``pxr``, populated into ovstage as is)."""
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
    """Load from outside the actuator, a link wrench written every step [N*m or N]."""
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


def cache_folder() -> Path:
    """Folder for ovphysx's, ovstage's and Warp's caches: one per user under the temp folder."""
    owner = os.getuid() if hasattr(os, "getuid") else os.getpid()
    return Path(tempfile.gettempdir()) / f"drive-envelope-ovphysx-{owner}"


@contextlib.contextmanager
def _environment(**values: str) -> Iterator[None]:
    """Set environment variables for the block only (the libraries read them at initialisation)."""
    saved = {key: os.environ.get(key) for key in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for key, old in saved.items():
            if old is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = old


def _prepare() -> Any:
    """Import ovphysx and do its once-per-process set-up; returns the ``ovphysx`` module.

    Raises:
        DriveEnvelopeError: ovphysx or physx-usd-schemas is missing.
    """
    global _ready
    try:
        import ovphysx
        import ovstage
        from ovphysx.samples.python_samples.schema_support import physx_schema_paths
    except ImportError as exc:
        raise DriveEnvelopeError(
            f"the physx engine needs ovphysx 0.7 (pip install 'drive-envelope[physx]'): {exc}"
        ) from None
    if _ready:
        return ovphysx
    folder = cache_folder()
    for name in ("cache", "warp", "cooked"):
        (folder / name).mkdir(parents=True, exist_ok=True)
    # the Omniverse client fixes its cache folder on the first ovstage call, Warp on its init
    with _environment(XDG_CACHE_HOME=str(folder / "cache"), WARP_CACHE_PATH=str(folder / "warp")):
        _init_warp()
        ovphysx.set_log_level(ovphysx.LogLevel.ERROR)
        with contextlib.suppress(RuntimeError):
            # sticky per process; refused while another PhysX instance is alive, in which case
            # the stage's enableGPUDynamics = false still keeps the stand on CPU dynamics
            ovphysx.PhysX.set_cpu_mode(True)
        with contextlib.suppress(RuntimeError):
            ovphysx.set_global_config(ovphysx.GlobalConfigKey.NUM_THREADS, 0)  # one small scene
            ovphysx.set_global_config(
                ovphysx.GlobalConfigKey.COOKED_COLLIDER_CACHE_DIRECTORY, str(folder / "cooked")
            )
        try:
            ovstage.population.register_usd_schemas([str(path) for path in physx_schema_paths()])
        except FileNotFoundError as exc:
            raise DriveEnvelopeError(f"the physx engine needs physx-usd-schemas: {exc}") from None
    _ready = True
    return ovphysx


def _init_warp() -> None:
    """Initialise Warp quietly (ovphysx returns Warp arrays) unless the caller already did."""
    import warp as wp

    if getattr(wp._src.context, "runtime", None) is not None:  # keep the caller's Warp set-up
        return
    level = wp.config.log_level
    wp.config.log_level = max(level, logging.WARNING)  # no "Warp initialized" banner on stdout
    try:
        wp.init()
    finally:
        wp.config.log_level = level


@contextlib.contextmanager
def _attached(ovphysx: Any, *, usda: str | None = None, path: str | None = None) -> Iterator[Any]:
    """A PhysX instance with one stage (USDA text or a file) populated and attached."""
    import ovstage

    physx = ovphysx.PhysX()
    stage = ovstage.Stage("drive-envelope")
    attached = False
    try:
        domains = ovstage.PopulationDomain.ALL  # ALL resolves nested world transforms (ovstage 0.3)
        if usda is not None:
            ovstage.population.open_usd_from_string(stage, usda, ordinal=_ORDINAL, domains=domains)
        else:
            ovstage.population.open_usd(stage, str(path), ordinal=_ORDINAL, domains=domains)
        stage.advance_write_floor(ordinal=_ORDINAL).wait()
        physx.wait_task(physx.attach_ovstage(stage, read_ordinal=_ORDINAL))
        attached = True
        yield physx
    finally:
        try:
            if attached:
                physx.wait_task(physx.detach_ovstage())
        finally:
            physx.destroy()
            stage.destroy()


def run_jobs(jobs: Sequence[PhysxJob]) -> list[PhysxResult]:
    """Step every job on PhysX and return the samples, in order.

    Raises:
        DriveEnvelopeError: ovphysx is missing or PhysX failed.
    """
    ovphysx = _prepare()
    results = []
    for job in jobs:
        try:
            with _attached(ovphysx, usda=job.usda) as physx:
                results.append(_step_job(physx, job))
        except (RuntimeError, ValueError) as exc:  # TaskError is a RuntimeError
            raise DriveEnvelopeError(f"PhysX (ovphysx) failed: {' '.join(str(exc).split())[:400]}") from exc
    return results


def inspect_drives(usd_path: str | os.PathLike[str]) -> dict[str, dict[str, float]]:
    """What PhysX loaded for every articulation DOF of a USD file, in PhysX's units.

    Returns:
        ``{joint path: {max_force, stiffness, damping, max_actuator_velocity,
        velocity_dependent_resistance, speed_effort_gradient}}`` (a joint with several free axes
        gets ``path[axis]`` keys). Values are PhysX's after its USD parsing, as ovphysx reports
        them: angular DOFs per degree (deg/s, N*m*s/deg, (deg/s)/(N*m), stiffness per degree),
        lengths and masses in stage units. Divide by the
        :class:`~drive_envelope._src.usd.scale.StageUnits` factors for SI.

    Raises:
        InputError: the file does not exist.
        DriveEnvelopeError: ovphysx is missing or PhysX failed.
    """
    if not Path(usd_path).is_file():
        raise InputError(f"{os.fspath(usd_path)}: no such file")
    ovphysx = _prepare()
    result: dict[str, dict[str, float]] = {}
    try:
        with _attached(ovphysx, path=os.fspath(usd_path)) as physx:
            columns = _read_joints(physx, list(_INSPECTED.values()))
            for column, attribute in _INSPECTED.items():
                for joint, values in columns[attribute].items():
                    for axis, value in enumerate(values):
                        key = joint if len(values) == 1 else f"{joint}[{axis}]"
                        result.setdefault(key, {})[column] = float(value)
    except (RuntimeError, ValueError) as exc:
        raise DriveEnvelopeError(f"PhysX (ovphysx) failed: {' '.join(str(exc).split())[:400]}") from exc
    return result


# -- stepping -----------------------------------------------------------------------------------------


def _read_joints(
    physx: Any, attributes: Sequence[str], pattern: str | None = None
) -> dict[str, dict[str, npt.NDArray[np.float64]]]:
    """``ARTICULATION_JOINT`` attributes of every (or the matching) joint: ``{attribute: {path: axes}}``."""
    from ovphysx.types import SimObjectType

    values: dict[str, dict[str, npt.NDArray[np.float64]]] = {name: {} for name in attributes}
    with physx.read_sync(SimObjectType.ARTICULATION_JOINT, list(attributes), pattern=pattern) as result:
        paths = result.dictionary
        names = {paths.intern_token(name): name for name in attributes}
        for group in result.groups:
            joints = paths.get_path_strings(group.prim_list)
            # one array group per attribute: tensors[i] holds joint i's axes (not one group per joint)
            column = values[names[group.attribute]]
            for i, tensor in enumerate(group.tensors):
                column[str(joints[group.prim_offset + i])] = np.asarray(tensor.numpy(), dtype=np.float64)
    return values


def _write(physx: Any, object_type: Any, attribute: str, pattern: str, row: npt.NDArray[np.float32]) -> None:
    """Write one attribute of the prims matching ``pattern``: every tensor gets ``row``."""
    written = 0
    with physx.write_sync(object_type, [attribute], pattern=pattern) as session:
        for group in session.groups:
            for tensor in group.tensors:  # fill every tensor: a commit publishes the whole group
                tensor.assign(np.broadcast_to(row, tuple(tensor.shape)).astype(np.float32))
            session.commit_sync(group)
            written += len(group.tensors)
    if written == 0:
        raise RuntimeError(f"no {attribute} to write at {pattern}")


def _step_job(physx: Any, job: PhysxJob) -> PhysxResult:
    """Set the initial state, then write the inputs, step and sample ``job.steps`` times."""
    from ovphysx.types import SimObjectType

    joint_type, link_type = SimObjectType.ARTICULATION_JOINT, SimObjectType.ARTICULATION_LINK
    revolute = job.joint == "revolute"
    # PhysX's first step initialises its structures (a 1 ns step); done here, before the initial
    # state is written, rather than implicitly at the first write
    physx.warmup()
    # revolute DOFs are read and written in degrees, prismatic ones in stage lengths
    coordinate = math.degrees(1.0) if revolute else job.length_scale
    _write(physx, joint_type, "jointPosition", JOINT_PATH, np.float32([job.initial_position * coordinate]))
    _write(physx, joint_type, "jointVelocity", JOINT_PATH, np.float32([job.initial_velocity * coordinate]))
    physx.update_articulations_kinematic(pattern=JOINT_PATH.rsplit("/", 1)[0])
    applied = np.float32([job.applied_effort * job.effort_scale])
    load = job.external_effort * job.effort_scale
    # [force xyz, torque xyz, world point]: a torque about Z, or a force along X through the
    # origin, which lies on the prismatic axis, so the force adds no torque
    wrench = np.zeros(9, dtype=np.float32)
    wrench[5 if revolute else 0] = load
    samples = np.zeros((3, job.steps + 1))
    samples[:2, 0] = _sample(physx, _STATE[:2])
    for i in range(1, job.steps + 1):
        _write(physx, joint_type, "jointActuationForce", JOINT_PATH, applied)
        if load != 0.0:
            _write(physx, link_type, "wrench", LINK_PATH, wrench)
        physx.step_sync(job.dt)
        samples[:, i] = _sample(physx, _STATE)
    position, velocity, effort = samples / np.array([[coordinate], [coordinate], [job.effort_scale]])
    if job.solver == "tgs":
        # TGS (external forces every substep) reports the total generalized force on the DOF, the
        # external load included; PGS reports the joint's own force (measured, ovphysx 0.3.7 and 0.7)
        effort[1:] -= job.external_effort
    if revolute:
        position = _unwrap(position, velocity, job.dt)
    return PhysxResult(position=position, velocity=velocity, effort=effort)


def _sample(physx: Any, attributes: Sequence[str]) -> list[float]:
    """The stand joint's single-axis values of some attributes, in ovphysx's units."""
    values = _read_joints(physx, attributes, JOINT_PATH)
    return [float(values[name][JOINT_PATH][0]) for name in attributes]


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

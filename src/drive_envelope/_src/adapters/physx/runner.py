"""Run test-stand stages on real PhysX (the ``ovphysx`` 0.7 wheel, CPU) in this process.

ovphysx 0.7 reads USD through ovstage, whose OpenUSD build is namespaced apart from usd-core's
``pxr``, so both live in one process (checked with usd-core 26.11 and ovstage 0.3: the stage is
authored with ``pxr`` and handed over as USDA text); ovphysx 0.3 needed a child process. The
first use sets ovphysx's process-wide state once: CPU-only mode (sticky for the process, as
ovphysx defines it), the PhysX schemas of ``physx-usd-schemas`` registered with ovstage
population, log level ERROR, and the Omniverse client's and Warp's caches in
``<tmp>/drive-envelope-ovphysx-<uid>`` (never the repository or the user's home; PhysX's cooked
colliders go to a process-private temp folder by default).

Per step the runner writes the applied joint effort (``jointActuationForce``), the external
load (a link wrench: a torque about the joint axis, or a force along it) and, for a job with a
drive schedule, the drive's targets (``jointPositionTarget``, ``jointVelocityTarget``) and gains
(``jointStiffness``, ``jointDamping``: 0 while the drive is unpowered) where they change, steps, and reads
``jointPosition``, ``jointVelocity`` (degrees on revolute joints, converted to radians here) and
``jointProjectedForce``: the joint force the solver applied over the step, projected on the DOF.
ovphysx 0.7 has no read of the drive's own force; on the test stand (centre of mass on the joint
axis) the projected force is the total actuator effort (drive + applied) on PGS and TGS alike
(ovphysx 0.3.7's TGS also counted the external load in it; 0.7 does not). On a link whose centre
of mass is off the axis it is not: it also carries the reaction of the link's own motion.
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
import tempfile
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.adapters.physx.scene import ARTICULATION_PATH, JOINT_PATH, LINK_PATH
from drive_envelope._src.errors import DriveEnvelopeError, InputError
from drive_envelope._src.kernels.warp_setup import quiet_warp

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
    target_position: npt.NDArray[np.float64] | None = None
    """Drive target position per step, in ovphysx's units (deg or stage length), or None (the stage's)."""
    target_velocity: npt.NDArray[np.float64] | None = None
    """Drive target velocity per step (deg/s or stage length/s), or None."""
    stiffness: npt.NDArray[np.float64] | None = None
    """Drive stiffness per step in USD units (per degree on angular drives), or None."""
    damping: npt.NDArray[np.float64] | None = None
    """Drive damping per step in USD units, or None."""


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


def _import_ovphysx() -> Any:
    """``import ovphysx``, checking it is >= 0.7 (older ones have another API; 0.3.7 another clamp).

    Raises:
        InputError: ovphysx is missing or older than 0.7 (naming the extra to install).
    """
    try:
        import ovphysx
    except ImportError:
        raise _needs_ovphysx("none") from None
    version = str(getattr(ovphysx, "__version__", "unknown"))
    if _release(version) < (0, 7):
        raise _needs_ovphysx(version)
    return ovphysx


def _needs_ovphysx(found: str) -> InputError:
    return InputError(
        f"--engine physx: needs ovphysx >= 0.7 (found {found}); "
        "install the extra: pip install 'drive-envelope[physx]'"
    )


def _release(version: str) -> tuple[int, int]:
    """(major, minor) of a version string; (0, 0) when it does not start with two numbers."""
    try:
        major, minor = (int(part) for part in version.split(".")[:2])
    except ValueError:
        return (0, 0)
    return (major, minor)


def _prepare() -> Any:
    """Import ovphysx and do its once-per-process set-up; returns the ``ovphysx`` module.

    Raises:
        InputError: ovphysx (>= 0.7) or physx-usd-schemas is missing.
    """
    global _ready
    ovphysx = _import_ovphysx()
    if _ready:
        return ovphysx
    import ovstage
    from ovphysx.samples.python_samples.schema_support import physx_schema_paths

    folder = cache_folder()
    for name in ("cache", "warp"):
        (folder / name).mkdir(parents=True, exist_ok=True)
    # the Omniverse client fixes its cache folder on the first ovstage call, Warp on its init;
    # PhysX's cooked colliders already go to a process-private temp folder by default
    with (
        _environment(XDG_CACHE_HOME=str(folder / "cache"), WARP_CACHE_PATH=str(folder / "warp")),
        quiet_warp(),
    ):
        ovphysx.set_log_level(ovphysx.LogLevel.ERROR)
        with contextlib.suppress(RuntimeError):
            # sticky per process; refused while another PhysX instance is alive, in which case
            # the stage's enableGPUDynamics = false still keeps the stand on CPU dynamics
            ovphysx.PhysX.set_cpu_mode(True)
        try:
            ovstage.population.register_usd_schemas(_schema_paths(ovphysx, physx_schema_paths()))
        except FileNotFoundError as exc:
            raise InputError(f"--engine physx: needs physx-usd-schemas: {exc}") from None
    _ready = True
    return ovphysx


def _schema_paths(ovphysx: Any, physx_paths: Any) -> list[str]:
    """The PhysX schemas, and Newton's when ovphysx knows them (newton-usd-schemas installed).

    ovstage builds its schema definitions once, on the first read: a schema registered later is
    ignored (ovphysx then warns at every attach that newton:* attributes may be dropped), so every
    schema ovphysx may read is registered here, together, before anything is populated.
    """
    paths = [str(path) for path in physx_paths]
    newton_root = getattr(ovphysx, "newton_schema_root", None)
    if newton_root is not None:
        with contextlib.suppress(Exception):  # no newton-usd-schemas: nothing to register
            root = newton_root()
            if root:
                paths.append(str(root))
    return paths


@contextlib.contextmanager
def _physx() -> Iterator[Any]:
    """One CPU PhysX instance (a DriveEnvelopeError for PhysX's own failures)."""
    ovphysx = _prepare()
    with warnings.catch_warnings():
        # ovphysx warns once that a CUDA build of Warp may open the driver; the stand runs on CPU
        warnings.filterwarnings("ignore", message="ovphysx is in CPU-only mode", category=RuntimeWarning)
        physx = ovphysx.PhysX()
        try:
            yield physx
        except (RuntimeError, ValueError) as exc:  # ovphysx's TaskError is a RuntimeError
            message = " ".join(str(exc).split())[:400]
            raise DriveEnvelopeError(f"PhysX (ovphysx) failed: {message}") from exc
        finally:
            gc.collect()  # ovphysx refuses to destroy while a Warp view of a read is alive
            with contextlib.suppress(RuntimeError):  # then ovphysx destroys it at exit instead
                physx.destroy()


@contextlib.contextmanager
def _attached(physx: Any, *, usda: str | None = None, path: str | None = None) -> Iterator[None]:
    """Populate an ovstage stage from USDA text or a file and attach it to ``physx`` for the block."""
    import ovstage

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
        yield
    finally:
        try:
            if attached:
                physx.wait_task(physx.detach_ovstage())
        finally:
            stage.destroy()


def run_jobs(jobs: Sequence[PhysxJob]) -> list[PhysxResult]:
    """Step every job on one PhysX instance and return the samples, in order.

    Raises:
        InputError: ovphysx (>= 0.7) or physx-usd-schemas is missing.
        DriveEnvelopeError: PhysX failed.
    """
    results = []
    with _physx() as physx:
        for job in jobs:
            with _attached(physx, usda=job.usda):
                results.append(_step_job(physx, job))
    return results


def inspect_drives(usd_path: str | os.PathLike[str]) -> dict[str, dict[str, float]]:
    """What PhysX loaded for every articulation DOF of a USD file, in ovphysx's units.

    Returns:
        ``{joint path: {max_force, stiffness, damping, max_actuator_velocity,
        velocity_dependent_resistance, speed_effort_gradient}}`` (a joint with several free axes
        gets ``path[axis]`` keys). Values are PhysX's after its USD parsing, folded back by ovphysx
        to USD's units: angular DOFs per degree (deg/s, N*m*s/deg, (deg/s)/(N*m), stiffness per
        degree), lengths and masses in stage units. Divide by the
        :class:`~drive_envelope._src.adapters.usd.scale.StageUnits` factors for SI.

    Raises:
        InputError: the file does not exist, or ovphysx (>= 0.7) is missing.
        DriveEnvelopeError: PhysX failed.
    """
    if not Path(usd_path).is_file():
        raise InputError(f"{os.fspath(usd_path)}: no such file")
    result: dict[str, dict[str, float]] = {}
    with _physx() as physx, _attached(physx, path=os.fspath(usd_path)):
        columns = _read_joints(physx, list(_INSPECTED.values()))
    for column, attribute in _INSPECTED.items():
        for joint, values in columns[attribute].items():
            for axis, value in enumerate(values):
                key = joint if len(values) == 1 else f"{joint}[{axis}]"
                result.setdefault(key, {})[column] = float(value)
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
    _write(physx, joint_type, "jointPosition", JOINT_PATH, _row(job.initial_position * coordinate))
    _write(physx, joint_type, "jointVelocity", JOINT_PATH, _row(job.initial_velocity * coordinate))
    physx.update_articulations_kinematic(pattern=ARTICULATION_PATH)  # link poses follow the joint
    applied = _row(job.applied_effort * job.effort_scale)
    load = job.external_effort * job.effort_scale
    # [force xyz, torque xyz, world point]: a torque about Z, or a force along X through the
    # origin, which lies on the prismatic axis, so the force adds no torque
    wrench = np.zeros(9, dtype=np.float32)
    wrench[5 if revolute else 0] = load
    samples = np.zeros((3, job.steps + 1))
    samples[:2, 0] = _sample(physx, _STATE[:2])[:, 0]
    schedule = _schedule(job)
    last: dict[str, float] = {}
    for i in range(1, job.steps + 1):
        _write(physx, joint_type, "jointActuationForce", JOINT_PATH, applied)
        if load != 0.0:
            _write(physx, link_type, "wrench", LINK_PATH, wrench)
        for attribute, values in schedule.items():
            value = float(values[i - 1])
            if last.get(attribute) != value:  # properties and targets persist until re-written
                _write(physx, joint_type, attribute, JOINT_PATH, _row(value))
                last[attribute] = value
        physx.step_sync(job.dt)
        samples[:, i] = _sample(physx, _STATE)[:, 0]
    position, velocity, effort = samples / np.array([[coordinate], [coordinate], [job.effort_scale]])
    if revolute:
        position = _unwrap(position, velocity, job.dt)
    return PhysxResult(position=position, velocity=velocity, effort=effort)


def _schedule(job: PhysxJob) -> dict[str, npt.NDArray[np.float64]]:
    """The per-step joint writes of a job: ovphysx attribute -> one value per step."""
    columns = {
        "jointPositionTarget": job.target_position,
        "jointVelocityTarget": job.target_velocity,
        "jointStiffness": job.stiffness,
        "jointDamping": job.damping,
    }
    return {name: values for name, values in columns.items() if values is not None}


def _row(value: float) -> npt.NDArray[np.float32]:
    """One single-axis joint row (float32, ovphysx's element type)."""
    return np.array([value], dtype=np.float32)


def _sample(physx: Any, attributes: Sequence[str], paths: Sequence[str] = (JOINT_PATH,)) -> np.ndarray:
    """Single-axis values of ``attributes`` (rows) of the joints at ``paths`` (columns), ovphysx units."""
    values = _read_joints(physx, attributes, paths[0] if len(paths) == 1 else None)  # one: read only it
    return np.array([[float(values[name][path][0]) for path in paths] for name in attributes])


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

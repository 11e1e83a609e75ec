"""The result of a chain run: per step, every joint's position, velocity and effort.

Row 0 is the initial state (effort 0.0); row ``i >= 1`` the state at the end of step ``i``.
:meth:`ChainTrajectory.joint` gives one joint's columns as a one-joint
:class:`~drive_envelope._src.scenario.trajectory.Trajectory`. Files: CSV with the header
``time,<joint>.position,<joint>.velocity,<joint>.effort,...`` or JSON with the same columns plus
the metadata (the suffix picks: ``.csv``/``.txt``/none or ``.json``), written atomically.
"""

from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.atomic import atomic_path
from drive_envelope._src.scenario.trajectory import Trajectory, trajectory_format

if TYPE_CHECKING:
    from drive_envelope._src.scenario.chain import ChainScenario

FloatArray = npt.NDArray[np.float64]
_QUANTITIES = ("position", "velocity", "effort")


@dataclass(frozen=True, kw_only=True, slots=True)
class ChainTrajectory:
    """Sampled states of a chain: ``time`` has ``steps + 1`` rows, the others ``(steps + 1, dofs)``."""

    time: FloatArray
    """Time at the end of each step, ``time[0] = 0`` [s]."""
    position: FloatArray
    """Joint positions [rad or m], one column per joint."""
    velocity: FloatArray
    """Joint velocities [rad/s or m/s]."""
    effort: FloatArray
    """Per joint, the step's effort as the engine reports it (``metadata["effort_source"]``);
    ``effort[0] = 0`` [N*m or N]."""
    joints: tuple[str, ...]
    """Joint names, one per column."""
    types: tuple[JointType, ...]
    """Joint types, which fix each column's units."""
    engine: str = ""
    """Engine that produced it (``reference``, ``physx``, ``mujoco``, ``newton``)."""
    name: str = ""
    """Scenario name."""
    metadata: dict[str, Any] = field(default_factory=dict)
    """JSON-compatible details (solver settings, precision, effort source)."""

    def __post_init__(self) -> None:
        time = np.asarray(self.time, dtype=np.float64)
        object.__setattr__(self, "time", time)
        shape = (time.shape[0], len(self.joints))
        if len(self.types) != len(self.joints):
            raise InputError(f"chain trajectory: {len(self.types)} joint types for {len(self.joints)} joints")
        for column in _QUANTITIES:
            values = np.asarray(getattr(self, column), dtype=np.float64)
            if values.shape != shape:
                raise InputError(
                    f"chain trajectory column {column!r}: expected shape {shape}, got {values.shape}"
                )
            if not np.isfinite(values).all():
                row, col = (int(i[0]) for i in np.nonzero(~np.isfinite(values)))
                raise InputError(
                    f"trajectory {self.name or self.engine!r}: {self.joints[col]}.{column} at row {row} is "
                    f"{float(values[row, col])!r}; expected finite numbers"
                )
            object.__setattr__(self, column, values)

    def __len__(self) -> int:
        return int(self.time.shape[0])

    def index(self, joint: str | int) -> int:
        """Column of a joint given by name or index.

        Raises:
            InputError: no such joint.
        """
        if (
            isinstance(joint, int)
            and not isinstance(joint, bool)
            and -len(self.joints) <= joint < len(self.joints)
        ):
            return joint % len(self.joints)
        if joint in self.joints:
            return self.joints.index(joint)  # type: ignore[arg-type]
        raise InputError(f"chain trajectory: no joint {joint!r}; joints: {', '.join(self.joints)}")

    def joint(self, joint: str | int) -> Trajectory:
        """One joint's columns as a one-joint trajectory."""
        i = self.index(joint)
        return Trajectory(
            time=self.time,
            position=self.position[:, i],
            velocity=self.velocity[:, i],
            effort=self.effort[:, i],
            joint=self.types[i],
            engine=self.engine,
            name=f"{self.name}:{self.joints[i]}" if self.name else self.joints[i],
            metadata=dict(self.metadata),
        )

    def columns(self) -> dict[str, FloatArray]:
        """``time`` and ``<joint>.<quantity>`` columns, in file order."""
        result = {"time": self.time}
        for i, name in enumerate(self.joints):
            for quantity in _QUANTITIES:
                result[f"{name}.{quantity}"] = getattr(self, quantity)[:, i]
        return result

    def header(self) -> dict[str, Any]:
        """Everything but the columns (JSON-compatible)."""
        units = {"revolute": ("rad", "rad/s", "N*m"), "prismatic": ("m", "m/s", "N")}
        return {
            "engine": self.engine,
            "name": self.name,
            "joints": list(self.joints),
            "types": list(self.types),
            "units": {
                f"{name}.{quantity}": unit
                for name, kind in zip(self.joints, self.types, strict=True)
                for quantity, unit in zip(_QUANTITIES, units[kind], strict=True)
            },
            "metadata": self.metadata,
        }


def chain_run(scenario: ChainScenario, engine: str, *columns: FloatArray, **metadata: Any) -> ChainTrajectory:
    """An engine's run of ``scenario``: its position, velocity and effort ``columns`` from t = 0.

    Rows ``(steps + 1, dofs)``, one every ``dt`` [s]; the metadata holds the scenario's solver
    settings, then ``metadata``.
    """
    sim = scenario.simulation
    position, velocity, effort = columns
    return ChainTrajectory(
        time=np.arange(position.shape[0], dtype=np.float64) * sim.dt,
        position=position,
        velocity=velocity,
        effort=effort,
        joints=scenario.names,
        types=tuple(joint.type for joint in scenario.joints),
        engine=engine,
        name=scenario.name,
        metadata={**sim.metadata(), **metadata},
    )


def chain_trajectory_to_csv(trajectory: ChainTrajectory) -> str:
    """CSV text, header ``time,<joint>.position,<joint>.velocity,<joint>.effort,...``."""
    columns = trajectory.columns()
    buffer = io.StringIO()
    buffer.write(",".join(columns) + "\n")
    rows = np.column_stack(list(columns.values())).tolist()
    buffer.write("".join(",".join(repr(v) for v in row) + "\n" for row in rows))  # repr: exact float64
    return buffer.getvalue()


def chain_trajectory_to_json(trajectory: ChainTrajectory) -> str:
    """JSON text: the header keys, then one list per column."""
    data: dict[str, Any] = dict(trajectory.header())
    data.update({name: values.tolist() for name, values in trajectory.columns().items()})
    return json.dumps(data, indent=1) + "\n"


def save_chain_trajectory(
    trajectory: ChainTrajectory,
    path: str | os.PathLike[str],
    *,
    format: str | None = None,
    force: bool = False,
) -> None:
    """Write a chain trajectory atomically as CSV or JSON (the suffix picks, or ``format``).

    Raises:
        InputError: an unknown suffix, Parquet (not written for chains yet), or a file that cannot
            be written.
    """
    chosen = trajectory_format(path, format)
    if chosen == "parquet":
        raise InputError(f"--output {os.fspath(path)!r}: chain trajectories are written as CSV or JSON")
    text = chain_trajectory_to_json(trajectory) if chosen == "json" else chain_trajectory_to_csv(trajectory)
    with atomic_path(path, force=force) as tmp, open(tmp, "w", encoding="utf-8", newline="") as handle:
        handle.write(text)

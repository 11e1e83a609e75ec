"""Per-step drive commands: the targets and the power state a bench log recorded, step by step.

A :class:`DriveSchedule` replaces a scenario's constant ``drive.target_position`` and
``drive.target_velocity`` with one value per time step, and says in which steps the drive is
powered. Step ``i`` runs from ``time[i]`` to ``time[i + 1]`` with ``target_position[i]``: the goal a
controller wrote at sample ``i`` acts until the next sample, as on a servo bus. An unpowered step has
zero drive gains (PhysX: stiffness and damping written 0): the drive gives no effort, the joint
swings free under its loads, and friction still acts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True, kw_only=True, slots=True)
class DriveSchedule:
    """Drive targets and power state per time step (all arrays of one length, ``steps``)."""

    target_position: FloatArray
    """Drive target position over each step [rad or m]."""
    target_velocity: FloatArray
    """Drive target velocity over each step [rad/s or m/s]."""
    enabled: BoolArray
    """Whether the drive is powered over each step; False: zero drive gains (free joint)."""

    def __post_init__(self) -> None:
        arrays = {
            "target_position": np.asarray(self.target_position, dtype=np.float64),
            "target_velocity": np.asarray(self.target_velocity, dtype=np.float64),
            "enabled": np.asarray(self.enabled, dtype=np.bool_),
        }
        lengths = {name: values.shape for name, values in arrays.items()}
        if any(len(shape) != 1 for shape in lengths.values()) or len(set(lengths.values())) != 1:
            raise InputError(f"drive schedule: expected 1-D arrays of one length, got shapes {lengths}")
        for name in ("target_position", "target_velocity"):
            bad = np.flatnonzero(~np.isfinite(arrays[name]))
            if bad.size:
                raise InputError(
                    f"drive schedule: {name} at step {int(bad[0])} is {float(arrays[name][bad[0]])!r}; "
                    "expected finite numbers"
                )
        for name, values in arrays.items():
            object.__setattr__(self, name, values)

    @property
    def steps(self) -> int:
        """Number of time steps the schedule covers."""
        return int(self.target_position.shape[0])

    def check_steps(self, steps: int, where: str) -> None:
        """Refuse a schedule whose length is not the scenario's number of steps.

        Raises:
            InputError: the lengths differ.
        """
        if self.steps != steps:
            raise InputError(f"{where}: the drive schedule has {self.steps} steps, the scenario {steps}")

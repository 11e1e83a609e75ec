"""The handle :func:`~drive_envelope._src.adapters.mujoco.spec.add_drive` returns: a drive's names.

It lives apart from ``spec`` so that the model-side functions (``params``, ``readout``) can take it
without importing the spec helpers.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import TYPE_CHECKING

from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import read_quantity

if TYPE_CHECKING:
    import mujoco

_TARGETS = {
    "pos": ("position", "rad", "m"),
    "vel": ("velocity", "rad/s", "m/s"),
    "ff": ("effort", "N*m", "N"),
}
"""Input -> (``set_targets`` argument, revolute SI unit, prismatic SI unit)."""


def read_number(value: object, unit: str, where: str) -> float:
    """A value given to a model-side call in SI [``unit``]: a real number, or a string with units."""
    if isinstance(value, str):
        return read_quantity(value, unit, where)
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    raise InputError(f"{where}: expected a number [{unit}] or a string with units, got {value!r}")


@dataclass(frozen=True, kw_only=True, slots=True)
class MjDrive:
    """A drive added by :func:`add_drive`: the names to find it in the compiled model."""

    name: str
    """Drive name: the first actuator (which carries the effort and the numbers)."""
    joint: str
    """The hinge or slide joint it drives."""
    instance: str
    """The plugin instance (shared by every drive with the same inputs and drive type)."""
    actuators: tuple[str, ...]
    """One actuator per input, in the order of :attr:`inputs`; the first carries the effort."""
    inputs: tuple[str, ...]
    """Control inputs, a subset of ``("pos", "vel", "ff")`` in canonical order."""
    envelope: PerformanceEnvelope
    """The performance envelope (joint side, SI) it was added with."""
    stiffness: float
    """Drive stiffness [N*m/rad or N/m] (force drive) or [1/s^2] (acceleration drive)."""
    damping: float
    """Drive damping [N*m*s/rad or N*s/m] (force drive) or [1/s] (acceleration drive)."""
    drive_type: DriveType = "force"
    """``"force"`` or ``"acceleration"``."""
    effort_sensor: str = ""
    """Name of the ``actuatorfrc`` sensor on the first actuator, empty if none was added."""
    replaced: tuple[str, ...] = ()
    """Names of the joint's actuators it replaced (``replace=True``); the first became :attr:`name`."""

    def control_index(self, model: mujoco.MjModel, name: str) -> int:
        """Index in ``data.ctrl`` of input ``name`` (``"pos"``, ``"vel"`` or ``"ff"``).

        Raises:
            InputError: the drive has no such input.
        """
        if name not in self.inputs:
            raise InputError(
                f"drive {self.name!r}: no input {name!r}; its inputs are {', '.join(self.inputs)}"
            )
        import mujoco

        actuator = self.actuators[self.inputs.index(name)]
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)
        if index < 0:  # -1 would index the model's last control
            raise InputError(
                f"drive {self.name!r}: the model has no actuator {actuator!r}; "
                "expected the model compiled from the spec add_drive was given"
            )
        return int(model.actuator_ctrladr[index])

    def _target(self, name: str, value: object) -> float:
        """One control value in SI: a finite real number, or a string with units ("90 deg")."""
        argument, revolute, prismatic = _TARGETS[name]
        unit = revolute if self.envelope.joint == "revolute" else prismatic
        where = f"drive {self.name!r}: set_targets: argument {argument!r}"
        number = read_number(value, unit, where)
        # MuJoCo would take a NaN or inf control, warn once and zero every control of the model
        if not math.isfinite(number):
            raise InputError(f"{where} = {value!r}: expected a finite target [{unit}]")
        return number

    def set_targets(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        *,
        position: float | None = None,
        velocity: float | None = None,
        effort: float | None = None,
    ) -> None:
        """Write the drive's controls; None leaves a control as it is.

        Args:
            model: The compiled model.
            data: Its data.
            position: Target position [rad or m] (input ``pos``).
            velocity: Target velocity [rad/s or m/s] (input ``vel``).
            effort: Feed-forward effort [N*m or N] (input ``ff``), counted as actuator effort.

        Each is a real number in SI or a string with units (``"90 deg"``, ``"300 rpm"``).

        Raises:
            InputError: the drive has no such input, a value that is not a finite number (or
                a string with a unit of the right dimension), or a model without the drive.
        """
        writes = [
            (self.control_index(model, name), self._target(name, value))
            for name, value in (("pos", position), ("vel", velocity), ("ff", effort))
            if value is not None
        ]
        for index, value in writes:  # all checked first: a refused call writes nothing
            data.ctrl[index] = value

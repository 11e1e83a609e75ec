"""The handle :func:`~drive_envelope._src.adapters.mujoco.spec.add_drive` returns: a drive's names.

It lives apart from ``spec`` so that the model-side functions (``params``, ``readout``) can take it
without importing the spec helpers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from drive_envelope._src.envelope.drive import DriveType
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco


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
        return int(model.actuator_ctrladr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, actuator)])

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
        """
        for name, value in (("pos", position), ("vel", velocity), ("ff", effort)):
            if value is not None:
                data.ctrl[self.control_index(model, name)] = value

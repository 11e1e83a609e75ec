"""The parameters ``identify`` can estimate: names, units, starting values and search intervals.

Twelve names, in SI, joint side: the envelope's four (``max_effort``, ``max_actuator_velocity``,
``velocity_dependent_resistance``, ``speed_effort_gradient``), the drive's ``stiffness`` and
``damping``, a servo's ``duty_effort`` (the effort its position loop commands at full duty:
stiffness is ``duty_per_rad * duty_effort``), PhysX's joint friction (``static_friction``,
``dynamic_friction``, ``viscous_friction``), ``armature`` and the pendulum's ``angle_offset``.
Starting values come from the stand; a search interval from the stand's ``[bounds]`` or, by
default, from the parameter's scale:

* gains and limits with a positive start (``max_effort``, ``max_actuator_velocity``, ``stiffness``,
  ``damping``, ``duty_effort``): a factor 10 either side, searched on a log scale;
* slopes, friction and armature: ``[0, 10 x scale]`` with the effort scale ``max_effort``, the speed
  scale the largest measured speed and the inertia scale the stand's joint-space inertia;
* ``angle_offset``: +-0.2 rad around its start.

On a stand with Coulomb friction (``static_friction == dynamic_friction``), fitting only one of the
two moves both; likewise ``duty_effort`` follows ``max_effort`` unless it is fitted or the stand's
``[servo]`` gives it (a servo whose full duty is its stall effort). ``dynamic_friction`` is held at
or below ``static_friction`` in the replay.

:class:`ParameterSpace` maps the optimizer's unit cube to parameter values and back.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError
from drive_envelope._src.params.table import PARAMETERS as ENVELOPE_PARAMETERS
from drive_envelope._src.scenario.spec import Scenario

FloatArray = npt.NDArray[np.float64]

_STAND_UNITS: dict[str, tuple[str, str]] = {
    "stiffness": ("N*m/rad", "N/m"),
    "duty_effort": ("N*m", "N"),
    "damping": ("N*m*s/rad", "N*s/m"),
    "static_friction": ("N*m", "N"),
    "dynamic_friction": ("N*m", "N"),
    "viscous_friction": ("N*m*s/rad", "N*s/m"),
    "armature": ("kg*m**2", "kg"),
    "angle_offset": ("rad", "rad"),
}
"""The stand's own parameters (not in the envelope table) -> SI unit (revolute, prismatic)."""
IDENTIFIABLE: dict[str, tuple[str, str]] = {
    # the envelope's four from the one parameter table, so identify and every engine agree on units
    **{row.name: (row.unit_revolute, row.unit_prismatic) for row in ENVELOPE_PARAMETERS},
    **_STAND_UNITS,
}
"""Every parameter ``identify`` can estimate -> SI unit (revolute, prismatic)."""
DEFAULT_FIT = (
    "max_effort",
    "max_actuator_velocity",
    "velocity_dependent_resistance",
    "speed_effort_gradient",
)
"""What ``--fit`` estimates when not given: the four envelope parameters."""
_LOG_SCALE = ("max_effort", "max_actuator_velocity", "stiffness", "damping", "duty_effort")


def parameter_units(joint: str = "revolute") -> dict[str, str]:
    """SI unit of every parameter for the joint type."""
    index = 0 if joint == "revolute" else 1
    return {name: units[index] for name, units in IDENTIFIABLE.items()}


def start_values(scenario: Scenario, duty_effort: float | None = None) -> dict[str, float]:
    """Every parameter's value in the stand (SI): the starting or fixed values.

    Args:
        scenario: The stand's scenario.
        duty_effort: The stand's ``[servo] duty_effort`` [N*m or N]; None: ``drive.max_effort``.
    """
    envelope = scenario.effective_envelope()
    drive, friction = scenario.drive, scenario.friction
    return {
        "max_effort": drive.max_effort,
        "max_actuator_velocity": envelope.max_actuator_velocity if envelope else math.inf,
        "velocity_dependent_resistance": envelope.velocity_dependent_resistance if envelope else 0.0,
        "speed_effort_gradient": envelope.speed_effort_gradient if envelope else 0.0,
        "stiffness": drive.stiffness,
        "duty_effort": drive.max_effort if duty_effort is None else duty_effort,
        "damping": drive.damping,
        "static_friction": friction.static_friction,
        "dynamic_friction": friction.dynamic_friction,
        "viscous_friction": friction.viscous_friction,
        "armature": scenario.joint.armature,
        "angle_offset": scenario.pendulum.angle_offset if scenario.pendulum is not None else 0.0,
    }


@dataclass(frozen=True, slots=True)
class ParameterSpace:
    """The fitted parameters' intervals and the fixed values of the rest (SI)."""

    names: tuple[str, ...]
    """Fitted parameters, in ``--fit`` order."""
    low: FloatArray
    """Lower bound of each fitted parameter [SI]."""
    high: FloatArray
    """Upper bound of each fitted parameter [SI]."""
    start: FloatArray
    """Starting value of each fitted parameter, inside its interval [SI]."""
    log_scale: tuple[bool, ...]
    """Whether each is searched on a log scale."""
    fixed: dict[str, float]
    """Every parameter's stand value (the fitted ones' starts included) [SI]."""
    tied: tuple[tuple[str, str], ...] = ()
    """``(follower, leader)`` pairs: the follower takes the leader's value (Coulomb friction)."""

    @property
    def size(self) -> int:
        """Number of fitted parameters."""
        return len(self.names)

    def to_values(self, unit: npt.ArrayLike) -> dict[str, FloatArray]:
        """Every parameter for candidates in the unit cube: ``unit`` of shape ``(n, S)``.

        Returns:
            Name -> array ``(S,)`` [SI]: fitted ones mapped from the cube, fixed ones broadcast.
        """
        cube = np.clip(np.atleast_2d(np.asarray(unit, dtype=np.float64)), 0.0, 1.0)
        count = cube.shape[1]
        values = {name: np.full(count, value) for name, value in self.fixed.items()}
        for i, name in enumerate(self.names):
            low, high = self.low[i], self.high[i]
            if self.log_scale[i]:
                values[name] = np.exp(np.log(low) + cube[i] * (np.log(high) - np.log(low)))
            else:
                values[name] = low + cube[i] * (high - low)
        for follower, leader in self.tied:
            values[follower] = values[leader].copy()
        return values

    def to_unit(self, values: Sequence[float] | FloatArray) -> FloatArray:
        """The unit-cube point of fitted parameter values (SI), shape ``(n,)``."""
        x = np.asarray(values, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            logs = (np.log(x) - np.log(self.low)) / (np.log(self.high) - np.log(self.low))
        lines = (x - self.low) / (self.high - self.low)
        return np.clip(np.where(np.asarray(self.log_scale), logs, lines), 0.0, 1.0)


def build_space(
    scenario: Scenario,
    names: Sequence[str],
    *,
    bounds: Mapping[str, tuple[float, float]],
    speed_scale: float,
    source: str,
    duty_effort: float | None = None,
) -> ParameterSpace:
    """The search space for ``names`` on this stand.

    Args:
        scenario: The stand's scenario (starting and fixed values).
        names: Parameters to fit.
        bounds: The stand's ``[bounds]``.
        speed_scale: A typical joint speed [rad/s or m/s]: the largest measured speed.
        source: The stand file (for messages).
        duty_effort: The stand's ``[servo] duty_effort`` [N*m or N], or None: it then follows
            ``max_effort`` unless fitted.

    Raises:
        InputError: an unknown or repeated name, a parameter the stand cannot start from (an
            unlimited ``max_effort``, an infinite ``max_actuator_velocity``, ``angle_offset``
            without a pendulum), or a start outside its bounds.
    """
    fixed = start_values(scenario, duty_effort)
    for name in names:
        if name not in IDENTIFIABLE:
            raise InputError(
                f"--fit {name!r}: unknown parameter; expected names from: {', '.join(IDENTIFIABLE)}"
            )
    if len(set(names)) != len(names):
        raise InputError(f"--fit {','.join(names)}: a parameter is named twice")
    effort = fixed["max_effort"]
    if not (math.isfinite(effort) and effort > 0.0):
        raise InputError(
            f"{source}: key 'drive.max_effort' = {effort!r}: identify needs a finite max_effort > 0 "
            "(the envelope's maxEffort), the starting value and the effort scale"
        )
    if "angle_offset" in names and scenario.pendulum is None:
        raise InputError(f"--fit angle_offset: {source} has no [pendulum] table")
    if "max_actuator_velocity" in names and math.isinf(fixed["max_actuator_velocity"]):
        raise InputError(
            f"--fit max_actuator_velocity: {source} gives no finite starting value; set "
            "envelope.max_actuator_velocity (e.g. a datasheet's no-load speed)"
        )
    scales = {
        "velocity_dependent_resistance": effort / speed_scale,
        "speed_effort_gradient": speed_scale / effort,
        "static_friction": effort,
        "dynamic_friction": effort,
        "viscous_friction": effort / speed_scale,
        "damping": effort / speed_scale,
        "stiffness": effort,
        "duty_effort": effort,
        "armature": scenario.effective_inertia,
    }
    low, high, logs = [], [], []
    for name in names:
        interval, log_scale = _interval(name, fixed[name], scales.get(name, 1.0), bounds.get(name))
        start = fixed[name]
        if not interval[0] <= start <= interval[1]:
            raise InputError(
                f"{source}: the starting value of {name} ({start!r}) is outside its bounds {list(interval)}"
            )
        low.append(interval[0])
        high.append(interval[1])
        logs.append(log_scale)
    return ParameterSpace(
        names=tuple(names),
        low=np.array(low),
        high=np.array(high),
        start=np.array([fixed[name] for name in names]),
        log_scale=tuple(logs),
        fixed=fixed,
        tied=_coulomb_tie(names, fixed) + _duty_tie(names, duty_effort),
    )


def _duty_tie(names: Sequence[str], duty_effort: float | None) -> tuple[tuple[str, str], ...]:
    """``duty_effort`` follows ``max_effort`` when only the latter is fitted and the stand sets none."""
    if duty_effort is None and "max_effort" in names and "duty_effort" not in names:
        return (("duty_effort", "max_effort"),)
    return ()


def _coulomb_tie(names: Sequence[str], fixed: Mapping[str, float]) -> tuple[tuple[str, str], ...]:
    """Static follows dynamic friction (or the reverse) when only one is fitted on a Coulomb stand."""
    if fixed["static_friction"] != fixed["dynamic_friction"]:
        return ()
    if "static_friction" in names and "dynamic_friction" not in names:
        return (("dynamic_friction", "static_friction"),)
    if "dynamic_friction" in names and "static_friction" not in names:
        return (("static_friction", "dynamic_friction"),)
    return ()


def _interval(
    name: str, start: float, scale: float, given: tuple[float, float] | None
) -> tuple[tuple[float, float], bool]:
    if given is not None:
        low, high = given
        return (low, high), name in _LOG_SCALE and low > 0.0 and high / low > 20.0
    if name == "angle_offset":
        return (start - 0.2, start + 0.2), False
    if name in _LOG_SCALE and start > 0.0:
        return (start / 10.0, start * 10.0), True
    return (0.0, max(10.0 * scale, 2.0 * start)), False

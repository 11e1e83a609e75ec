"""The loads a bench has besides a constant effort: a gravity pendulum and PhysX joint friction.

``[pendulum]`` hangs a point mass on a revolute joint: ``mass`` [kg] at ``distance`` [m] from the
axis, ``angle_offset`` [rad] between the joint's zero and the mass hanging straight down. It adds
``mass*distance^2`` to the joint-space inertia and the gravity effort
``-mass*gravity*distance*sin(position + angle_offset)`` [N*m] (``[simulation] gravity``, 9.80665
m/s^2 by default). Gravity comes from outside the actuator: the envelope does not limit it.

``[friction]`` is PhysX 5.6's articulation joint friction (``PxJointFrictionParams``, USD
``physxJointAxis:<axis>:staticFrictionEffort``, ``dynamicFrictionEffort``,
``viscousFrictionCoefficient``): ``static_friction`` and ``dynamic_friction`` [N*m or N],
``viscous_friction`` [N*m*s/rad or N*s/m]. In each solver iteration, after the drive, PhysX takes the
impulse that would stop the joint; when its magnitude is above ``static_friction*dt`` it is clipped
to ``(dynamic_friction + viscous_friction*|v|)*dt``. Friction is not actuator effort either.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.checks import check_finite, quantities, require, unit_for
from drive_envelope._src.validation import check_keys

STANDARD_GRAVITY = 9.80665
"""Default gravitational acceleration of a pendulum stand [m/s^2]."""

FRICTION_KEYS = ("static_friction", "dynamic_friction", "viscous_friction")
PENDULUM_KEYS = ("mass", "distance", "angle_offset")


@dataclass(frozen=True, kw_only=True, slots=True)
class PendulumSpec:
    """A point mass on the joint's link, pulled by gravity (revolute joints only)."""

    mass: float
    """Point mass [kg]; ``> 0``."""
    distance: float
    """Distance from the joint axis to the point mass [m]; ``>= 0``."""
    angle_offset: float = 0.0
    """Joint angle of the straight-down pose is ``-angle_offset`` [rad]; 0: hanging down at 0."""

    def __post_init__(self) -> None:
        check_finite("pendulum.mass", self.mass, positive=True)
        check_finite("pendulum.distance", self.distance, nonnegative=True)
        check_finite("pendulum.angle_offset", self.angle_offset)

    @property
    def inertia(self) -> float:
        """Moment of inertia of the point mass about the joint axis [kg*m^2]."""
        return self.mass * self.distance**2

    def gravity_effort(self, position: Any, gravity: float) -> Any:
        """Gravity's effort on the joint, ``-m*g*d*sin(position + angle_offset)`` [N*m].

        Args:
            position: Joint position [rad]; a float or a NumPy array.
            gravity: Gravitational acceleration [m/s^2].
        """
        import numpy as np

        return -self.mass * gravity * self.distance * np.sin(position + self.angle_offset)


@dataclass(frozen=True, kw_only=True, slots=True)
class FrictionSpec:
    """PhysX 5.6 articulation joint friction (``PxJointFrictionParams``); all 0 by default."""

    static_friction: float = 0.0
    """Break-away effort: a joint whose stopping effort is below it stays stopped [N*m or N]; ``>= 0``."""
    dynamic_friction: float = 0.0
    """Coulomb effort against the motion once moving [N*m or N]; ``0 <= dynamic <= static``."""
    viscous_friction: float = 0.0
    """Effort per unit joint speed against the motion [N*m*s/rad or N*s/m]; ``>= 0``."""

    def __post_init__(self) -> None:
        for name in FRICTION_KEYS:
            check_finite(f"friction.{name}", getattr(self, name), nonnegative=True)
        if self.dynamic_friction > self.static_friction:
            # PhysX's schema asks for it, and with static = viscous = 0 PhysX would ignore it
            raise InputError(
                f"friction.dynamic_friction ({self.dynamic_friction!r}) must be <= "
                f"friction.static_friction ({self.static_friction!r}), as PhysX's schema requires"
            )

    @property
    def active(self) -> bool:
        """Whether PhysX runs its friction model: static or viscous friction is nonzero."""
        return self.static_friction != 0.0 or self.viscous_friction != 0.0


def read_pendulum(data: Mapping[str, Any], joint: str, source: str) -> PendulumSpec | None:
    """The ``[pendulum]`` table (None when absent).

    Raises:
        InputError: an unknown or missing key, a bad value, or a pendulum on a prismatic joint.
    """
    if not data:
        return None
    check_keys(data, PENDULUM_KEYS, source, "pendulum")
    if joint != "revolute":
        raise InputError(f"{source}: [pendulum] needs a revolute joint, got joint.type {joint!r}")
    require(data, "pendulum", {"mass": "kg", "distance": "m"}, source)
    units = {"mass": "kg", "distance": "m", "angle_offset": "rad"}
    return PendulumSpec(**quantities(data, "pendulum", units, source))


def read_friction(data: Mapping[str, Any], joint: str, source: str) -> FrictionSpec:
    """The ``[friction]`` table (no friction when absent)."""
    check_keys(data, FRICTION_KEYS, source, "friction")
    effort = unit_for(joint, "N*m", "N")
    units = {
        "static_friction": effort,
        "dynamic_friction": effort,
        "viscous_friction": unit_for(joint, "N*m*s/rad", "N*s/m"),
    }
    values = quantities(data, "friction", units, source)
    if "dynamic_friction" in values and "static_friction" not in values:
        values["static_friction"] = values["dynamic_friction"]  # Coulomb: break away at the sliding effort
    return FrictionSpec(**values)

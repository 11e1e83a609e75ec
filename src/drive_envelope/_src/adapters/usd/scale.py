"""Conversion factors between SI joint-side values and the numbers a USD stage stores.

UsdPhysics measures lengths in stage units (``metersPerUnit``) and masses in stage mass units
(``kilogramsPerUnit``); PhysX simulates in those units as they are, so an effort of 1 N*m in a
centimetre stage is ``1e4`` kg*cm^2/s^2. Angular drive instances (``angular``, ``rotX|Y|Z``) also store
angles in degrees: velocities in deg/s and every "per angle" quantity per degree (PhysX converts them
back, ``physx/.../usdLoad/Joint.cpp`` ``fillPhysxPerformanceEnvelopeDesc`` and ``fillPhysxDriveDesc``).

Every factor ``f`` here maps SI to USD: ``usd_value = si_value * f``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

ANGULAR_INSTANCES = ("angular", "rotX", "rotY", "rotZ")
"""Drive instances whose values USD stores per degree."""
LINEAR_INSTANCES = ("linear", "transX", "transY", "transZ")
"""Drive instances with linear (length) values."""

_RAD_PER_DEG = math.pi / 180.0


def is_angular(instance: str) -> bool:
    """Whether ``instance`` is an angular drive instance (degrees in USD)."""
    return instance in ANGULAR_INSTANCES


@dataclass(frozen=True, kw_only=True, slots=True)
class StageUnits:
    """The unit metadata of a stage and the SI -> USD factors derived from it."""

    meters_per_unit: float = 1.0
    """Stage length unit [m] (``UsdGeom.GetStageMetersPerUnit``; USD's fallback is 0.01)."""
    kilograms_per_unit: float = 1.0
    """Stage mass unit [kg] (``UsdPhysics.GetStageKilogramsPerUnit``; fallback 1)."""

    def __post_init__(self) -> None:
        for name in ("meters_per_unit", "kilograms_per_unit"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")

    def effort(self, instance: str) -> float:
        """Factor for efforts (maxForce): torque N*m -> kgu*lu^2/s^2, force N -> kgu*lu/s^2."""
        length_power = 2 if is_angular(instance) else 1
        return 1.0 / (self.kilograms_per_unit * self.meters_per_unit**length_power)

    def velocity(self, instance: str) -> float:
        """Factor for speeds: rad/s -> deg/s, m/s -> lu/s."""
        return 1.0 / _RAD_PER_DEG if is_angular(instance) else 1.0 / self.meters_per_unit

    def position(self, instance: str) -> float:
        """Factor for positions: rad -> deg, m -> lu."""
        return self.velocity(instance)

    def per_speed(self, instance: str) -> float:
        """Factor for effort per speed (resistance, damping): N*m*s/rad -> per deg, N*s/m -> per lu."""
        return self.effort(instance) / self.velocity(instance)

    def per_position(self, instance: str) -> float:
        """Factor for effort per position (stiffness): N*m/rad -> per deg, N/m -> per lu."""
        return self.effort(instance) / self.position(instance)

    def speed_per_effort(self, instance: str) -> float:
        """Factor for speed per effort (speedEffortGradient): (rad/s)/(N*m) -> (deg/s)/torque unit."""
        return self.velocity(instance) / self.effort(instance)

    def mass(self) -> float:
        """Factor for masses: kg -> stage mass units."""
        return 1.0 / self.kilograms_per_unit

    def inertia(self) -> float:
        """Factor for moments of inertia: kg*m^2 -> kgu*lu^2."""
        return 1.0 / (self.kilograms_per_unit * self.meters_per_unit**2)

    def length(self) -> float:
        """Factor for lengths: m -> stage units."""
        return 1.0 / self.meters_per_unit

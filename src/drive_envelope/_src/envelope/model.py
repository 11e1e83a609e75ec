r"""The performance envelope: two coupled linear limits in the (joint velocity, drive effort) plane.

For a joint velocity ``v`` and a drive effort ``tau`` (joint side, SI) the envelope admits::

    |tau| <= max_effort - velocity_dependent_resistance * |v|          (eq. 1, torque-speed line)
    |v|   <= max_actuator_velocity - speed_effort_gradient * |tau|     (eq. 2, speed-torque line)

The feasible region is symmetric under ``(v, tau) -> (-v, tau)`` and ``(v, tau) -> (v, -tau)``: the
braking quadrants (effort opposite to velocity) obey the same curves as the driving ones.

::

          tau
           ^  stall (0, tau_0)
           |______
           |      \___ eq. 1      corner: both lines bind
           |          \___  /
           |               *
           |                \  eq. 2
           +-----------------+----> v
                         no-load (v_0, 0)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError
from drive_envelope._src.params.table import si_unit
from drive_envelope._src.validation import check_numbers, nearest_key
from drive_envelope._src.values import read_quantity

JointType = Literal["revolute", "prismatic"]
ENVELOPE_FIELDS = (
    "max_effort",
    "max_actuator_velocity",
    "velocity_dependent_resistance",
    "speed_effort_gradient",
)
_JOINT_TYPES = ("revolute", "prismatic")

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]


class QuadrantCorners(NamedTuple):
    """Corner points of the feasible region in the first quadrant (v >= 0, effort >= 0).

    Every point is ``(velocity [rad/s or m/s], effort [N*m or N])``.
    """

    stall: tuple[float, float]
    """Largest effort at zero velocity: ``(0, min(max_effort, max_actuator_velocity / gradient))``."""
    corner: tuple[float, float] | None
    """Where eq. 1 and eq. 2 both bind, or None when one line lies inside the other."""
    no_load: tuple[float, float]
    """Largest velocity at zero effort: ``(min(max_actuator_velocity, max_effort / resistance), 0)``."""


NO_LIMIT_FIELDS = ("max_effort", "max_actuator_velocity")
"""The fields whose "no limit" is ``inf``: the one rule for every surface (Python, files, Isaac Lab;
the MuJoCo plugin writes it -1 in ``dynprm`` and reads it back as ``inf``; PhysX's FLT_MAX reads as it)."""


@dataclass(frozen=True, kw_only=True, slots=True)
class PerformanceEnvelope:
    """The PhysX drive performance envelope of one joint axis, joint side, SI units.

    Invalid values raise :class:`~drive_envelope.errors.InputError` (a ``ValueError``) naming the
    field and the value.
    """

    max_effort: float
    """Effort cap at zero velocity, PhysX ``maxEffort`` (the drive's maxForce) [N*m or N]. ``>= 0``;
    ``inf`` means no effort limit (PhysX's unauthored maxForce, FLT_MAX); 0 allows no effort at all."""
    max_actuator_velocity: float = math.inf
    """Velocity cap at zero effort, PhysX ``maxActuatorVelocity`` [rad/s or m/s]. ``>= 0``;
    ``inf`` means no speed limit."""
    velocity_dependent_resistance: float = 0.0
    """Effort lost per unit speed, slope of eq. 1, PhysX ``velocityDependentResistance``
    [N*m*s/rad or N*s/m]. ``>= 0``, finite."""
    speed_effort_gradient: float = 0.0
    """Speed lost per unit effort, slope of eq. 2, PhysX ``speedEffortGradient``
    [(rad/s)/(N*m) or (m/s)/N]. ``>= 0``, finite."""
    joint: JointType = "revolute"
    """Joint type, which fixes the units: ``"revolute"`` (N*m, rad/s) or ``"prismatic"`` (N, m/s)."""
    name: str = ""
    """Free-form label (actuator name), empty if none."""

    def __post_init__(self) -> None:
        if self.joint not in _JOINT_TYPES:
            raise InputError(f"joint must be 'revolute' or 'prismatic', got {self.joint!r}")
        for field in ENVELOPE_FIELDS:
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                hint = f"; a string with units: PerformanceEnvelope.from_dict({{{field!r}: ...}})"
                raise InputError(
                    f"{field} must be a number, got {value!r}" + (hint if isinstance(value, str) else "")
                )
            value = float(value)
            object.__setattr__(self, field, value)
            if math.isnan(value) or value < 0.0:
                raise InputError(f"{field} must be >= 0, got {value!r}")
            if math.isinf(value) and field not in NO_LIMIT_FIELDS:
                raise InputError(f"{field} must be finite, got {value!r}")

    # -- the two curves -------------------------------------------------------------------------

    def effort_limit(self, velocity: ArrayLike) -> FloatArray:
        """Largest |effort| the envelope allows at joint velocity ``velocity`` (eq. 1 and eq. 2).

        Args:
            velocity: Joint velocity [rad/s or m/s]; any shape, only ``|velocity|`` matters.

        Returns:
            ``min(max_effort - R*|v|, (v_max - |v|)/G)`` clipped at 0 [N*m or N]; the ``(v_max-|v|)/G``
            term is dropped when ``G = 0`` and then ``|v| > v_max`` gives 0. 0 means no effort is
            feasible at that speed. A NaN velocity gives 0 (the drive lets go); an infinite one the
            limit at infinite speed: 0 when ``R > 0`` or ``v_max`` is finite, else ``max_effort``.
        """
        check_numbers("effort_limit", velocity=velocity)
        speed = np.array(velocity, dtype=np.float64)  # a copy, 0-d for a scalar
        return self._effort_limit_of_speed(np.abs(speed, out=speed))

    def _effort_limit_of_speed(self, speed: FloatArray) -> FloatArray:
        """:meth:`effort_limit` of ``speed = |velocity|``, reusing ``speed``'s memory (hot path).

        The parameters are scalars here, so each term is formed only where it can bind: no ``0*inf``
        (``R = 0`` at an infinite speed) and no ``inf - inf`` (``v_max = inf``), hence no NaN but
        the one a NaN speed carries, which the final ``fmax`` turns into 0.
        """
        resistance, gradient = self.velocity_dependent_resistance, self.speed_effort_gradient
        if resistance > 0.0:
            # R*|v| beyond float range: -inf, then no effort (0); inf - inf (no effort cap at an
            # infinite speed) is NaN, which fmax turns into 0, the limit at infinite speed
            with np.errstate(over="ignore", invalid="ignore"):
                limit = np.multiply(speed, -resistance, out=np.empty_like(speed))
                limit += self.max_effort
        else:
            limit = np.full_like(speed, self.max_effort)
            if not math.isfinite(self.max_actuator_velocity):  # no line binds: only a NaN shows
                limit[np.isnan(speed)] = 0.0
        if math.isfinite(self.max_actuator_velocity):
            if gradient > 0.0:
                eq2 = np.subtract(self.max_actuator_velocity, speed, out=speed)
                with np.errstate(over="ignore"):  # a subnormal gradient: no effort limit from eq. 2
                    eq2 /= gradient  # not *= 1/G: 0 * inf would be NaN at |v| = v_max
                np.minimum(limit, eq2, out=limit)
            else:  # beyond the speed limit (or NaN): nothing
                limit[~(speed <= self.max_actuator_velocity)] = 0.0
        return np.fmax(limit, 0.0, out=limit)  # fmax: a NaN speed gives 0

    def velocity_at_effort(self, effort: ArrayLike) -> FloatArray:
        """Largest |velocity| the envelope allows while the drive exerts ``effort`` (eq. 1 and eq. 2).

        Args:
            effort: Drive effort [N*m or N]; any shape, only ``|effort|`` matters.

        Returns:
            ``min(v_max - G*|tau|, (max_effort - |tau|)/R)`` clipped at 0 [rad/s or m/s] (``inf``
            possible); with ``R = 0`` the second term is dropped and ``|tau| > max_effort`` gives 0.
        """
        magnitude = np.abs(np.asarray(effort, dtype=np.float64))
        gradient = self.speed_effort_gradient
        # G = 0: the speed cap does not depend on effort (no 0 * inf at an infinite effort)
        limit = self.max_actuator_velocity - (gradient * magnitude if gradient > 0.0 else 0.0)
        if self.velocity_dependent_resistance > 0.0:
            # a subnormal resistance: no speed limit from eq. 1 (inf); inf - inf (no effort cap at
            # an infinite effort): NaN, read as 0 below
            with np.errstate(over="ignore", invalid="ignore"):
                eq1 = (self.max_effort - magnitude) / self.velocity_dependent_resistance
            limit = np.minimum(limit, eq1)
        else:
            limit = np.where(magnitude > self.max_effort, 0.0, limit)
        return np.fmax(limit, 0.0)

    def contains(self, velocity: ArrayLike, effort: ArrayLike, *, atol: float = 0.0) -> npt.NDArray[np.bool_]:
        """Whether the operating points ``(velocity, effort)`` satisfy both curves.

        Args:
            velocity: Joint velocity [rad/s or m/s]; broadcast with ``effort``.
            effort: Drive effort [N*m or N].
            atol: Slack added to the right-hand side of both inequalities, in their own units.

        Returns:
            Boolean array of the broadcast shape.
        """
        speed = np.abs(np.asarray(velocity, dtype=np.float64))
        magnitude = np.abs(np.asarray(effort, dtype=np.float64))
        eq1 = magnitude <= self.max_effort - self.velocity_dependent_resistance * speed + atol
        eq2 = speed <= self.max_actuator_velocity - self.speed_effort_gradient * magnitude + atol
        return np.logical_and(eq1, eq2)

    def margins(self, velocity: ArrayLike, effort: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Signed distance of each operating point to each curve, positive inside.

        Returns:
            ``(effort_margin, velocity_margin)``: ``max_effort - R|v| - |tau|`` [N*m or N] and
            ``v_max - G|tau| - |v|`` [rad/s or m/s].
        """
        speed = np.abs(np.asarray(velocity, dtype=np.float64))
        magnitude = np.abs(np.asarray(effort, dtype=np.float64))
        effort_margin = self.max_effort - self.velocity_dependent_resistance * speed - magnitude
        velocity_margin = self.max_actuator_velocity - self.speed_effort_gradient * magnitude - speed
        return effort_margin, velocity_margin

    # -- geometry -------------------------------------------------------------------------------

    def stall_effort(self) -> float:
        """Largest effort at zero velocity [N*m or N]."""
        return float(self.effort_limit(0.0))

    def no_load_velocity(self) -> float:
        """Largest velocity at zero effort [rad/s or m/s] (``inf`` when unbounded)."""
        return float(self.velocity_at_effort(0.0))

    def corners(self, *, velocity_extent: float | None = None) -> QuadrantCorners:
        """Corner points of the first quadrant; the other quadrants mirror them.

        Args:
            velocity_extent: Cut for a region unbounded in velocity, as in :meth:`boundary`.
        """
        path = self.quadrant_path(velocity_extent=velocity_extent)
        interior = [tuple(map(float, p)) for p in path[1:-1] if p[0] > 0.0 and p[1] > 0.0]
        corner = (interior[0][0], interior[0][1]) if interior else None
        return QuadrantCorners(
            stall=(0.0, float(path[-1][1])), corner=corner, no_load=(float(path[0][0]), 0.0)
        )

    def quadrant_path(self, *, velocity_extent: float | None = None) -> FloatArray:
        """Outer boundary in the first quadrant, from the no-load point to the stall point.

        Args:
            velocity_extent: Cut for a region unbounded in velocity, as in :meth:`boundary`.

        Returns:
            Array ``(K, 2)`` of ``(velocity, effort)`` vertices, ``K`` in 2..3.
        """
        v0, stall = self.no_load_velocity(), self.stall_effort()
        if math.isinf(stall):  # a point [[v0, 0]] would pass for a polygon
            raise InputError(
                "the envelope is unbounded in effort (max_effort = inf and speed_effort_gradient = 0): "
                "it has no boundary polygon"
            )
        if math.isinf(v0):
            if velocity_extent is None or not velocity_extent > 0:
                raise InputError("the envelope is unbounded in velocity: pass velocity_extent > 0")
            v0 = float(velocity_extent)
        return _clip_quadrant(self, v0, stall)

    def boundary(self, *, velocity_extent: float | None = None) -> FloatArray:
        """Polygon of the feasible region in the (velocity, effort) plane, all four quadrants.

        Args:
            velocity_extent: Where to cut the region when it is unbounded in velocity
                (``max_actuator_velocity = inf`` and ``velocity_dependent_resistance = 0``)
                [rad/s or m/s]. Ignored for a bounded region.

        Returns:
            Array of shape ``(K, 2)``: vertices ``(velocity, effort)`` counter-clockwise starting at
            the positive no-load point, every corner included, the first vertex not repeated.

        Raises:
            InputError: the region is unbounded and no ``velocity_extent`` was given.
        """
        path = self.quadrant_path(velocity_extent=velocity_extent)
        flip_v, flip_both, flip_tau = np.array([-1.0, 1.0]), np.array([-1.0, -1.0]), np.array([1.0, -1.0])
        polygon = np.concatenate(
            [path, (path[::-1] * flip_v)[1:], (path * flip_both)[1:], (path[::-1] * flip_tau)[1:-1]]
        )
        return _dedupe(polygon + 0.0)  # + 0.0 turns -0.0 into 0.0

    # -- conversion -----------------------------------------------------------------------------

    def to_dict(self) -> dict[str, object]:
        """Plain dict with the SI values (``inf`` stays a float); ``from_dict`` inverts it."""
        data: dict[str, object] = {"name": self.name, "joint": self.joint}
        data.update({field: getattr(self, field) for field in ENVELOPE_FIELDS})
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, object], *, source: str = "envelope") -> PerformanceEnvelope:
        """Build an envelope from a mapping of SI numbers or strings with units.

        Args:
            data: Keys ``max_effort`` (required), ``max_actuator_velocity`` (default inf),
                ``velocity_dependent_resistance``, ``speed_effort_gradient`` (default 0), ``joint``
                (default "revolute"), ``name``. Values are SI numbers, ``"inf"``, or strings with units.
            source: File name or label used in error messages.

        Raises:
            InputError: unknown key (with the nearest valid one), missing ``max_effort``, a value of
                the wrong unit, negative, NaN or infinite where not allowed.
        """
        return envelope_from_mapping(data, source=source)


_KEYS = ("name", "joint", *ENVELOPE_FIELDS)


_SCENARIO_TABLES = ("joint", "drive", "envelope", "load", "pendulum", "friction", "simulation", "servo")
"""Tables of a scenario or stand file: one of them where an envelope goes is named as such."""


def require_envelope(value: object, where: str) -> PerformanceEnvelope:
    """``value`` if it is a :class:`PerformanceEnvelope`, else one line naming the call and the type.

    The clamps take the envelope first: a dict, a catalog name or the arguments swapped would
    otherwise fail deep inside as an ``AttributeError`` or ``float()``'s ``TypeError``.
    """
    if isinstance(value, PerformanceEnvelope):
        return value
    hint = (
        " (a file or catalog name: drive_envelope.datasheet.resolve_envelope)"
        if isinstance(value, str)
        else ""
    )
    raise InputError(
        f"{where}: argument 'envelope': expected a PerformanceEnvelope first{hint}, "
        f"got {type(value).__name__} {value!r}"
    )


def envelope_from_mapping(data: Mapping[str, object], *, source: str) -> PerformanceEnvelope:
    """Build a :class:`PerformanceEnvelope` from a mapping; every error names ``source`` and the key."""
    if not isinstance(data, Mapping):
        raise InputError(f"{source}: expected a table of envelope keys, got {type(data).__name__}")
    for key in data:
        if key not in _KEYS:
            if key in _SCENARIO_TABLES and isinstance(data[key], Mapping):
                # a scenario or stand ([joint], [drive]...) named where an envelope goes: say so
                raise InputError(
                    f"{source}: a scenario or stand file (its [{key}] table), not an envelope file "
                    "(max_effort, max_actuator_velocity, ... at the top level): give the envelope file, "
                    "datasheet or catalog name its [envelope] table names"
                )
            raise InputError(
                f"{source}: unknown key {key!r}{nearest_key(str(key), _KEYS)}; valid keys: {', '.join(_KEYS)}"
            )
    joint = data.get("joint", "revolute")
    if joint not in _JOINT_TYPES:
        raise InputError(f"{source}: key 'joint': expected 'revolute' or 'prismatic', got {joint!r}")
    name = data.get("name", "")
    if not isinstance(name, str):
        raise InputError(f"{source}: key 'name': expected a string, got {name!r}")
    if "max_effort" not in data:
        raise InputError(
            f"{source}: missing required key 'max_effort' "
            f"(the drive's effort cap, {si_unit('max_effort', joint)})"
        )
    try:
        values = {
            field: read_quantity(data[field], si_unit(field, joint), f"{source}: key {field!r}")
            for field in ENVELOPE_FIELDS
            if field in data
        }
    except InputError as exc:
        if "joint" in data or not _reads_as_prismatic(data):
            raise
        # a slide's numbers (N, m/s) under the default joint type: say what is missing
        raise InputError(f'{exc}; a prismatic joint\'s envelope says so: add joint = "prismatic"') from None
    try:
        return PerformanceEnvelope(joint=joint, name=name, **values)  # type: ignore[arg-type]
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None


def _reads_as_prismatic(data: Mapping[str, object]) -> bool:
    """Whether every envelope value of ``data`` reads in the prismatic units (N, m/s, ...)."""
    try:
        for field in ENVELOPE_FIELDS:
            if field in data:
                read_quantity(data[field], si_unit(field, "prismatic"), field)
    except InputError:
        return False
    return True


def _clip_quadrant(env: PerformanceEnvelope, v0: float, tau0: float) -> FloatArray:
    """First-quadrant region: the box [0, v0] x [0, tau0] clipped by both half-planes.

    Returns the vertices from the no-load point (v0, 0) to the stall point (0, tau0), along the
    outer boundary (the origin and the axes are dropped).
    """
    box = [(0.0, 0.0), (v0, 0.0), (v0, tau0), (0.0, tau0)]
    resistance, gradient = env.velocity_dependent_resistance, env.speed_effort_gradient
    # half-plane a*v + b*tau <= c
    planes = [(resistance, 1.0, env.max_effort)]
    if math.isfinite(env.max_actuator_velocity):
        planes.append((1.0, gradient, env.max_actuator_velocity))
    polygon = box
    for a, b, c in planes:
        polygon = _clip_polygon(polygon, a, b, c)
    points = np.array(polygon, dtype=np.float64).reshape(-1, 2)
    # walk from (v0, 0) counter-clockwise to (0, tau0): drop the origin
    outer = [tuple(p) for p in points if not (p[0] == 0.0 and p[1] == 0.0)]
    if not outer:  # the region is the origin alone
        return np.zeros((1, 2))
    start = min(range(len(outer)), key=lambda i: (outer[i][1], -outer[i][0]))
    ordered = outer[start:] + outer[:start]
    return _dedupe(np.array(ordered, dtype=np.float64).reshape(-1, 2))


def _clip_polygon(
    polygon: list[tuple[float, float]], a: float, b: float, c: float
) -> list[tuple[float, float]]:
    """Sutherland-Hodgman clip of a convex polygon by the half-plane ``a*v + b*tau <= c``."""
    result: list[tuple[float, float]] = []
    count = len(polygon)
    for i in range(count):
        p, q = polygon[i], polygon[(i + 1) % count]
        fp, fq = a * p[0] + b * p[1] - c, a * q[0] + b * q[1] - c
        if fp <= 0.0:
            result.append(p)
        if (fp < 0.0 < fq) or (fq < 0.0 < fp):
            t = fp / (fp - fq)
            result.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return result


def _dedupe(points: FloatArray) -> FloatArray:
    """Drop consecutive (and wrap-around) duplicate vertices.

    "Duplicate" is relative to the polygon's own extent per axis, so a region of any scale (1e-20
    or 1e20) keeps its corners.
    """
    if points.shape[0] < 2:
        return points
    extent = np.max(np.abs(points), axis=0)
    atol = 1e-15 * np.where(extent > 0.0, extent, 1.0)

    def same(a: FloatArray, b: FloatArray) -> bool:
        return bool(np.all(np.abs(a - b) <= atol + 1e-12 * np.abs(b)))

    keep = [0]
    for i in range(1, points.shape[0]):
        if not same(points[i], points[keep[-1]]):
            keep.append(i)
    if len(keep) > 1 and same(points[keep[-1]], points[keep[0]]):
        keep.pop()
    return points[keep]

"""Curve data of an envelope plot, computed without matplotlib (the compute half of compute/plot).

:func:`envelope_curve` returns an :class:`EnvelopeCurve`: the feasible polygon in all four
quadrants, the sampled effort limit, the two boundary lines with their equations and parameter
values, and the first-quadrant corner points. :func:`drive_envelope.plots.plot_envelope` draws it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.params.table import si_unit

__all__ = ["BoundaryLine", "CornerPoint", "EnvelopeCurve", "OperatingPoints", "envelope_curve"]

FloatArray = npt.NDArray[np.float64]
_MARGIN = 1.15  # plot window beyond the region's extreme points
_QUADRANT_SIGNS = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])


@dataclass(frozen=True, kw_only=True, slots=True)
class BoundaryLine:
    """One envelope equation drawn as a straight line in each quadrant."""

    name: str
    """``"eq1"`` (torque-speed line) or ``"eq2"`` (speed-torque line)."""
    equation: str
    """Symbolic form, e.g. ``|τ| = τ_max − k_τv·|v|``."""
    label: str
    """Equation with the parameter values and units, for a legend."""
    segments: FloatArray
    """Shape ``(4, 2, 2)``: per quadrant (I, II, III, IV) the two end points ``(velocity, effort)`` of
    the line inside the plot window [rad/s or m/s, N*m or N]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class CornerPoint:
    """A labelled vertex of the feasible region in the first quadrant (the others mirror it)."""

    name: str
    """``"stall"``, ``"corner"`` or ``"no-load"``."""
    velocity: float
    """Velocity of the point [rad/s or m/s]."""
    effort: float
    """Effort of the point [N*m or N]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class OperatingPoints:
    """Operating points to draw over an envelope: plain arrays of one length, one set per label.

    Build one from any source: a simulated trajectory, a bench log, a check's kept samples.
    """

    velocity: FloatArray
    """Joint velocity of each point [rad/s or m/s]."""
    effort: FloatArray
    """Total actuator effort of each point [N*m or N]."""
    time: FloatArray | None = None
    """Time of each point [s]; None colours the points by sample index instead."""
    label: str = ""
    """Legend label of the set, empty for ``points <n>``."""

    def __post_init__(self) -> None:
        velocity = np.asarray(self.velocity, dtype=np.float64)
        effort = np.asarray(self.effort, dtype=np.float64)
        time = None if self.time is None else np.asarray(self.time, dtype=np.float64)
        shapes = {a.shape for a in (velocity, effort, time) if a is not None}
        if len(shapes) != 1 or velocity.ndim != 1:
            given = ", ".join(
                f"{n} {a.shape}"
                for n, a in (("velocity", velocity), ("effort", effort), ("time", time))
                if a is not None
            )
            raise InputError(f"OperatingPoints: expected 1-D arrays of one length, got {given}")
        object.__setattr__(self, "velocity", velocity)
        object.__setattr__(self, "effort", effort)
        object.__setattr__(self, "time", time)

    def __len__(self) -> int:
        return int(self.velocity.shape[0])

    @property
    def clock(self) -> FloatArray:
        """``time``, or the sample index when there is no time [s or -]."""
        return self.time if self.time is not None else np.arange(len(self), dtype=np.float64)


@dataclass(frozen=True, kw_only=True, slots=True)
class EnvelopeCurve:
    """Everything an envelope plot shows, as arrays (joint side, SI)."""

    envelope: PerformanceEnvelope
    """The envelope drawn."""
    boundary: FloatArray
    """Feasible polygon ``(K, 2)`` of ``(velocity, effort)`` vertices, counter-clockwise from the
    positive no-load point (:meth:`PerformanceEnvelope.boundary`) [rad/s or m/s, N*m or N]."""
    velocity: FloatArray
    """Sampled velocities from ``-velocity_extent`` to ``+velocity_extent`` [rad/s or m/s]."""
    effort_limit: FloatArray
    """Largest feasible ``|effort|`` at each sampled velocity (0 outside the region) [N*m or N]."""
    lines: tuple[BoundaryLine, ...]
    """eq. 1 and, when ``max_actuator_velocity`` is finite, eq. 2."""
    corners: tuple[CornerPoint, ...]
    """Stall point, corner (when both lines bind) and no-load point, first quadrant."""
    velocity_extent: float
    """Half-width of the plot window in velocity [rad/s or m/s]."""
    effort_extent: float
    """Half-height of the plot window in effort [N*m or N]."""
    velocity_unit: str
    """SI unit of velocities (``rad/s`` or ``m/s``)."""
    effort_unit: str
    """SI unit of efforts (``N*m`` or ``N``)."""


def envelope_curve(
    envelope: PerformanceEnvelope,
    *,
    velocity_extent: float | None = None,
    effort_extent: float | None = None,
    samples: int = 401,
) -> EnvelopeCurve:
    """Compute the data of an envelope plot.

    Args:
        envelope: The envelope (joint side, SI).
        velocity_extent: Half-width of the window [rad/s or m/s]; default 1.15 x the no-load
            velocity, or 1.0 when the region is unbounded in velocity (then the polygon is cut there).
        effort_extent: Half-height of the window [N*m or N]; default 1.15 x the stall effort.
        samples: Number of sampled velocities, ``>= 2``.

    Raises:
        InputError: a non-positive extent or fewer than 2 samples.
    """
    if samples < 2:
        raise InputError(f"samples must be >= 2, got {samples!r}")
    no_load = envelope.no_load_velocity()
    v_ext = _extent(velocity_extent, no_load * _MARGIN if math.isfinite(no_load) else 1.0, "velocity_extent")
    e_ext = _extent(
        effort_extent, max(envelope.stall_effort(), envelope.max_effort) * _MARGIN, "effort_extent"
    )
    cut = min(v_ext, no_load)
    polygon = envelope.boundary(velocity_extent=cut) if cut > 0.0 else np.zeros((1, 2))
    velocity = np.linspace(-v_ext, v_ext, samples)
    return EnvelopeCurve(
        envelope=envelope,
        boundary=polygon,
        velocity=velocity,
        effort_limit=envelope.effort_limit(velocity),
        lines=_lines(envelope, v_ext, e_ext),
        corners=_corner_points(envelope),
        velocity_extent=v_ext,
        effort_extent=e_ext,
        velocity_unit=si_unit("max_actuator_velocity", envelope.joint),
        effort_unit=si_unit("max_effort", envelope.joint),
    )


def _extent(value: float | None, default: float, name: str) -> float:
    if value is None:
        return default if default > 0.0 else 1.0
    if not (math.isfinite(value) and value > 0.0):
        raise InputError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def _mirror(first_quadrant: FloatArray) -> FloatArray:
    """``(2, 2)`` end points in quadrant I -> ``(4, 2, 2)`` in quadrants I..IV."""
    return first_quadrant[None, :, :] * _QUADRANT_SIGNS[:, None, :] + 0.0  # + 0.0: no -0.0


def _fmt(value: float) -> str:
    return f"{value:.4g}"


def _lines(env: PerformanceEnvelope, v_ext: float, e_ext: float) -> tuple[BoundaryLine, ...]:
    sym_e = "τ" if env.joint == "revolute" else "F"
    units = {f: si_unit(f, env.joint) for f in ("max_effort", "max_actuator_velocity")}
    resistance, gradient = env.velocity_dependent_resistance, env.speed_effort_gradient
    v_end = v_ext if resistance == 0.0 else min(v_ext, env.max_effort / resistance)
    eq1 = np.array([[0.0, env.max_effort], [v_end, env.max_effort - resistance * v_end]])
    r_unit = si_unit("velocity_dependent_resistance", env.joint)
    lines = [
        BoundaryLine(
            name="eq1",
            equation=f"|{sym_e}| = {sym_e}_max − k_{sym_e}v·|v|",
            label=(
                f"eq. 1: |{sym_e}| = {_fmt(env.max_effort)} − {_fmt(resistance)}·|v|   "
                f"({sym_e}_max = {_fmt(env.max_effort)} {units['max_effort']}, "
                f"k_{sym_e}v = {_fmt(resistance)} {r_unit})"
            ),
            segments=_mirror(eq1),
        )
    ]
    if math.isfinite(env.max_actuator_velocity):
        vmax = env.max_actuator_velocity
        e_end = e_ext if gradient == 0.0 else min(e_ext, vmax / gradient)
        eq2 = np.array([[vmax, 0.0], [vmax - gradient * e_end, e_end]])
        g_unit = si_unit("speed_effort_gradient", env.joint)
        lines.append(
            BoundaryLine(
                name="eq2",
                equation=f"|v| = v_max − k_v{sym_e}·|{sym_e}|",
                label=(
                    f"eq. 2: |v| = {_fmt(vmax)} − {_fmt(gradient)}·|{sym_e}|   "
                    f"(v_max = {_fmt(vmax)} {units['max_actuator_velocity']}, "
                    f"k_v{sym_e} = {_fmt(gradient)} {g_unit})"
                ),
                segments=_mirror(eq2),
            )
        )
    return tuple(lines)


def _corner_points(env: PerformanceEnvelope) -> tuple[CornerPoint, ...]:
    """Stall, corner and no-load points; a region unbounded in velocity has only its stall point."""
    stall = CornerPoint(name="stall", velocity=0.0, effort=env.stall_effort())
    no_load = env.no_load_velocity()
    if not math.isfinite(no_load) or no_load == 0.0:
        return (stall,)
    corners = env.corners()
    points = [stall]
    if corners.corner is not None:
        points.append(CornerPoint(name="corner", velocity=corners.corner[0], effort=corners.corner[1]))
    points.append(CornerPoint(name="no-load", velocity=no_load, effort=0.0))
    return tuple(points)

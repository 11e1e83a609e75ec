"""Curve data of an envelope plot, computed without matplotlib (the compute half of compute/plot).

:func:`envelope_curve` returns an :class:`EnvelopeCurve`: the feasible polygon in all four
quadrants, the sampled effort limit, the two boundary lines with their equations and parameter
values, and the first-quadrant corner points. :func:`drive_envelope.plots.plot_envelope` draws it.

Every number drawn is finite and every window half-width lies in [:data:`MIN_EXTENT`,
:data:`MAX_EXTENT`], the range matplotlib draws to scale (it widens a smaller window on its own and
overflows on a larger one); anything else is an :class:`InputError`, never a figure that is silently
not to scale. Operating points with NaN or inf are refused, not dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.params.table import si_unit

MIN_EXTENT = 1e-280
"""Smallest half-width of a plot window [SI]: below it matplotlib widens the axis by itself."""
MAX_EXTENT = 1e300
"""Largest half-width of a plot window [SI]: beyond it matplotlib's transforms overflow."""

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
        given = {"velocity": self.velocity, "effort": self.effort, "time": self.time}
        arrays = {
            name: np.asarray(values, dtype=np.float64) for name, values in given.items() if values is not None
        }
        if len({values.shape for values in arrays.values()}) != 1 or arrays["velocity"].ndim != 1:
            shapes = ", ".join(f"{name} {values.shape}" for name, values in arrays.items())
            raise InputError(f"OperatingPoints: expected 1-D arrays of one length, got {shapes}")
        for name, values in arrays.items():
            if not np.isfinite(values).all():
                bad = int(np.flatnonzero(~np.isfinite(values))[0])
                raise InputError(
                    f"operating points {self.label or ''!r}: {name}[{bad}] is {float(values[bad])!r}; "
                    "expected finite numbers (remove such samples before plotting)"
                )
            object.__setattr__(self, name, values)

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
        InputError: an extent that is not a finite number > 0, a window outside [MIN_EXTENT,
            MAX_EXTENT] (e.g. ``max_effort = 1e308``), or fewer than 2 samples.
    """
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
        raise InputError(f"samples must be an integer >= 2, got {samples!r}")
    velocity_unit = si_unit("max_actuator_velocity", envelope.joint)
    effort_unit = si_unit("max_effort", envelope.joint)
    no_load = envelope.no_load_velocity()
    if effort_extent is None and math.isinf(envelope.stall_effort()):
        raise InputError(
            "cannot plot: the envelope is unbounded in effort (max_effort = inf and speed_effort_gradient "
            "= 0: no line limits the effort); give a finite max_effort, or pass effort_extent [N*m or N]"
        )
    with np.errstate(over="ignore"):  # 1.15 x a value near the float limit: inf, refused below
        default_v = no_load * _MARGIN if math.isfinite(no_load) else 1.0
        default_e = max(envelope.stall_effort(), _finite(envelope.max_effort)) * _MARGIN
    v_ext = _plottable(_extent(velocity_extent, default_v, "velocity_extent"), "velocity", velocity_unit)
    e_ext = _plottable(_extent(effort_extent, default_e, "effort_extent"), "effort", effort_unit)
    cut = min(v_ext, no_load)
    polygon = _region(envelope, cut, e_ext) if cut > 0.0 else np.zeros((1, 2))
    velocity = np.linspace(-v_ext, v_ext, samples)
    return EnvelopeCurve(
        envelope=envelope,
        boundary=polygon,
        velocity=velocity,
        effort_limit=effort_limit_at(envelope, velocity),
        lines=_lines(envelope, v_ext, e_ext),
        corners=_corner_points(envelope),
        velocity_extent=v_ext,
        effort_extent=e_ext,
        velocity_unit=velocity_unit,
        effort_unit=effort_unit,
    )


def effort_limit_at(envelope: PerformanceEnvelope, velocity: FloatArray) -> FloatArray:
    """The effort limit at ``velocity`` [N*m or N]; R*|v| beyond float range is a limit of 0, silently."""
    with np.errstate(over="ignore"):
        return envelope.effort_limit(velocity)


def _extent(value: float | None, default: float, name: str) -> float:
    if value is None:
        return default if default > 0.0 else 1.0
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not (math.isfinite(value) and value > 0.0)
    ):
        raise InputError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def _plottable(extent: float, axis: str, unit: str) -> float:
    """``extent`` when matplotlib can draw a window of that half-width to scale, else an error."""
    if MIN_EXTENT <= extent <= MAX_EXTENT:
        return extent
    large = not extent < MAX_EXTENT
    raise InputError(
        f"cannot plot: the {axis} axis would span +-{extent:.6g} {unit}, too {'large' if large else 'small'} "
        f"to draw to scale (expected a half-width {'at most' if large else 'at least'} "
        f"{MAX_EXTENT if large else MIN_EXTENT:g} {unit})"
    )


def _finite(value: float) -> float:
    """``value``, or 0 where it is infinite (a limit that is not there sets no scale)."""
    return value if math.isfinite(value) else 0.0


def _region(envelope: PerformanceEnvelope, cut: float, e_ext: float) -> FloatArray:
    """The feasible polygon, computed on unit scales so tiny or huge envelopes keep every corner."""
    # max_effort = inf with a speed line: the line bounds the effort (the stall) and scales it
    e_scale = max(envelope.stall_effort(), _finite(envelope.max_effort), 0.0) or e_ext
    with np.errstate(over="ignore", under="ignore"):
        unit = {
            "max_effort": envelope.max_effort / e_scale,
            "max_actuator_velocity": envelope.max_actuator_velocity / cut,
            "velocity_dependent_resistance": envelope.velocity_dependent_resistance * (cut / e_scale),
            "speed_effort_gradient": envelope.speed_effort_gradient * (e_scale / cut),
        }
    limits = ("max_effort", "max_actuator_velocity")  # inf: no limit, scaled or not
    if not all(math.isfinite(value) for key, value in unit.items() if key not in limits):
        return envelope.boundary(velocity_extent=cut)  # a scale beyond float range: draw it unscaled
    scaled = PerformanceEnvelope(**unit, joint=envelope.joint)  # type: ignore[arg-type]
    return scaled.boundary(velocity_extent=1.0) * np.array([cut, e_scale])


def _mirror(first_quadrant: FloatArray) -> FloatArray:
    """``(2, 2)`` end points in quadrant I -> ``(4, 2, 2)`` in quadrants I..IV."""
    return first_quadrant[None, :, :] * _QUADRANT_SIGNS[:, None, :] + 0.0  # + 0.0: no -0.0


def _clip(segment: FloatArray, v_ext: float, e_ext: float) -> FloatArray:
    """The part of a first-quadrant segment inside the window [0, v_ext] x [0, e_ext] (Liang-Barsky).

    A line far outside the window (``max_actuator_velocity = 1e308`` beside a small no-load speed)
    would overflow matplotlib's transforms; outside entirely, its end points are NaN (not drawn).
    """
    with np.errstate(over="ignore", invalid="ignore"):
        start, delta = segment[0], segment[1] - segment[0]
        low, high = 0.0, 1.0
        for axis, extent in ((0, v_ext), (1, e_ext)):
            for p, q in ((-delta[axis], start[axis]), (delta[axis], extent - start[axis])):
                if p == 0.0:
                    if q < 0.0:
                        return np.full((2, 2), np.nan)
                    continue
                t = q / p
                if not math.isfinite(t):
                    continue
                low, high = (max(low, t), high) if p < 0.0 else (low, min(high, t))
        if low > high:
            return np.full((2, 2), np.nan)
        clipped = np.array([start + low * delta, start + high * delta])
    return clipped if np.isfinite(clipped).all() else np.full((2, 2), np.nan)


def _fmt(value: float) -> str:
    return f"{value:.4g}"


def _lines(env: PerformanceEnvelope, v_ext: float, e_ext: float) -> tuple[BoundaryLine, ...]:
    sym_e = "τ" if env.joint == "revolute" else "F"
    units = {f: si_unit(f, env.joint) for f in ENVELOPE_FIELDS}
    resistance, gradient = env.velocity_dependent_resistance, env.speed_effort_gradient
    v_end = v_ext if resistance == 0.0 else min(v_ext, env.max_effort / resistance)
    eq1 = np.array([[0.0, env.max_effort], [v_end, env.max_effort - resistance * v_end]])
    lines = [  # (name, equation, label, first-quadrant segment)
        (
            "eq1",
            f"|{sym_e}| = {sym_e}_max − k_{sym_e}v·|v|",
            f"eq. 1: |{sym_e}| = {_fmt(env.max_effort)} − {_fmt(resistance)}·|v|   "
            f"({sym_e}_max = {_fmt(env.max_effort)} {units['max_effort']}, "
            f"k_{sym_e}v = {_fmt(resistance)} {units['velocity_dependent_resistance']})",
            eq1,
        )
    ]
    if math.isfinite(env.max_actuator_velocity):
        vmax = env.max_actuator_velocity
        e_end = e_ext if gradient == 0.0 else min(e_ext, vmax / gradient)
        lines.append((
            "eq2",
            f"|v| = v_max − k_v{sym_e}·|{sym_e}|",
            f"eq. 2: |v| = {_fmt(vmax)} − {_fmt(gradient)}·|{sym_e}|   "
            f"(v_max = {_fmt(vmax)} {units['max_actuator_velocity']}, "
            f"k_v{sym_e} = {_fmt(gradient)} {units['speed_effort_gradient']})",
            np.array([[vmax, 0.0], [vmax - gradient * e_end, e_end]]),
        ))  # fmt: skip
    return tuple(
        BoundaryLine(name=name, equation=equation, label=label, segments=_mirror(_clip(ends, v_ext, e_ext)))
        for name, equation, label, ends in lines
    )


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

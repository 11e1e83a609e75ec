"""velocityDependentResistance (spec section 2.2): a direct value, or the slope of an operating diagram.

The spec infers k_tau_v from the motor's operation diagram or performance curves: how the maximum
torque decreases with speed. ``[losses] operating_points`` are such a curve's points, motor side;
they are reflected to the joint (speed ``/ i_G``, torque ``x i_G * eta_G``, so the slope scales by
``i_G**2 * eta_G``) and fitted by ordinary least squares, ``k_tau_v = -slope``.

A curve that falls to zero effort within its own speed range is not a loss line: it is the
speed-torque line of eq. 2 (the back-EMF line of a motor at fixed voltage, which a DC motor's
published curve usually is), whose slope is speed_effort_gradient. Putting it into k_tau_v would
count the back-EMF drop twice, so such points give k_tau_v = 0 with a note saying why.

A curve with a knee (losses at low speed, then the back-EMF drop to no load) holds both lines: k_tau_v
is the slope of the part before the knee only. The knee is found by the same chooser ``fit
--from-curve`` uses (:mod:`drive_envelope._src.envelope.line_choice`), so both read one curve the
same way.
"""

from __future__ import annotations

import math

import numpy as np

from drive_envelope._src.datasheet.context import DeriveContext
from drive_envelope._src.envelope.line_choice import REACH, choose_model
from drive_envelope._src.errors import InputError

_ZERO_EFFORT = 0.01
"""A point below this fraction of the curve's largest effort counts as zero effort (a no-load point)."""
_REACH = REACH
"""A fitted line that reaches zero effort within this factor of the largest speed is a speed-torque line
(the factor ``fit --from-curve`` uses)."""
_ON_HULL = 1e-4
"""Digitized points lie on the curve: the chooser's band for points on the boundary."""


def resistance(ctx: DeriveContext) -> tuple[float, str]:
    """k_tau_v at the joint [N*m*s/rad or N*s/m] and its method.

    The method is ``direct``, ``fitted``, ``fitted_before_knee`` (the points bend into the
    speed-torque line: the slope before the knee), ``speed_torque_line`` (the operating points are
    the speed-torque line, so 0) or ``none``.
    """
    losses, output = ctx.sheet.losses, ctx.sheet.output
    direct = losses.velocity_dependent_resistance if losses else None
    if direct is None and output is not None:
        direct = output.velocity_dependent_resistance
    points = losses.operating_points if losses else None
    if direct is not None:
        if points is not None:
            ctx.notes.append(
                "losses.operating_points ignored: a direct velocity_dependent_resistance is given"
            )
        ctx.provenance["velocity_dependent_resistance"] = "datasheet"
        return direct, "direct"
    if points is None:
        ctx.notes.append(
            "no loss data: velocity_dependent_resistance = 0 (no speed-dependent losses modelled)"
        )
        ctx.provenance["velocity_dependent_resistance"] = "default"
        return 0.0, "none"
    return _fitted(ctx, points)


def _fitted(ctx: DeriveContext, points: tuple[tuple[float, float], ...]) -> tuple[float, str]:
    t = ctx.transmission
    speeds = np.array([t.motor_speed(p[0]) for p in points], dtype=np.float64)
    efforts = np.array([t.motor_effort(p[1]) for p in points], dtype=np.float64)
    distinct = np.unique(speeds).size
    if distinct < 2:
        raise InputError(
            f"{ctx.sheet.source}: key 'losses.operating_points': needs at least 2 points with distinct "
            f"speeds, got {len(points)} point(s) with {distinct} distinct speed(s)"
        )
    if not (np.all(np.isfinite(speeds)) and np.all(np.isfinite(efforts))):
        raise InputError(
            f"{ctx.sheet.source}: key 'losses.operating_points': reflected to the joint the points are "
            "out of range (check the gear ratio and the points' units)"
        )
    ctx.provenance["velocity_dependent_resistance"] = "derived"
    knee = _knee(speeds, efforts)
    if knee is not None:
        below = speeds <= knee
        value = _least_squares_resistance(speeds[below], efforts[below])
        ctx.notes.append(
            f"losses.operating_points bend at {knee:.6g} {ctx.units['joint_speed']}: above it they are the "
            "speed-torque line of eq. 2, so velocity_dependent_resistance is the slope of the "
            f"{int(np.count_nonzero(below))} points below it only"
        )
        return value, "fitted_before_knee"
    # ordinary least squares of effort on speed at the joint; the resistance is minus the slope
    centred = speeds - speeds.mean()
    slope = float(np.dot(centred, efforts - efforts.mean()) / np.dot(centred, centred))
    intercept = float(efforts.mean() - slope * speeds.mean())
    speed_unit = ctx.units["joint_speed"]
    top = float(np.max(efforts))
    # a point at zero effort is a no-load speed only on a falling curve (a rising one starts there)
    no_load = slope < 0.0 and bool(np.any((efforts <= _ZERO_EFFORT * top) & (speeds > 0.0)))
    reaches_zero = slope < 0.0 and -intercept / slope <= _REACH * float(np.max(speeds))
    if no_load or reaches_zero:
        zero_at = float(speeds[np.argmin(efforts)]) if no_load else -intercept / slope
        if slope < 0.0:
            # either slope may carry the line, both cannot be 0: it gives speed_effort_gradient
            ctx.curve_gradient = -1.0 / slope
        ctx.notes.append(
            f"losses.operating_points fall to zero effort at {zero_at:.6g} {speed_unit} (a no-load speed): "
            "they are the speed-torque line of eq. 2 (its slope gives speed_effort_gradient, "
            f"{-1.0 / slope if slope < 0.0 else 0.0:.6g} {ctx.units['joint_gradient']}, unless the datasheet "
            "gives one), not speed-dependent losses, so velocity_dependent_resistance = 0"
        )
        return 0.0, "speed_torque_line"
    if slope > 0.0:
        ctx.notes.append(
            f"operating points rise with speed (fitted slope {slope:.6g} at the joint): "
            "velocity_dependent_resistance = 0"
        )
        return 0.0, "fitted"
    value = -slope
    if not math.isfinite(value):
        raise InputError(
            f"{ctx.sheet.source}: key 'losses.operating_points': the fitted slope is out of range"
        )
    ctx.notes.append(
        f"velocity_dependent_resistance fitted from {len(points)} operating points (least squares at the "
        "joint: motor speeds / i_G, torques x i_G * eta_G)"
    )
    return value, "fitted"


def _knee(speeds: np.ndarray, efforts: np.ndarray) -> float | None:
    """The speed where a loss line turns into the speed-torque line, or None (one line).

    Points at one speed or two lines that the chooser does not support give None; so do knees with
    fewer than two points below them (no slope to take).
    """
    if speeds.size < 4:
        return None
    model, _, _ = choose_model(speeds, efforts, 0.0, {}, 2, _ON_HULL)
    if model.lines != "both" or np.count_nonzero(speeds <= model.split) < 2:
        return None
    return float(model.split)


def _least_squares_resistance(speeds: np.ndarray, efforts: np.ndarray) -> float:
    """Minus the least-squares slope of effort on speed, at least 0 [N*m*s/rad or N*s/m]."""
    centred = speeds - speeds.mean()
    denominator = float(np.dot(centred, centred))
    if denominator == 0.0:
        return 0.0
    slope = float(np.dot(centred, efforts - efforts.mean()) / denominator)
    return max(-slope, 0.0)

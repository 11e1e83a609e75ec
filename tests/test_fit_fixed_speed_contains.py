"""A containing fit with a held max_actuator_velocity contains every point it can (issue 24).

Found running docs/analysis.md: Magmotor's C 21-H-175 curve at 36 V (2628/2157/1903/0 rpm at
0/26/40/145 oz-in, the catalog entry ``magmotor-c21-h-175``) held at 3000 rpm, above every point,
left the stall point and the 1903 rpm point outside: eq. 2's slope was fitted to the samples past
the split only. By hand: eq. 2 from (3000 rpm, 0) must pass on or above the stall point (0 rpm,
145 oz-in), which bounds the slope the most: G = (3000 rpm) / (145 oz-in).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.analysis.api import fit_curve
from drive_envelope._src.analysis.fit import FitOptions
from drive_envelope._src.analysis.text import format_fit
from drive_envelope._src.envelope.line_model import fit_structure

RPM = math.pi / 30.0  # rad/s per rev/min
OZF_IN = 0.45359237 / 16.0 * 9.80665 * 0.0254  # N*m per ounce-force inch
CURVE = "speed [rpm],torque [oz-in]\n2628,0\n2157,26\n1903,40\n0,145\n"


def _contains(result: object, x: list[float], y: list[float]) -> bool:
    env = result.envelope  # type: ignore[attr-defined]
    return all(
        t <= env.max_effort - env.velocity_dependent_resistance * v + 1e-9
        and v <= env.max_actuator_velocity - env.speed_effort_gradient * t + 1e-9
        for v, t in zip(x, y, strict=True)
    )


@pytest.mark.parametrize("rpm", [3000.0, 5000.0])
def test_a_held_speed_above_every_point_contains_the_curve(tmp_path: Path, rpm: float) -> None:
    path = tmp_path / "diagram.csv"
    path.write_text(CURVE, encoding="utf-8")
    result = fit_curve(path, options=FitOptions(fixed={"max_actuator_velocity": rpm * RPM}))
    assert result.samples_outside == 0
    assert result.envelope.max_actuator_velocity == rpm * RPM
    assert result.envelope.speed_effort_gradient == pytest.approx(rpm * RPM / (145 * OZF_IN), rel=1e-3)
    x = [2628 * RPM, 2157 * RPM, 1903 * RPM, 0.0]
    y = [0.0, 26 * OZF_IN, 40 * OZF_IN, 145 * OZF_IN]
    assert _contains(result, x, y)


def test_a_held_max_effort_brings_the_loss_slope_down_for_samples_past_the_split() -> None:
    """Split at 3 rad/s, max_effort held at 10 N*m: the samples below give R = 0.1 (9.8 N*m at 2 rad/s),
    the sample (20 rad/s, 9.5 N*m) past the split lies above that eq. 1: R = 0.5 / 20 = 0.025 by hand."""
    x = np.array([0.0, 1.0, 2.0, 20.0, 30.0, 40.0])
    y = np.array([10.0, 9.9, 9.8, 9.5, 5.0, 0.0])
    model = fit_structure(x, y, 0.0, {"max_effort": 10.0}, "both", 3.0)
    assert model.effort == 10.0
    assert model.resistance == pytest.approx(0.025)
    free = fit_structure(x, y, 0.0, {}, "both", 3.0)  # free: the cap moves out instead
    assert free.resistance == pytest.approx(0.1) and free.effort == pytest.approx(11.5)


CUT_CURVE = "speed [rpm],torque [N*m]\n0,4\n1000,3.5\n2000,3.0\n3000,2.4\n3500,1.0\n3600,0\n"


def test_a_fixed_speed_that_cuts_points_off_is_said_not_every_point_contained(tmp_path: Path) -> None:
    """``fit`` output that contradicted itself (issue 23, item 12).

    The curve (0 rpm, 4 N*m) ... (3600 rpm, 0 N*m) held at max_actuator_velocity = 3000 rpm
    (314.159 rad/s) leaves the 3500 and 3600 rpm points outside: 2, counted by hand.
    """
    path = tmp_path / "diagram.csv"
    path.write_text(CUT_CURVE, encoding="utf-8")
    result = fit_curve(path, options=FitOptions(fixed={"max_actuator_velocity": 3000 * math.pi / 30}))
    assert result.samples_outside == 2
    text = format_fit(result)
    assert "every point contained" not in text
    assert "2 point(s) outside, cut off by the fixed max_actuator_velocity = 314.159 (SI)" in text
    free = fit_curve(path)
    assert free.samples_outside == 0 and "every point contained" in format_fit(free)

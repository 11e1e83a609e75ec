"""``fit`` output that contradicted itself (issue 23, item 12), each from its case.

The curve (0 rpm, 4 N*m) ... (3600 rpm, 0 N*m) held at max_actuator_velocity = 3000 rpm
(314.159 rad/s) leaves the 3500 and 3600 rpm points outside: 2, counted by hand.
"""

from __future__ import annotations

import math
from pathlib import Path

from drive_envelope._src.analysis.api import fit_curve
from drive_envelope._src.analysis.fit import FitOptions
from drive_envelope._src.analysis.fit_estimates import ParameterEstimate
from drive_envelope._src.analysis.text import format_fit

CURVE = "speed [rpm],torque [N*m]\n0,4\n1000,3.5\n2000,3.0\n3000,2.4\n3500,1.0\n3600,0\n"


def test_a_fixed_speed_that_cuts_points_off_is_said_not_every_point_contained(tmp_path: Path) -> None:
    path = tmp_path / "diagram.csv"
    path.write_text(CURVE, encoding="utf-8")
    result = fit_curve(path, options=FitOptions(fixed={"max_actuator_velocity": 3000 * math.pi / 30}))
    assert result.samples_outside == 2
    text = format_fit(result)
    assert "every point contained" not in text
    assert "2 point(s) outside, cut off by the fixed max_actuator_velocity = 314.159 (SI)" in text
    free = fit_curve(path)
    assert free.samples_outside == 0 and "every point contained" in format_fit(free)


def test_a_degenerate_interval_beside_a_std_is_explained() -> None:
    """A std of 0.00577 beside [37.6991, 37.6991]: most resamples agree exactly; say so."""
    from dataclasses import replace

    from drive_envelope._src.analysis.fit import fit_samples

    velocity = [0.0, 10.0, 20.0, 30.0, 37.6991]
    effort = [4.0, 3.0, 2.0, 1.0, 0.0]
    result = fit_samples(velocity, effort, options=FitOptions(bootstrap=0))
    estimate = ParameterEstimate(
        name="max_actuator_velocity", value=37.6991, unit="rad/s", status="fitted", std=0.00577,
        interval=(37.69911184, 37.69911185),  # equal to the 6 digits shown, not bit for bit
    )  # fmt: skip
    others = [p for p in result.parameters if p.name != "max_actuator_velocity"]
    text = format_fit(replace(result, parameters=(*others, estimate)))
    assert "37.6991 (>= 95 % of resamples; std from the rest)" in text
    assert "[37.6991, 37.6991]" not in text

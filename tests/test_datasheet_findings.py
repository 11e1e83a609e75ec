"""Datasheet slips that gave a silently wrong number (issue 23, items 7-10), each from its case.

Golden values by hand: 46 rpm = 46 * 2*pi/60 = 4.817108 rad/s; the XM430-W350's line from
(0 rpm, 4.1 N*m) to (46 rpm, 0 N*m) has Delta v / Delta tau = 4.817108 / 4.1 = 1.174904 (rad/s)/(N*m).
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.load import datasheet_from_mapping

RPM = 2.0 * math.pi / 60.0


def _derive(data: dict[str, Any]) -> Any:
    return derive(datasheet_from_mapping(data, source="sheet.toml"))


def test_operating_points_that_are_the_speed_torque_line_give_its_gradient() -> None:
    """Item 7: the contract case, XM430-W350 at 12 V. Either slope may carry the line, not neither."""
    result = _derive(
        {
            "name": "XM430-W350",
            "joint": "revolute",
            "controller": {"max_voltage": "12 V"},
            "output": {"max_effort": "4.1 N*m", "max_velocity": "46 rpm"},
            "losses": {"operating_points": [["0 rpm", "4.1 N*m"], ["46 rpm", "0 N*m"]]},
        }
    )
    env = result.envelope
    assert env.max_effort == 4.1
    assert env.max_actuator_velocity == pytest.approx(46 * RPM, rel=1e-12)
    assert env.velocity_dependent_resistance == 0.0
    assert env.speed_effort_gradient == pytest.approx(46 * RPM / 4.1, rel=1e-12)
    assert result.speed_effort_gradient_method == "operating_points"


def test_a_printed_gradient_still_wins_over_the_points() -> None:
    """The points' line is a fallback: a printed speed_effort_gradient is used as printed."""
    result = _derive(
        {
            "name": "x",
            "joint": "revolute",
            "output": {"max_effort": "4.1 N*m", "max_velocity": "46 rpm", "speed_effort_gradient": 0.5},
            "losses": {"operating_points": [["0 rpm", "4.1 N*m"], ["46 rpm", "0 N*m"]]},
        }
    )
    assert result.envelope.speed_effort_gradient == 0.5

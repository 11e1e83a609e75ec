"""The canonical envelope: a line that never binds moves to where it starts to bind, region unchanged.

Golden values by hand from eq. 1 and eq. 2: the issue's seed-0 envelope (0.633 N*m, 129.6 rad/s,
R 0.0392, G 325.5) has eq. 2 under eq. 1 at rest (129.6 / 325.5 = 0.398 N*m) but eq. 1 below eq. 2
beyond about 6.5 rad/s, so both lines bind and nothing moves; raising eq. 1 above eq. 2 everywhere
moves max_effort to the effort at rest; a steep eq. 1 reaching zero before eq. 2 moves eq. 2 to
eq. 1's zero-effort speed.
"""

from __future__ import annotations

import numpy as np
import pytest

from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.identify.canonical import binding_lines, canonical_envelope

NAMES = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")


def _values(effort: float, speed: float, resistance: float, gradient: float) -> dict[str, float]:
    return dict(zip(NAMES, (effort, speed, resistance, gradient), strict=True)) | {"duty_effort": effort}


def _same_region(a: dict[str, float], b: dict[str, float]) -> None:
    first = PerformanceEnvelope(**{name: a[name] for name in NAMES})
    second = PerformanceEnvelope(**{name: b[name] for name in NAMES})
    velocity = np.linspace(-200.0, 200.0, 4001)
    np.testing.assert_allclose(first.effort_limit(velocity), second.effort_limit(velocity), atol=1e-12)


def test_both_lines_bind_nothing_moves() -> None:
    values = _values(0.633, 129.6, 0.0392, 325.5)
    out, notes = canonical_envelope(values)
    assert out == values and notes == ()
    assert binding_lines(out) == {"eq1": True, "eq2": True}


def test_eq1_above_the_speed_line_moves_to_the_effort_at_rest() -> None:
    values = _values(0.633, 129.6, 0.002, 325.5)  # 0.633 - 0.002*129.6 = 0.374 > 0: eq. 1 never binds
    assert binding_lines(values)["eq1"] is False
    out, notes = canonical_envelope(values)
    assert out["max_effort"] == pytest.approx(129.6 / 325.5) and out["velocity_dependent_resistance"] == 0.0
    assert out["duty_effort"] == 0.633  # the servo loop keeps its gain
    assert "max_effort 0.633 N*m never binds" in notes[0] and "0.398157" in notes[0]
    assert binding_lines(out) == {"eq1": True, "eq2": True}
    _same_region(values, out)


def test_eq2_beyond_eq1s_zero_moves_to_it() -> None:
    values = _values(0.5, 40.0, 0.05, 10.0)  # eq. 1 reaches 0 at 10 rad/s; eq. 2 at rest 4 N*m, zero at 40
    assert binding_lines(values)["eq2"] is False
    out, notes = canonical_envelope(values)
    assert out["max_actuator_velocity"] == pytest.approx(10.0) and out["speed_effort_gradient"] == 0.0
    assert "max_actuator_velocity 40 never binds" in notes[0]
    _same_region(values, out)

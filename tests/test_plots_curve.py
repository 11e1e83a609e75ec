"""Curve data of envelope plots (no matplotlib): polygon, boundary lines, corners, window."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drive_envelope import InputError, PerformanceEnvelope
from drive_envelope.plots import envelope_curve

# both lines bind: eq. 1 from (0, 10) with slope -0.5, eq. 2 from (6, 0) with slope -0.2 (v per N*m)
ENV = PerformanceEnvelope(
    max_effort=10.0, max_actuator_velocity=6.0, velocity_dependent_resistance=0.5, speed_effort_gradient=0.2
)


def test_polygon_is_the_envelope_boundary() -> None:
    """The polygon is PerformanceEnvelope.boundary(), all four quadrants."""
    curve = envelope_curve(ENV)
    np.testing.assert_array_equal(curve.boundary, ENV.boundary())
    assert {tuple(np.sign(p)) for p in curve.boundary if p[0] != 0 and p[1] != 0} == {
        (1.0, 1.0),
        (-1.0, 1.0),
        (-1.0, -1.0),
        (1.0, -1.0),
    }


def test_corners_solve_both_equations_by_hand() -> None:
    """Corner: tau = 10 - 0.5 v and v = 6 - 0.2 tau give v = 4/0.9, tau = 10 - 2/0.9."""
    names = {c.name: (c.velocity, c.effort) for c in envelope_curve(ENV).corners}
    v = (6.0 - 0.2 * 10.0) / (1.0 - 0.2 * 0.5)
    assert names["corner"] == pytest.approx((v, 10.0 - 0.5 * v), rel=1e-12)
    assert names["stall"] == pytest.approx((0.0, 10.0))
    assert names["no-load"] == pytest.approx((6.0, 0.0))


def test_lines_carry_equations_with_values_and_mirror_into_four_quadrants() -> None:
    """eq. 1 and eq. 2 carry their values; each has one segment per quadrant, mirrored."""
    curve = envelope_curve(ENV, velocity_extent=8.0, effort_extent=12.0)
    eq1, eq2 = curve.lines
    assert "10" in eq1.label and "0.5" in eq1.label and "N*m*s/rad" in eq1.label
    assert "6" in eq2.label and "0.2" in eq2.label
    assert eq1.segments.shape == eq2.segments.shape == (4, 2, 2)
    # eq. 1 in quadrant I runs from the stall point to where it meets effort 0 (v = 20) or the window
    np.testing.assert_allclose(eq1.segments[0], [[0.0, 10.0], [8.0, 6.0]])
    np.testing.assert_allclose(eq1.segments[2], -eq1.segments[0])
    # eq. 2 in quadrant I from the no-load point up to the window top: v = 6 - 0.2*12
    np.testing.assert_allclose(eq2.segments[0], [[6.0, 0.0], [6.0 - 0.2 * 12.0, 12.0]])
    np.testing.assert_allclose(eq2.segments[1][:, 0], -eq2.segments[0][:, 0])


def test_effort_limit_samples_match_the_envelope() -> None:
    """effort_limit is the envelope's limit at each sampled velocity, symmetric in velocity."""
    curve = envelope_curve(ENV, samples=11)
    np.testing.assert_array_equal(curve.effort_limit, ENV.effort_limit(curve.velocity))
    np.testing.assert_allclose(curve.effort_limit, curve.effort_limit[::-1])
    assert curve.velocity[0] == -curve.velocity_extent
    assert curve.velocity_extent == pytest.approx(6.0 * 1.15)


def test_unbounded_plain_drive_is_cut_at_the_window() -> None:
    """A plain drive (max_effort only) has only eq. 1 and a stall point; the polygon is cut."""
    curve = envelope_curve(PerformanceEnvelope(max_effort=3.0), velocity_extent=2.0)
    assert [line.name for line in curve.lines] == ["eq1"]
    assert [c.name for c in curve.corners] == ["stall"]
    assert np.max(np.abs(curve.boundary[:, 0])) == 2.0
    assert math.isfinite(curve.effort_extent)


def test_prismatic_units() -> None:
    """A prismatic envelope is labelled in m/s and N."""
    curve = envelope_curve(
        PerformanceEnvelope(max_effort=200.0, max_actuator_velocity=0.5, joint="prismatic")
    )
    assert (curve.velocity_unit, curve.effort_unit) == ("m/s", "N")
    assert "F" in curve.lines[0].equation


@pytest.mark.parametrize("kwargs", [{"velocity_extent": 0.0}, {"effort_extent": -1.0}, {"samples": 1}])
def test_bad_arguments_raise_input_error(kwargs: dict[str, float]) -> None:
    """Non-positive extents and fewer than two samples are refused."""
    with pytest.raises(InputError):
        envelope_curve(ENV, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("scale", [1e-250, 1e-20, 1.0, 1e20, 1e250])
def test_region_keeps_every_corner_at_any_scale(scale: float) -> None:
    """Scale effort and speed by the same factor: the polygon scales with them, every vertex kept."""
    scaled = PerformanceEnvelope(
        max_effort=10.0 * scale,
        max_actuator_velocity=6.0 * scale,
        velocity_dependent_resistance=0.5,
        speed_effort_gradient=0.2,
    )
    np.testing.assert_allclose(envelope_curve(scaled).boundary, ENV.boundary() * scale, rtol=1e-12)


@pytest.mark.parametrize(
    ("envelope", "message"),
    [
        (PerformanceEnvelope(max_effort=1e308), "effort axis would span"),
        (PerformanceEnvelope(max_effort=1.0, max_actuator_velocity=1e305), "velocity axis would span"),
        (PerformanceEnvelope(max_effort=1e-300, max_actuator_velocity=1.0), "too small to draw to scale"),
    ],
)
def test_windows_matplotlib_cannot_draw_are_refused(envelope: PerformanceEnvelope, message: str) -> None:
    """Refuse a window matplotlib would overflow or silently widen, naming the axis."""
    with pytest.raises(InputError, match=message):
        envelope_curve(envelope)


def test_unlimited_max_effort_is_drawn_where_the_speed_line_bounds_it() -> None:
    """max_effort = inf with a speed line: the region is the line's diamond (stall 3/0.1 = 30 N*m)."""
    bounded = PerformanceEnvelope(max_effort=math.inf, max_actuator_velocity=3.0, speed_effort_gradient=0.1)
    curve = envelope_curve(bounded)  # it was refused: "the effort axis would span +-inf"
    np.testing.assert_allclose(curve.boundary, [[3.0, 0.0], [0.0, 30.0], [-3.0, 0.0], [0.0, -30.0]])
    with pytest.raises(InputError, match="unbounded in effort"):  # no line limits the effort
        envelope_curve(PerformanceEnvelope(max_effort=math.inf, max_actuator_velocity=3.0))


def test_boundary_lines_are_clipped_to_the_window() -> None:
    """End each line at the window; a line entirely outside it (v_max = 1.7e308) has NaN ends."""
    far = PerformanceEnvelope(
        max_effort=10.0,
        max_actuator_velocity=1.7e308,
        velocity_dependent_resistance=2.0,
        speed_effort_gradient=1e-9,
    )
    curve = envelope_curve(far)  # no-load speed 10 / 2 = 5 rad/s: the window is +-5.75
    eq1, eq2 = curve.lines
    np.testing.assert_allclose(eq1.segments[0], [[0.0, 10.0], [5.0, 0.0]])
    assert np.isnan(eq2.segments).all()
    partial = envelope_curve(ENV, velocity_extent=5.5, effort_extent=5.0)
    # eq. 2 runs from (6, 0) to (5, 5) (|v| = 6 - 0.2 |tau|); the window cuts it at v = 5.5
    np.testing.assert_allclose(partial.lines[1].segments[0], [[5.5, 2.5], [5.0, 5.0]])

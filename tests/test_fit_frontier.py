"""`fit` finds both lines from the frontier: interior samples, the knee anywhere, noise, few saturated
samples, one line only (issue 16, section 1).

Interior samples, the drive not saturated, are made by scaling a boundary point toward the origin by
a factor drawn from [0, 0.9] along a random ray: at least 10 % inside the boundary's radius. Expected
values are the envelopes the samples were drawn from (and, for the demo, the catalog derivation the
simulation ran on); the knee speed of the issue's example is computed by hand.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drive_envelope import PerformanceEnvelope
from drive_envelope.analysis import FitOptions, check_samples, fit_samples
from drive_envelope.datasheet import resolve_envelope
from drive_envelope.teststand import load_scenario, scenario_from_mapping, simulate

REPO = Path(__file__).resolve().parents[1]
FIELDS = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")
# the issue's sweep: max_effort 150 N*m, max_actuator_velocity 6 rad/s, R = 2, G = 0.01
ISSUE = PerformanceEnvelope(
    max_effort=150.0, max_actuator_velocity=6.0, velocity_dependent_resistance=2.0, speed_effort_gradient=0.01
)
# the knee: 150 - 2 v = (6 - v) / 0.01  ->  v = (6 - 0.01 * 150) / (1 - 0.01 * 2) = 4.5 / 0.98
ISSUE_KNEE = 4.5 / 0.98


def knee(env: PerformanceEnvelope) -> float:
    """Speed where eq. 1 meets eq. 2: E - R v = (V - v) / G  ->  v = (V - G E) / (1 - G R)."""
    e, r = env.max_effort, env.velocity_dependent_resistance
    v, g = env.max_actuator_velocity, env.speed_effort_gradient
    return (v - g * e) / (1.0 - g * r)


def interior(env: PerformanceEnvelope, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Samples at most 90 % of the boundary's radius from the origin, along random rays."""
    theta = rng.uniform(0.0, math.pi / 2.0, n)
    ux, uy = np.cos(theta), np.sin(theta)
    e, r = env.max_effort, env.velocity_dependent_resistance
    v, g = env.max_actuator_velocity, env.speed_effort_gradient
    radius = rng.uniform(0.0, 0.9, n) / np.maximum((uy + r * ux) / e, (ux + g * uy) / v)
    return radius * ux, radius * uy


def both_lines(
    env: PerformanceEnvelope, n1: int, n2: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """``n1`` saturated samples on eq. 1 (uniform in speed) and ``n2`` on eq. 2 (uniform in effort)."""
    corner = knee(env)
    v1 = rng.uniform(0.0, corner, n1)
    t2 = rng.uniform(0.0, float(env.effort_limit(corner)), n2)
    return np.concatenate([v1, env.velocity_at_effort(t2)]), np.concatenate([env.effort_limit(v1), t2])


def signed(v: np.ndarray, t: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Spread folded samples over all four quadrants."""
    direction, braking = rng.choice([-1.0, 1.0], v.size), rng.choice([-1.0, 1.0], v.size)
    return v * direction, t * direction * braking


def assert_close(env: PerformanceEnvelope, truth: PerformanceEnvelope, rel: float) -> None:
    """Caps relative to themselves; slopes by the effort (or speed) they change over the caps."""
    e, v = truth.max_effort, truth.max_actuator_velocity
    scale = {"max_effort": e, "max_actuator_velocity": v}
    scale |= {"velocity_dependent_resistance": e / v, "speed_effort_gradient": v / e}
    for field in FIELDS:
        assert abs(getattr(env, field) - getattr(truth, field)) <= rel * scale[field], field


def test_issue_sweep_with_interior_samples_finds_the_speed_line() -> None:
    """Recover max_actuator_velocity of the issue's sweep: eq. 2 binds from 4.59 to 6 rad/s only."""
    rng = np.random.default_rng(16)
    v = rng.uniform(0.0, ISSUE.no_load_velocity(), 400)  # uniform in speed: a quarter on eq. 2
    t = ISSUE.effort_limit(v)
    vi, ti = interior(ISSUE, 400, rng)
    result = fit_samples(np.concatenate([v, vi]), np.concatenate([t, ti]), FitOptions(bootstrap=0))
    assert_close(result.envelope, ISSUE, 1e-6)
    speed_line = result.lines[1]
    on_eq2 = np.flatnonzero(v > ISSUE_KNEE)
    assert 0.2 < on_eq2.size / v.size < 0.3
    assert speed_line.identified and set(speed_line.on_line.tolist()) == set(on_eq2.tolist())
    assert speed_line.velocity_range is not None and speed_line.velocity_range[0] > ISSUE_KNEE
    # fitting every sample (the mean gap over the interior) misses the speed line, as before
    everything = fit_samples(
        np.concatenate([v, vi]), np.concatenate([t, ti]), FitOptions(bootstrap=0, frontier_band=1.0)
    )
    assert everything.frontier_samples == 800 and math.isinf(everything.envelope.max_actuator_velocity)


def test_demo_swing_identifies_the_speed_limit_check_sees() -> None:
    """Fit the demo's own trajectory to the catalog envelope it was simulated with, to 1e-6."""
    trajectory = simulate(load_scenario(REPO / "examples/scenarios/actuator_swing.toml"), engine="reference")
    truth = resolve_envelope("tmotor-ak80-6")
    result = fit_samples(trajectory.velocity, trajectory.effort, FitOptions(bootstrap=0))
    assert_close(result.envelope, truth, 1e-6)
    check = check_samples(truth, trajectory.velocity, trajectory.effort)
    assert check.velocity is not None and check.velocity.samples_on_limit >= 10
    effort_line, speed_line = result.lines
    # the run accelerates at max_effort for 12 steps (samples 2-13), then rides eq. 2 (14-23)
    assert [tuple(r) for r in effort_line.to_dict()["samples"]] == [(2, 13)]
    assert [tuple(r) for r in speed_line.to_dict()["samples"]] == [(14, 23)]
    assert speed_line.driving == speed_line.on_line.size and speed_line.braking == 0
    assert result.samples_outside == 0


@settings(max_examples=25, deadline=None)
@given(
    corner=st.floats(0.1, 0.95),  # knees nearer standstill: see docs/analysis.md, limits
    drop=st.floats(0.0, 0.75),
    max_effort=st.floats(0.5, 500.0),
    speed=st.floats(0.5, 500.0),
    saturated=st.integers(8, 60),
    crowd=st.integers(0, 20),
    seed=st.integers(0, 2**16),
)
def test_knee_anywhere_is_recovered_exactly_among_interior_samples(
    corner: float, drop: float, max_effort: float, speed: float, saturated: int, crowd: int, seed: int
) -> None:
    """Recover every parameter to 1e-6 and name exactly the saturated samples, for any knee."""
    # eq. 1 loses `drop * corner` of max_effort by the corner (below `corner`: eq. 1 flatter than eq. 2)
    corner_speed, share = corner * speed, drop * corner
    truth = PerformanceEnvelope(
        max_effort=max_effort,
        max_actuator_velocity=speed,
        velocity_dependent_resistance=max_effort * share / corner_speed,
        speed_effort_gradient=(speed - corner_speed) / (max_effort * (1.0 - share)),
    )
    rng = np.random.default_rng(seed)
    v, t = both_lines(truth, saturated, saturated, rng)
    vi, ti = interior(truth, crowd * saturated, rng)
    sv, st_ = signed(np.concatenate([v, vi]), np.concatenate([t, ti]), rng)
    result = fit_samples(sv, st_, FitOptions(bootstrap=0))
    assert_close(result.envelope, truth, 1e-6)
    assert set(result.lines[0].on_line.tolist()) == set(range(saturated))
    assert set(result.lines[1].on_line.tolist()) == set(range(saturated, 2 * saturated))
    for line in result.lines:
        pairs = np.sign(sv[line.on_line]) * np.sign(st_[line.on_line])
        assert (line.driving, line.braking) == (int((pairs > 0).sum()), int((pairs < 0).sum()))


def test_few_saturated_samples_among_many_interior_ones() -> None:
    """Recover both lines from 10 samples on eq. 1 and 6 on eq. 2 among 800 interior samples."""
    truth = ISSUE
    rng = np.random.default_rng(3)
    v, t = both_lines(truth, 10, 6, rng)
    vi, ti = interior(truth, 800, rng)
    result = fit_samples(np.concatenate([v, vi]), np.concatenate([t, ti]), FitOptions(bootstrap=0))
    assert_close(result.envelope, truth, 1e-6)
    assert result.lines[1].on_line.size == 6 and result.frontier_samples < 30


@pytest.mark.parametrize(("noise", "rel"), [(0.005, 0.02), (0.01, 0.04)])
def test_noisy_frontier_among_interior_samples_gives_the_central_lines(noise: float, rel: float) -> None:
    """Stay within 2 % (0.5 % noise) or 4 % (1 % noise) at quantile 0.5, among 3x as many interior samples."""
    truth = PerformanceEnvelope(
        max_effort=40.0,
        max_actuator_velocity=30.0,
        velocity_dependent_resistance=0.4,
        speed_effort_gradient=0.25,
    )
    for seed in range(3):
        rng = np.random.default_rng(seed)
        v = rng.uniform(0.0, truth.no_load_velocity(), 400)
        t = truth.effort_limit(v)
        v, t = v + rng.normal(0.0, noise * 30.0, v.size), t + rng.normal(0.0, noise * 40.0, t.size)
        vi, ti = interior(truth, 1200, rng)
        result = fit_samples(
            np.concatenate([v, vi]), np.concatenate([t, ti]), FitOptions(outlier_quantile=0.5, bootstrap=0)
        )
        assert_close(result.envelope, truth, rel)
        assert result.frontier_band > 0.01  # widened from the 1 % start to the noise it saw


def test_one_line_only_is_not_turned_into_two() -> None:
    """Report max_actuator_velocity as inf for a sweep along eq. 1 only, with and without noise."""
    truth = PerformanceEnvelope(
        max_effort=40.0,
        max_actuator_velocity=30.0,
        velocity_dependent_resistance=0.4,
        speed_effort_gradient=0.25,
    )
    top = 0.7 * knee(truth)  # the sweep stops at 70 % of the knee speed
    for noise, quantile in ((0.0, 0.0), (0.005, 0.5), (0.005, 0.0)):
        rng = np.random.default_rng(7)
        v = rng.uniform(0.0, top, 300)
        t = truth.effort_limit(v) + rng.normal(0.0, noise * 40.0, v.size)
        v = v + rng.normal(0.0, noise * 30.0, v.size)
        vi = rng.uniform(0.0, 0.85 * top, 600)  # interior samples below the top speed reached
        ti = truth.effort_limit(vi) * rng.uniform(0.0, 0.9, vi.size)
        result = fit_samples(
            np.concatenate([v, vi]),
            np.concatenate([t, ti]),
            FitOptions(outlier_quantile=quantile, bootstrap=0),
        )
        speed = result.estimate("max_actuator_velocity")
        assert math.isinf(speed.value) and speed.status == "unidentified", (noise, quantile)
        assert not result.lines[1].identified
        assert result.envelope.max_effort == pytest.approx(40.0, rel=0.02 if noise else 1e-6)


def test_a_drive_leaving_saturation_is_no_speed_limit() -> None:
    """Keep eq. 2 unidentified when the swing's effort fades along a curve at its top speed."""
    # the demo's swing on an envelope whose speed line is far away (1000 rad/s): after accelerating at
    # 12 N*m the effort bends down along the drive's own curve, not along a line
    scenario = scenario_from_mapping(
        {
            "name": "swing without a speed limit",
            "joint": {"type": "revolute", "inertia": 0.04, "initial_position": -3.0},
            "drive": {
                "type": "force",
                "stiffness": 5.0,
                "damping": 0.2,
                "target_position": 3.0,
                "max_effort": 12.0,
            },
            "envelope": {"max_actuator_velocity": 1000.0},
            "load": {"external_effort": -0.5},
            "simulation": {
                "dt": 0.0083333333,
                "duration": 1.5,
                "solver": "tgs",
                "position_iterations": 4,
                "velocity_iterations": 1,
            },
        },
        source="test",
    )
    trajectory = simulate(scenario, engine="reference")
    result = fit_samples(trajectory.velocity, trajectory.effort, FitOptions(bootstrap=0))
    assert math.isinf(result.envelope.max_actuator_velocity)
    assert result.envelope.max_effort == pytest.approx(12.0, rel=1e-9)
    assert any("do not lie along one line" in note for note in result.notes)


def test_a_single_line_to_zero_effort_is_the_speed_line() -> None:
    """Read one line reaching zero effort among interior samples as eq. 2: R = 0, V and G from it."""
    truth = PerformanceEnvelope(
        max_effort=8.0,
        max_actuator_velocity=20.0,
        velocity_dependent_resistance=0.0,
        speed_effort_gradient=2.5,
    )  # stall 20 / 2.5 = 8 N*m: the speed line alone bounds the region
    rng = np.random.default_rng(11)
    t = rng.uniform(0.0, 8.0, 200)
    vi, ti = interior(truth, 400, rng)
    result = fit_samples(
        np.concatenate([truth.velocity_at_effort(t), vi]), np.concatenate([t, ti]), FitOptions(bootstrap=0)
    )
    assert_close(result.envelope, truth, 1e-6)
    assert result.estimate("velocity_dependent_resistance").status == "fitted"
    assert any("speed-torque line (eq. 2)" in note for note in result.notes)


# -- the hull and the report's evidence -------------------------------------------------------------


def test_hull_gauge_and_frontier_by_hand() -> None:
    """Draw the hull of a few points and measure radial gaps to it, as computed by hand."""
    from drive_envelope._src.analysis.fit_frontier import gauge, hull_chain, select_frontier

    # samples (1, 4), (3, 3), (4, 0.5), (2, 1): (2, 1) is inside; the hull runs from (0, 4) through
    # the other three samples to (4, 0)
    x, y = np.array([1.0, 3.0, 4.0, 2.0]), np.array([4.0, 3.0, 0.5, 1.0])
    hx, hy = hull_chain(np.array([1.0, 3.0, 4.0]), np.array([4.0, 3.0, 0.5]))
    assert hx.tolist() == [0.0, 1.0, 3.0, 4.0, 4.0] and hy.tolist() == [4.0, 4.0, 3.0, 0.5, 0.0]
    # the ray through (2, 1) meets the edge (3,3)-(4,0.5), the line 2.5 x + y = 10.5, at t * (2, 1)
    # with 6 t = 10.5: the sample is at 1 / 1.75 of the hull's radius
    assert gauge(hx, hy, np.array([2.0]), np.array([1.0]))[0] == pytest.approx(6.0 / 10.5)
    frontier = select_frontier(x, y, band=0.1)
    assert frontier.mask.tolist() == [True, True, True, False]
    assert frontier.gap[3] == pytest.approx(1.0 - 6.0 / 10.5)
    assert select_frontier(x, y, band=0.5).mask.all()


def test_clean_and_noisy_hulls_are_told_apart() -> None:
    """Call samples along hull edges clean and samples touching it only at vertices noisy."""
    from drive_envelope._src.analysis.fit_frontier import clean_hull

    rng = np.random.default_rng(0)
    v = rng.uniform(0.0, ISSUE.no_load_velocity(), 300)
    t = ISSUE.effort_limit(v)
    assert clean_hull(v, t)
    assert not clean_hull(v + rng.normal(0.0, 0.03, v.size), t + rng.normal(0.0, 0.75, v.size))


def test_sample_ranges_and_json_of_the_evidence() -> None:
    """Number the deciding samples from 1 in runs, and cap the runs JSON lists."""
    from drive_envelope._src.analysis.fit_evidence import MAX_JSON_RANGES, LineEvidence, sample_ranges

    assert sample_ranges(np.array([0, 1, 2, 7, 9, 10])) == [(1, 3), (8, 8), (10, 11)]
    assert sample_ranges(np.array([], dtype=np.intp)) == []
    scattered = LineEvidence(
        curve="velocity",
        identified=True,
        bounded=2 * MAX_JSON_RANGES + 2,
        on_line=np.arange(0, 2 * MAX_JSON_RANGES + 2, 2),
        driving=MAX_JSON_RANGES + 1,
        braking=0,
        velocity_range=(1.0, 2.0),
        effort_range=(0.0, 3.0),
    )
    data = scattered.to_dict()
    assert len(data["samples"]) == MAX_JSON_RANGES and data["samples_truncated"]
    assert data["on_line"] == MAX_JSON_RANGES + 1


def test_spikes_standing_clear_of_the_frontier_are_set_aside() -> None:
    """Leave 2 % spikes out of the hull with an allowance, and keep them in the fit's count."""
    rng = np.random.default_rng(3)
    v, t = both_lines(ISSUE, 500, 500, rng)
    v, t = v + rng.normal(0.0, 0.002 * 6.0, v.size), t + rng.normal(0.0, 0.002 * 150.0, t.size)
    spikes = rng.choice(v.size, 20, replace=False)
    t[spikes] *= 2.5
    result = fit_samples(v, t, FitOptions(outlier_quantile=0.06, bootstrap=0))
    assert 10 <= result.set_aside <= 20
    assert result.frontier_samples >= 950
    assert_close(result.envelope, ISSUE, 0.02)
    assert any("spikes" in note for note in result.notes)

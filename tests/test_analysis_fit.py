"""Fitting envelopes: recovery of known envelopes from synthetic sweeps, identifiability, curves.

Tolerances used (and stated in docs/analysis.md):
* noise-free samples on the boundary: every parameter to 1e-6 relative;
* noise of 0.5 % of the caps on both axes, 2000 samples, outlier quantile 0.5 (central line):
  every parameter within 2 %;
* same noise, outlier quantile 0 (containing envelope): every sample inside, caps biased outward by
  at most 5 %;
* 2 % gross outliers, outlier quantile 0.06 (the allowance applies per line, so it must cover
  the outliers' local share): every parameter within 5 %.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drive_envelope import PerformanceEnvelope, load_envelope, save_envelope
from drive_envelope._src.analysis.text import format_fit
from drive_envelope.analysis import FitOptions, ParameterEstimate, fit_curve, fit_log, fit_samples
from drive_envelope.errors import InputError

TRUTH = PerformanceEnvelope(
    max_effort=40.0, max_actuator_velocity=30.0, velocity_dependent_resistance=0.4, speed_effort_gradient=0.25
)
MECHANICAL = PerformanceEnvelope(
    max_effort=12.0, max_actuator_velocity=8.0, velocity_dependent_resistance=0.3
)
PRISMATIC = PerformanceEnvelope(
    max_effort=800.0,
    max_actuator_velocity=0.5,
    velocity_dependent_resistance=200.0,
    speed_effort_gradient=4e-4,
    joint="prismatic",
)
FIELDS = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")


def sweep(
    env: PerformanceEnvelope, n: int, *, noise: float = 0.0, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """A torque-speed sweep: for efforts uniform in [0, stall], the largest feasible speed, all quadrants."""
    rng = np.random.default_rng(seed)
    effort = rng.uniform(0.0, env.stall_effort(), n)
    velocity = env.velocity_at_effort(effort)
    velocity = velocity + rng.normal(0.0, noise * env.no_load_velocity(), n)
    effort = effort + rng.normal(0.0, noise * env.max_effort, n)
    return velocity * rng.choice([-1.0, 1.0], n), effort * rng.choice([-1.0, 1.0], n)


def assert_close(result_env: PerformanceEnvelope, truth: PerformanceEnvelope, rel: float) -> None:
    for field in FIELDS:
        expected = getattr(truth, field)
        scale = abs(expected) if expected else 1e-3  # a zero slope is checked in absolute terms
        assert abs(getattr(result_env, field) - expected) <= rel * scale, field


@pytest.mark.parametrize(
    "truth", [TRUTH, MECHANICAL, PRISMATIC], ids=["both-lines", "vertical-eq2", "prismatic"]
)
def test_recovers_noise_free_envelopes_exactly(truth: PerformanceEnvelope) -> None:
    """Recover every parameter to 1e-6 from noise-free samples on the boundary."""
    velocity, effort = sweep(truth, 400)
    result = fit_samples(velocity, effort, FitOptions(joint=truth.joint, bootstrap=0))
    assert_close(result.envelope, truth, 1e-6)
    assert result.samples_outside == 0
    assert result.envelope.joint == truth.joint


def test_recovers_noisy_sweep_with_the_central_line() -> None:
    """Recover every parameter within 2 % from a noisy sweep with outlier quantile 0.5."""
    velocity, effort = sweep(TRUTH, 2000, noise=0.005, seed=1)
    result = fit_samples(velocity, effort, FitOptions(outlier_quantile=0.5, bootstrap=30))
    assert_close(result.envelope, TRUTH, 0.02)
    for estimate in result.parameters:
        assert estimate.status == "fitted" and estimate.std is not None and estimate.interval is not None
        assert 0.0 < estimate.std < 0.05 * estimate.value
    assert 0.3 < result.samples_outside / result.samples < 0.7


def test_containing_fit_holds_every_sample_with_small_outward_bias() -> None:
    """Contain every noisy sample with outlier quantile 0, caps at most 5 % above the truth."""
    velocity, effort = sweep(TRUTH, 2000, noise=0.005, seed=2)
    env = fit_samples(velocity, effort, FitOptions(bootstrap=0)).envelope
    assert env.contains(velocity, effort, atol=1e-9).all()
    for field in ("max_effort", "max_actuator_velocity"):
        assert 1.0 <= getattr(env, field) / getattr(TRUTH, field) <= 1.05


def test_outlier_quantile_ignores_gross_outliers() -> None:
    """Stay within 5 % when 2 % of the samples are wild, given outlier quantile 0.06."""
    velocity, effort = sweep(TRUTH, 2000, noise=0.002, seed=3)
    spikes = np.random.default_rng(4).choice(velocity.size, 40, replace=False)
    effort[spikes] *= 3.0
    assert fit_samples(velocity, effort, FitOptions(bootstrap=0)).envelope.max_effort > 1.5 * TRUTH.max_effort
    robust = fit_samples(velocity, effort, FitOptions(outlier_quantile=0.06, bootstrap=0))
    assert_close(robust.envelope, TRUTH, 0.05)


def test_speed_limit_never_reached_is_reported_unidentified() -> None:
    """Report max_actuator_velocity as inf, with a note, when the sweep stops below the speed limit."""
    rng = np.random.default_rng(5)
    velocity = rng.uniform(0.0, 15.0, 500)  # eq. 1 binds up to 22.2 rad/s: eq. 2 is never reached
    effort = TRUTH.effort_limit(velocity)
    result = fit_samples(velocity, effort, FitOptions(bootstrap=20))
    speed = result.estimate("max_actuator_velocity")
    assert math.isinf(speed.value) and speed.status == "unidentified" and speed.std is None
    assert result.estimate("speed_effort_gradient").status == "unidentified"
    assert any("max_actuator_velocity not identified" in note for note in result.notes)
    assert result.envelope.max_effort == pytest.approx(40.0, rel=1e-6)
    assert result.envelope.velocity_dependent_resistance == pytest.approx(0.4, rel=1e-6)
    assert result.to_dict()["max_actuator_velocity"] == "inf"


def test_fixed_parameters_are_held() -> None:
    """Hold fixed parameters at their values and fit the others around them."""
    velocity, effort = sweep(TRUTH, 400)
    result = fit_samples(velocity, effort, FitOptions(fixed={"max_effort": 40.0}, bootstrap=0))
    assert result.estimate("max_effort").status == "fixed"
    assert_close(result.envelope, TRUTH, 1e-6)
    single = fit_samples(velocity, effort, FitOptions(fixed={"max_actuator_velocity": math.inf}, bootstrap=0))
    assert math.isinf(single.envelope.max_actuator_velocity)
    assert single.envelope.contains(velocity, effort, atol=1e-9).all()


def test_bootstrap_is_reproducible_by_seed() -> None:
    """Give identical uncertainties for the same seed and different ones for another seed."""
    velocity, effort = sweep(TRUTH, 300, noise=0.005, seed=6)
    first, second, other = (
        fit_samples(velocity, effort, FitOptions(bootstrap=15, seed=s)).to_dict()["uncertainty"]
        for s in (1, 1, 2)
    )
    assert first == second and first != other


def test_fit_options_are_validated() -> None:
    """Refuse an outlier quantile above 0.5, an unknown fixed name and too few samples."""
    with pytest.raises(InputError, match="outlier-quantile"):
        FitOptions(outlier_quantile=0.7)
    with pytest.raises(InputError, match="unknown parameter 'max_torque'"):
        FitOptions(fixed={"max_torque": 1.0})
    with pytest.raises(InputError, match="at least 3 samples"):
        fit_samples([1.0], [1.0])
    with pytest.raises(InputError, match="seed: expected an integer >= 0, got -1"):
        FitOptions(seed=-1)
    with pytest.raises(InputError, match=r"bootstrap: expected an integer in 0\.\.10000"):
        FitOptions(bootstrap=10**8)
    with pytest.raises(InputError, match="fix: max_effort must be a number"):
        FitOptions(fixed={"max_effort": "12"})  # type: ignore[dict-item]


@pytest.mark.parametrize("options", [{"outlier_quantile": 0.5}, {}, 0.5])
def test_fit_samples_names_options_that_are_not_fit_options(options: object) -> None:
    """A dict was AttributeError at its first field; an empty one silently meant the defaults."""
    with pytest.raises(InputError, match=r"^fit_samples: argument 'options': expected a FitOptions") as info:
        fit_samples([1.0, 2.0, 3.0], [3.0, 2.0, 1.0], options)  # type: ignore[arg-type]
    assert "\n" not in str(info.value) and type(options).__name__ in str(info.value)


def test_samples_beyond_the_fit_range_are_refused_not_mis_fitted() -> None:
    """Refuse samples above 1e100 (the fit's sums would overflow into a wrong slope) and NaN."""
    speed = np.linspace(0.0, 30.0, 50)
    with pytest.raises(InputError, match=r"\|velocity\| up to 3e\+307 \[SI\]; expected at most 1e\+100"):
        fit_samples(speed * 1e306, (40.0 - 0.4 * speed) * 1e306)
    scaled = fit_samples(speed * 1e90, (40.0 - 0.4 * speed) * 1e90, FitOptions(bootstrap=0))
    assert scaled.estimate("velocity_dependent_resistance").value == pytest.approx(0.4, rel=1e-6)
    with pytest.raises(InputError, match=r"effort sample 2 is nan"):
        fit_samples([1.0, 2.0, 3.0], [1.0, 2.0, float("nan")])


def test_fit_log_errors_name_the_log_and_the_joint(tmp_path: Path) -> None:
    """Prefix errors about the samples with the log (and the selected joint)."""
    log = tmp_path / "sweep.csv"
    log.write_text("joint,velocity,effort\na,1,2\na,2,1\nb,0,3\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"sweep\.csv: joint 'b': 1 sample\(s\); expected at least 3"):
        fit_log(log, select="b")


def test_fits_a_digitized_datasheet_curve_in_vendor_units(tmp_path: Path) -> None:
    """Fit points digitized in rpm and mNm to the envelope they were drawn from."""
    env = PerformanceEnvelope(
        max_effort=0.8,
        max_actuator_velocity=500.0,
        velocity_dependent_resistance=2e-4,
        speed_effort_gradient=400.0,
    )
    speeds = np.linspace(0.0, env.no_load_velocity(), 12)
    torque = env.effort_limit(speeds)
    rpm = speeds * 60.0 / (2.0 * math.pi)
    lines = ["# digitized from the operating diagram", "speed [rpm],torque (mNm)"]
    lines += [f"{s!r},{t * 1000.0!r}" for s, t in zip(rpm.tolist(), torque.tolist(), strict=True)]
    points = tmp_path / "diagram.csv"
    points.write_text("\n".join(lines) + "\n", encoding="utf-8")
    result = fit_curve(points)
    assert_close(result.envelope, env, 1e-6)
    assert result.envelope.name == "diagram"
    assert all(p.std is None for p in result.parameters)


def test_fit_log_selects_a_joint_and_round_trips_the_envelope_file(tmp_path: Path) -> None:
    """Fit one joint of a long-format CSV, then save and reload the envelope unchanged."""
    velocity, effort = sweep(TRUTH, 200)
    rows = [
        f"{i * 0.01!r},{'knee' if i % 2 else 'hip'},{v!r},{e!r}"
        for i, (v, e) in enumerate(zip(velocity.tolist(), effort.tolist(), strict=True))
    ]
    log = tmp_path / "sweep.csv"
    log.write_text("time,joint,velocity,effort\n" + "\n".join(rows) + "\n", encoding="utf-8")
    with pytest.raises(InputError, match="pick one with --select"):
        fit_log(log)
    result = fit_log(log, select="knee", options=FitOptions(bootstrap=0, min_segment_samples=3))
    assert result.envelope.name == "knee" and result.samples == 100
    out = tmp_path / "knee.toml"
    save_envelope(result.envelope, out)
    assert load_envelope(out) == result.envelope


@settings(max_examples=15, deadline=None)
@given(
    max_effort=st.floats(0.5, 100.0),
    speed=st.floats(1.0, 100.0),
    resistance_share=st.floats(0.0, 0.4),
    corner_share=st.floats(0.2, 0.9),
    seed=st.integers(0, 2**16),
)
def test_containing_fit_holds_every_sample_of_any_envelope(
    max_effort: float, speed: float, resistance_share: float, corner_share: float, seed: int
) -> None:
    """Contain every noisy sample, for any envelope shape, with outlier quantile 0."""
    # eq. 1 loses resistance_share of the effort by the corner speed; eq. 2 ends at `speed`
    corner_speed = corner_share * speed
    corner_effort = max_effort * (1.0 - resistance_share)
    truth = PerformanceEnvelope(
        max_effort=max_effort,
        max_actuator_velocity=speed,
        velocity_dependent_resistance=max_effort * resistance_share / corner_speed,
        speed_effort_gradient=(speed - corner_speed) / corner_effort,
    )
    velocity, effort = sweep(truth, 150, noise=0.01, seed=seed)
    result = fit_samples(velocity, effort, FitOptions(bootstrap=0))
    assert result.samples_outside == 0
    assert result.envelope.contains(velocity, effort, atol=1e-9 * max(max_effort, speed)).all()


def test_frontier_band_is_validated() -> None:
    """Refuse a frontier band outside (0, 1], naming it; accept 1 (every sample) and None (automatic)."""
    for bad in (0.0, -0.1, 1.5, float("nan"), True, "0.1"):
        with pytest.raises(InputError, match=r"frontier-band: expected a fraction in \(0, 1\]"):
            FitOptions(frontier_band=bad)  # type: ignore[arg-type]
    velocity, effort = sweep(TRUTH, 200)
    every = fit_samples(velocity, effort, FitOptions(frontier_band=1.0, bootstrap=0))
    assert every.frontier_samples == 200 and every.frontier_band == 1.0
    assert_close(every.envelope, TRUTH, 1e-6)


def test_json_reports_the_frontier_and_each_lines_samples() -> None:
    """Give the frontier's size and band, and per line its on-line samples by quadrant pair."""
    velocity, effort = sweep(TRUTH, 300, seed=9)
    data = fit_samples(velocity, effort, FitOptions(bootstrap=0)).to_dict()
    assert data["frontier"] == {"samples": 300, "band": 1e-4, "set_aside": 0}
    lines = data["lines"]
    assert lines["effort"]["on_line"] + lines["velocity"]["on_line"] == 300
    for line in lines.values():
        assert line["identified"] and line["driving"] + line["braking"] == line["on_line"]
        assert sum(last - first + 1 for first, last in line["samples"]) == line["on_line"]


def test_fixed_parameters_hold_on_a_speed_torque_line() -> None:
    """Keep a fixed max_effort on a line to zero effort; a fixed R keeps the line as eq. 1."""
    line = PerformanceEnvelope(max_effort=5.0, max_actuator_velocity=10.0, speed_effort_gradient=2.0)
    effort = np.linspace(0.0, 5.0, 50)
    velocity = line.velocity_at_effort(effort)  # from (0, 5 N*m) to (10 rad/s, 0): one line
    held = fit_samples(velocity, effort, FitOptions(fixed={"max_effort": 6.0}, bootstrap=0)).envelope
    assert held.max_effort == 6.0 and held.velocity_dependent_resistance == 0.0
    assert held.max_actuator_velocity == pytest.approx(10.0, rel=1e-9)
    assert held.speed_effort_gradient == pytest.approx(2.0, rel=1e-6)
    loss = fit_samples(
        velocity, effort, FitOptions(fixed={"velocity_dependent_resistance": 0.5}, bootstrap=0)
    ).envelope
    assert math.isinf(loss.max_actuator_velocity) and loss.max_effort == pytest.approx(5.0, rel=1e-9)


def test_a_degenerate_interval_beside_a_std_is_explained() -> None:
    """A std of 0.00577 beside [37.6991, 37.6991]: most resamples agree exactly; say so.

    Issue 23, item 12.
    """
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

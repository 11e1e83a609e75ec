"""The implicit clamp (PhysX semantics) and the implicit PD drive: closed forms and properties.

Closed forms solve the two curves at the post-step velocity ``v1 = v + r*dt*(e - e0)`` by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import drive_envelope as de
from drive_envelope import (
    PerformanceEnvelope,
    clamp_drive_impulse,
    clamp_effort_implicit,
    implicit_drive_effort,
)
from drive_envelope.errors import InputError

DT = 0.01
R_UNIT = 2.0  # response of a 0.5 kg*m^2 inertia


def test_first_step_from_rest_with_resistance() -> None:
    """Give max_effort / (1 + r*R*dt) on the first step from rest."""
    env = PerformanceEnvelope(max_effort=10.0, velocity_dependent_resistance=2.0)
    result = clamp_effort_implicit(env, 1e3, 0.0, R_UNIT, DT)
    assert result == pytest.approx(10.0 / (1.0 + R_UNIT * 2.0 * DT), rel=1e-14)


def test_velocity_settles_exactly_on_max_actuator_velocity() -> None:
    """Stop exactly at max_actuator_velocity when eq. 2 binds with G = 0."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=3.0)
    effort = clamp_effort_implicit(env, 100.0, 2.99, R_UNIT, DT)
    assert effort == pytest.approx(0.5, rel=1e-12)  # (3 - 2.99) / (r*dt)
    assert 2.99 + R_UNIT * DT * effort == pytest.approx(3.0, rel=1e-15)


def test_gradient_line_at_post_step_velocity() -> None:
    """Solve v0 + r*dt*e = v_max - G*e for the effort on the speed-effort line."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=3.0, speed_effort_gradient=0.1)
    # 2 + 0.02 e = 3 - 0.1 e  ->  e = 1 / 0.12
    assert clamp_effort_implicit(env, 100.0, 2.0, R_UNIT, DT) == pytest.approx(1.0 / 0.12, rel=1e-12)


def test_overspeed_releases_the_drive() -> None:
    """Return 0 (the drive lets go) when even full braking cannot reach the envelope."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=3.0)
    # full braking: 5 - 0.02*10 = 4.8 > 3
    assert clamp_effort_implicit(env, -100.0, 5.0, R_UNIT, DT) == 0.0


def test_braking_back_into_the_envelope() -> None:
    """Brake with full effort when one step of braking gets back inside."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=3.0)
    assert clamp_effort_implicit(env, -100.0, 3.1, R_UNIT, DT) == pytest.approx(-10.0)


def test_braking_effort_shrinks_with_speed() -> None:
    """Shrink braking effort with speed like driving effort (the symmetric curve)."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=3.0, velocity_dependent_resistance=1.0)
    # |e| = 10 - (3.1 - 0.02|e|)  ->  0.98|e| = 6.9
    assert clamp_effort_implicit(env, -100.0, 3.1, R_UNIT, DT) == pytest.approx(-6.9 / 0.98, rel=1e-12)


def test_applied_effort_counts_in_the_total() -> None:
    """Limit the TOTAL (already applied + drive) effort to max_effort."""
    env = PerformanceEnvelope(max_effort=10.0)
    v_after_applied = 0.0 + R_UNIT * DT * 4.0
    result = clamp_effort_implicit(env, 15.0, v_after_applied, R_UNIT, DT, applied_effort=4.0)
    assert result == pytest.approx(10.0)


def test_dt_one_equals_impulse_level() -> None:
    """Match the impulse-level function exactly when dt = 1."""
    env = PerformanceEnvelope(
        max_effort=7.0,
        max_actuator_velocity=4.0,
        velocity_dependent_resistance=0.3,
        speed_effort_gradient=0.2,
    )
    rng = np.random.default_rng(1)
    v, req, r, e0 = (
        rng.normal(0, 5, 500),
        rng.normal(0, 20, 500),
        rng.uniform(0.1, 3, 500),
        rng.normal(0, 2, 500),
    )
    effort = clamp_effort_implicit(env, req, v, r, 1.0, applied_effort=e0)
    impulse = clamp_drive_impulse(v, e0, req, r, 4.0, 7.0, 0.2, 0.3)
    np.testing.assert_array_equal(effort, impulse)


def test_zero_request_gives_zero() -> None:
    """Return exactly 0 for a zero request, in or out of the envelope."""
    env = PerformanceEnvelope(max_effort=1.0, max_actuator_velocity=1.0)
    assert clamp_effort_implicit(env, 0.0, np.array([0.0, 0.5, 5.0, -5.0]), 1.0, DT).tolist() == [0.0] * 4


def test_infinite_max_velocity_is_no_speed_limit() -> None:
    """Apply only max_effort when max_actuator_velocity is inf."""
    env = PerformanceEnvelope(max_effort=3.0, max_actuator_velocity=math.inf)
    assert clamp_effort_implicit(env, [5.0, -5.0, 1.0], 1e6, 1.0, DT).tolist() == [3.0, -3.0, 1.0]


def test_float32_mode_matches_float64_on_benign_inputs() -> None:
    """Agree within float32 precision between the two arithmetic modes."""
    rng = np.random.default_rng(2)
    args = [
        rng.normal(0, 3, 1000),
        rng.normal(0, 0.05, 1000),
        rng.normal(0, 0.2, 1000),
        rng.uniform(0.5, 5, 1000),
    ]
    f64 = clamp_drive_impulse(*args, 3.0, 0.1, 5.0, 0.02)
    f32 = clamp_drive_impulse(*args, 3.0, 0.1, 5.0, 0.02, dtype=np.float32)
    assert f32.dtype == np.float32
    np.testing.assert_allclose(f32, f64, rtol=1e-5, atol=1e-6)


# -- properties -------------------------------------------------------------------------------

_positive = st.floats(min_value=1e-3, max_value=1e3, allow_nan=False)
_nonneg = st.one_of(st.just(0.0), _positive)
_signed = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False)


def _feasible(env: PerformanceEnvelope, velocity: float, effort: float) -> bool:
    scale = 1e-9 * (1.0 + abs(velocity) + abs(effort) + env.max_effort)
    return bool(env.contains(velocity, effort, atol=scale))


@settings(max_examples=400, deadline=None)
@given(
    max_effort=_nonneg,
    max_velocity=st.one_of(st.just(math.inf), _nonneg),
    resistance=_nonneg,
    gradient=_nonneg,
    velocity=_signed,
    request=_signed,
    applied=st.floats(min_value=-50, max_value=50),
    inertia=_positive,
    dt=st.sampled_from([1e-3, 1.0 / 120.0, 0.02]),
)
def test_implicit_clamp_properties(
    max_effort: float,
    max_velocity: float,
    resistance: float,
    gradient: float,
    velocity: float,
    request: float,
    applied: float,
    inertia: float,
    dt: float,
) -> None:
    """Never NaN, never above the request, never flipped; feasible at v1 unless zero itself is not."""
    env = PerformanceEnvelope(
        max_effort=max_effort,
        max_actuator_velocity=max_velocity,
        velocity_dependent_resistance=resistance,
        speed_effort_gradient=gradient,
    )
    response = 1.0 / inertia
    # PhysX ignores a curve whose denominator is within 2^-23 of zero: stay clear of that guard here
    # (the PhysX vectors test it), i.e. response*dt must not equal G or 1/R to float32 precision.
    assume(
        abs(response - gradient / dt) > 1e-6
        and (resistance == 0 or abs(response - 1 / (resistance * dt)) > 1e-6)
    )
    result = float(clamp_effort_implicit(env, request, velocity, response, dt, applied_effort=applied))
    assert not math.isnan(result)
    assert abs(result) <= abs(request)
    assert result * request >= 0.0
    v1 = velocity + response * dt * (result - applied)
    v_zero = velocity - response * dt * applied
    if not _feasible(env, v1, result):
        assert result == 0.0
        assert not _feasible(env, v_zero, 0.0)


@settings(max_examples=300, deadline=None)
@given(
    velocity=st.floats(min_value=-10, max_value=10),
    request=st.floats(min_value=-100, max_value=100, allow_subnormal=False),
    inertia=st.floats(min_value=0.05, max_value=5),
)
def test_implicit_clamp_is_the_largest_feasible_effort(
    velocity: float, request: float, inertia: float
) -> None:
    """Make any larger effort toward the request infeasible at its own post-step velocity."""
    env = PerformanceEnvelope(
        max_effort=10.0,
        max_actuator_velocity=5.0,
        velocity_dependent_resistance=0.7,
        speed_effort_gradient=0.2,
    )
    response = 1.0 / inertia
    result = float(clamp_effort_implicit(env, request, velocity, response, DT))
    if math.isclose(result, request, rel_tol=1e-12) or result == 0.0:
        return
    bigger = result + 1e-6 * math.copysign(1.0, request)
    assert not env.contains(velocity + response * DT * bigger, bigger)


@settings(max_examples=200, deadline=None)
@given(
    stiffness=st.floats(min_value=0, max_value=1e4),
    damping=st.floats(min_value=0, max_value=1e3),
    error=st.floats(min_value=-3, max_value=3),
    velocity=st.floats(min_value=-20, max_value=20),
    target_velocity=st.floats(min_value=-20, max_value=20),
    inertia=st.floats(min_value=0.01, max_value=10),
)
def test_force_drive_satisfies_the_end_of_step_law(
    stiffness: float, damping: float, error: float, velocity: float, target_velocity: float, inertia: float
) -> None:
    """Satisfy F = k*(e - dt*v1) + c*(v_target - v1) at the end-of-step velocity v1."""
    response = 1.0 / inertia
    effort = float(
        implicit_drive_effort(
            stiffness=stiffness,
            damping=damping,
            position_error=error,
            velocity=velocity,
            target_velocity=target_velocity,
            response=response,
            dt=DT,
        )
    )
    v1 = velocity + response * DT * effort
    law = stiffness * (error - DT * v1) + damping * (target_velocity - v1)
    assert effort == pytest.approx(law, rel=1e-9, abs=1e-9 * (1 + stiffness + damping))


def test_force_drive_golden() -> None:
    """Compute one step by hand: a = 0.11, x = 1/1.22, J = x*(0.5 - 0.11)."""
    effort = implicit_drive_effort(
        stiffness=100.0,
        damping=10.0,
        position_error=0.5,
        velocity=1.0,
        target_velocity=0.0,
        response=2.0,
        dt=DT,
    )
    assert effort == pytest.approx(0.39 / 1.22 / DT, rel=1e-14)


def test_acceleration_drive_golden() -> None:
    """Use a unit response in the law and divide the impulse by the response."""
    effort = implicit_drive_effort(
        stiffness=100.0,
        damping=10.0,
        position_error=0.5,
        velocity=1.0,
        target_velocity=0.0,
        response=2.0,
        dt=DT,
        drive_type="acceleration",
    )
    assert effort == pytest.approx(0.39 / 1.11 / 2.0 / DT, rel=1e-14)


def test_acceleration_drive_is_inertia_independent() -> None:
    """Give the same velocity change for any inertia (the point of an acceleration drive)."""
    changes = []
    for inertia in (0.1, 1.0, 10.0):
        effort = implicit_drive_effort(
            stiffness=50.0,
            damping=5.0,
            position_error=0.2,
            velocity=0.0,
            target_velocity=0.0,
            response=1.0 / inertia,
            dt=DT,
            drive_type="acceleration",
        )
        changes.append(float(effort) * DT / inertia)
    assert changes == pytest.approx([changes[0]] * 3, rel=1e-12)


def test_drive_rejects_bad_arguments() -> None:
    """Refuse a non-positive or infinite dt (check_time_step's rule, as every backend) and an unknown
    drive type."""
    for dt in (0.0, math.inf):
        with pytest.raises(ValueError, match=r"dt: expected a time step > 0 and finite \[s\]"):
            implicit_drive_effort(
                stiffness=1, damping=1, position_error=0, velocity=0, target_velocity=0, response=1, dt=dt
            )
    with pytest.raises(ValueError, match="drive_type"):
        implicit_drive_effort(
            stiffness=1,
            damping=1,
            position_error=0,
            velocity=0,
            target_velocity=0,
            response=1,
            dt=0.1,
            drive_type="velocity",  # type: ignore[arg-type]
        )


# dt is a host number in every backend; a tensor or an array is refused with the same line

ENV = de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0, speed_effort_gradient=0.5)


def test_an_array_dt_is_refused_alike_in_numpy_and_warp() -> None:
    """One rule (``check_time_step``) in every backend: the same line for an array as a dt."""
    with pytest.raises(
        InputError, match=r"^dt: expected a Python float time step \[s\], got a numpy\.ndarray"
    ):
        de.clamp_effort_implicit(ENV, 5.0, 1.0, 2.0, np.array(0.01))
    pytest.importorskip("warp")
    import drive_envelope.warp as dw

    params = dw.EnvelopeArrays.from_envelopes(ENV, count=1, device="cpu")
    with pytest.raises(
        InputError, match=r"^dt: expected a Python float time step \[s\], got a numpy\.ndarray"
    ):
        dw.clamp_effort_implicit(params, 5.0, 1.0, 2.0, np.array(0.01))
    assert dw.clamp_effort_implicit(params, 5.0, 1.0, 2.0, np.int64(1)).numpy().shape == (1,)


@pytest.mark.parametrize("dt", [0.01, np.float64(0.01), np.float32(0.01)])
def test_every_backend_takes_the_same_host_numbers_as_dt(dt: object) -> None:
    expected = float(de.clamp_effort_implicit(ENV, 5.0, 1.0, 2.0, 0.01))
    assert float(de.clamp_effort_implicit(ENV, 5.0, 1.0, 2.0, dt)) == pytest.approx(expected, abs=1e-5)
    pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort_implicit

    got = clamp_effort_implicit(EnvelopeTensors.from_envelopes(ENV), 5.0, 1.0, 2.0, dt)
    assert float(got) == pytest.approx(expected, abs=1e-5)
    pytest.importorskip("warp")
    import drive_envelope.warp as dw

    params = dw.EnvelopeArrays.from_envelopes(ENV, count=1, device="cpu")
    got = dw.clamp_effort_implicit(params, 5.0, 1.0, 2.0, dt).numpy()[0]
    assert float(got) == pytest.approx(expected, abs=1e-5)


def test_every_backend_refuses_a_tensor_dt() -> None:
    torch = pytest.importorskip("torch")
    with pytest.raises(InputError, match=r"^dt: "):
        de.clamp_effort_implicit(ENV, 5.0, 0.0, 1.0, torch.tensor(0.01))  # type: ignore[arg-type]
    pytest.importorskip("warp")
    import drive_envelope.warp as dw

    params = dw.EnvelopeArrays.from_envelopes(ENV, count=1, device="cpu")
    with pytest.raises(InputError, match=r"^dt: "):
        dw.clamp_effort_implicit(params, 5.0, 0.0, 1.0, torch.tensor(0.01))


@pytest.mark.parametrize("bad", [{"max_effort": 12.0}, None, 50.0, "tmotor-ak80-6"])
def test_the_clamps_name_an_envelope_argument_that_is_not_one(bad: object) -> None:
    """A dict, None, the arguments swapped or a catalog name: one line naming the call and the type.

    They were ``AttributeError: 'dict' object has no attribute 'effort_limit'`` and, swapped,
    ``TypeError: float() argument must be ... not 'PerformanceEnvelope'``.
    """
    for call, run in [
        ("clamp_effort", lambda: de.clamp_effort(bad, 50.0, ENV)),  # type: ignore[arg-type]
        ("clamp_effort_implicit", lambda: de.clamp_effort_implicit(bad, 50.0, 1.0, 2.0, DT)),  # type: ignore[arg-type]
    ]:
        with pytest.raises(
            InputError, match=rf"^{call}: argument 'envelope': expected a PerformanceEnvelope first"
        ) as info:
            run()
        assert "\n" not in str(info.value) and type(bad).__name__ in str(info.value)
    if isinstance(bad, str):
        assert "drive_envelope.datasheet.resolve_envelope" in str(info.value)


def test_implicit_drive_effort_names_what_physx_never_takes() -> None:
    """A negative gain was an anti-spring (stiffness -30 gave -13.8 N*m toward the error's far side),
    a negative response 0 without a word, a NaN gain a NaN effort; strings, shapes and the drive
    type were bare ValueErrors. Each is one line naming the argument.
    """
    base = {"stiffness": 30.0, "damping": 1.0, "position_error": 0.5, "velocity": 0.0,
            "target_velocity": 0.0, "response": 20.0, "dt": 0.005}  # fmt: skip
    assert float(implicit_drive_effort(**base)) > 0.0  # type: ignore[arg-type]
    for change, message in [
        ({"stiffness": -30.0}, r"stiffness: expected >= 0 \[N\*m/rad or N/m\], got -30\.0"),
        ({"damping": [1.0, np.nan]}, r"damping: expected >= 0 \[N\*m\*s/rad or N\*s/m\], got nan"),
        ({"response": -20.0}, r"response: expected >= 0 \[rad/s/\(N\*m\*s\) or m/s/\(N\*s\)\], got -20\.0"),
        ({"stiffness": -1.0, "drive_type": "acceleration"}, r"stiffness: expected >= 0 \[1/s\^2\]"),
        ({"stiffness": "30 N*m/deg"}, r"stiffness: expected SI numbers, got '30 N\*m/deg'"),
        (
            {"stiffness": np.ones(3), "damping": np.ones(2)},
            r"shapes do not broadcast \(stiffness=\(3,\), damping=\(2,\)",
        ),
    ]:
        with pytest.raises(InputError, match=r"^implicit_drive_effort: " + message) as info:
            implicit_drive_effort(**{**base, **change})  # type: ignore[arg-type]
        assert "\n" not in str(info.value)
    with pytest.raises(InputError, match=r"^drive_type must be 'force' or 'acceleration', got 'position'$"):
        implicit_drive_effort(**{**base, "drive_type": "position"})  # type: ignore[arg-type]
    # a NaN response lets go, as in the clamps: 0 for a force drive
    assert float(implicit_drive_effort(**{**base, "response": np.nan})) == 0.0  # type: ignore[arg-type]

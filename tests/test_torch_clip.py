"""The explicit clip rules on torch tensors (``drive_envelope.torch.clip_effort``, issue 22).

``"end_of_step"`` is the torch port of the NumPy clamp (``clamp_effort_implicit`` over
``clamp_drive_impulse``): in float64 it must give the NumPy reference's numbers to the bit on random
vectors; its properties (sign kept, never above the request nor max_effort, inside the envelope at the
end-of-step velocity when that admits any effort) are checked on hypothesis draws. ``FreeVelocity``
is checked against hand numbers for a constant load.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drive_envelope as de

torch = pytest.importorskip("torch")
dt_mod = pytest.importorskip("drive_envelope.torch")

pytestmark = pytest.mark.torch


def _random_case(seed: int, n: int = 20000) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "effort": rng.normal(0.0, 60.0, n),
        "velocity": rng.normal(0.0, 4.0, n),
        "response": rng.uniform(0.0, 50.0, n),
        "max_effort": rng.uniform(0.0, 80.0, n),
        "max_actuator_velocity": np.where(rng.random(n) < 0.1, math.inf, rng.uniform(0.0, 6.0, n)),
        "velocity_dependent_resistance": np.where(rng.random(n) < 0.3, 0.0, rng.uniform(0.0, 5.0, n)),
        "speed_effort_gradient": np.where(rng.random(n) < 0.3, 0.0, rng.uniform(0.0, 0.2, n)),
    }


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_end_of_step_equals_numpy_reference_bit_for_bit(seed: int) -> None:
    """float64: the torch end-of-step clip is NumPy's clamp_effort_implicit, element for element, exactly."""
    case = _random_case(seed)
    names = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")
    params = dt_mod.EnvelopeTensors.from_values(**{n: case[n] for n in names}, dtype=torch.float64)
    got = dt_mod.clip_effort(
        params,
        torch.as_tensor(case["effort"]),
        torch.as_tensor(case["velocity"]),
        torch.as_tensor(case["response"]),
        0.005,
    ).numpy()
    expected = np.array(
        [
            de.clamp_effort_implicit(
                de.PerformanceEnvelope(
                    max_effort=float(case["max_effort"][i]),
                    max_actuator_velocity=float(case["max_actuator_velocity"][i]),
                    velocity_dependent_resistance=float(case["velocity_dependent_resistance"][i]),
                    speed_effort_gradient=float(case["speed_effort_gradient"][i]),
                ),
                case["effort"][i],
                case["velocity"][i],
                case["response"][i],
                0.005,
            )
            for i in range(0, case["effort"].size, 97)  # the envelope is scalar in NumPy: a sample
        ]
    )
    np.testing.assert_array_equal(np.abs(got[::97]), np.abs(expected))
    np.testing.assert_array_equal(
        np.signbit(got[::97]) & (got[::97] != 0), np.signbit(expected) & (expected != 0)
    )


def test_end_of_step_equals_numpy_core_on_the_whole_batch() -> None:
    """float64: the same numbers as NumPy's clamp_drive_impulse on effort*dt, whole batch at once."""
    case = _random_case(7)
    step = 0.005
    names = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")
    params = dt_mod.EnvelopeTensors.from_values(**{n: case[n] for n in names}, dtype=torch.float64)
    got = dt_mod.clip_effort(params, case["effort"], case["velocity"], case["response"], step).numpy()
    impulse = de.clamp_drive_impulse(
        case["velocity"],
        0.0,
        case["effort"] * step,
        case["response"],
        case["max_actuator_velocity"],
        case["max_effort"] * step,
        case["speed_effort_gradient"] / step,
        case["velocity_dependent_resistance"] * step,
    )
    expected = np.copysign(
        np.minimum(np.fmin(np.abs(impulse / step), np.abs(case["effort"])), case["max_effort"]), impulse
    )
    np.testing.assert_array_equal(got, expected)


finite = st.floats(-1e3, 1e3, allow_nan=False)
positive = st.floats(0.0, 1e3, allow_nan=False)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(
    effort=finite,
    velocity=st.floats(-20.0, 20.0),
    response=st.floats(0.01, 100.0),  # r ~ 0 is one of PhysX's epsilon cases (tests/test_clamp_properties.py)
    max_effort=positive,
    max_v=st.floats(0.0, 20.0),
    resistance=st.floats(0.0, 10.0),
    gradient=st.floats(0.0, 1.0),
)
def test_end_of_step_properties(
    effort: float,
    velocity: float,
    response: float,
    max_effort: float,
    max_v: float,
    resistance: float,
    gradient: float,
) -> None:
    """Sign kept, never above the request or max_effort; inside the envelope at v + r*dt*e when nonzero."""
    step = 0.005
    params = dt_mod.EnvelopeTensors.from_values(
        max_effort=max_effort,
        max_actuator_velocity=max_v,
        velocity_dependent_resistance=resistance,
        speed_effort_gradient=gradient,
        dtype=torch.float64,
    )
    e = float(dt_mod.clip_effort(params, effort, velocity, response, step))
    assert not math.isnan(e)
    assert e == 0.0 or math.copysign(1.0, e) == math.copysign(1.0, effort)
    assert abs(e) <= abs(effort) and abs(e) <= max_effort
    if e != 0.0:
        end = velocity + response * step * e
        scale = 1e-9 * (1.0 + abs(velocity) + response * step * abs(effort) + max_effort)
        assert abs(end) <= max_v - gradient * abs(e) + scale * (1.0 + gradient)
        assert abs(e) <= max_effort - resistance * abs(end) + scale * (1.0 + resistance)


def test_start_of_step_is_the_explicit_clamp_and_end_of_step_needs_response() -> None:
    """clip='start_of_step' is clamp_effort at the given velocity; end_of_step without response refuses."""
    params = dt_mod.EnvelopeTensors.from_values(
        max_effort=10.0, max_actuator_velocity=2.0, dtype=torch.float64
    )
    assert float(dt_mod.clip_effort(params, 5.0, 2.5, clip="start_of_step")) == 0.0  # above the line
    assert float(dt_mod.clip_effort(params, -5.0, 2.5, 1.0, 0.1)) == -5.0  # braking back inside: whole
    with pytest.raises(de.InputError, match="needs response"):
        dt_mod.clip_effort(params, 5.0, 0.0)
    with pytest.raises(de.InputError, match="clip = 'later'"):
        dt_mod.clip_effort(params, 5.0, 0.0, 1.0, 0.1, clip="later")


def test_free_velocity_recovers_a_constant_load() -> None:
    """A load of 2 N*m on 0.5 kg*m^2 adds 0.02 rad/s per 5 ms step: predicted exactly from the second step."""
    inertia, step, load = 0.5, 0.005, 2.0
    free = dt_mod.FreeVelocity(torch.zeros((2, 1), dtype=torch.float64))
    v = torch.zeros((2, 1), dtype=torch.float64)
    assert free.predict(v, 1.0 / inertia, step).tolist() == [[0.0], [0.0]]  # no history yet
    effort = torch.tensor([[1.0], [-3.0]], dtype=torch.float64)
    free.record(effort)
    v = v + step * (effort + load) / inertia
    predicted = free.predict(v, 1.0 / inertia, step)
    np.testing.assert_allclose(predicted.numpy(), (v + step * load / inertia).numpy(), rtol=0, atol=1e-15)
    free.reset(torch.tensor([1]))
    predicted = free.predict(v, 1.0 / inertia, step)
    assert predicted[1, 0] == v[1, 0]  # environment 1 forgot its step

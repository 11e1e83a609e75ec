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


# -- the fused end-of-step clip (torch.compile): the same formula as one kernel ----------------------


def _envelope(case: dict[str, np.ndarray], dtype: object) -> object:
    names = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")
    return dt_mod.EnvelopeTensors.from_values(**{n: case[n] for n in names}, dtype=dtype)


def _fused_or_skip(*args: object, **kwargs: object) -> object:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # a failed compile warns: here it must say why
        try:
            return dt_mod.clip_effort(*args, **kwargs, fused=True)
        except RuntimeWarning as exc:  # torch.compile needs a working C++ toolchain; report, don't fail
            pytest.skip(f"torch.compile unavailable here: {exc}")


def test_fused_end_of_step_gives_the_eager_numbers_float32() -> None:
    """float32, 20000 random cases: the compiled kernel equals the eager port to 2 ulp of the effort scale."""
    case = _random_case(3)
    params = _envelope(case, torch.float32)
    inputs = [torch.as_tensor(case[k], dtype=torch.float32) for k in ("effort", "velocity", "response")]
    eager = dt_mod.clip_effort(params, *inputs, 0.005).numpy()
    fused = _fused_or_skip(params, *inputs, 0.005).numpy()
    scale = np.maximum(np.abs(case["effort"]), 1.0).astype(np.float32)
    assert np.max(np.abs(fused - eager) / scale) <= 2.0 * np.finfo(np.float32).eps
    assert np.mean(fused == eager) > 0.999  # nearly every element to the bit
    assert np.all((fused == 0) | (np.sign(fused) == np.sign(case["effort"])))
    assert np.mean(np.abs(eager) < np.abs(case["effort"]) - 1e-3) > 0.3  # the batch saturates often


def test_free_velocity_clip_is_predict_clip_record_in_one_call() -> None:
    """FreeVelocity.clip (fused) gives what predict + clip_effort + record give, and keeps the history."""
    rng = np.random.default_rng(5)
    shape = (64, 12)  # 768 elements: below FUSE_MIN_ELEMENTS, so fused=None stays eager
    params = dt_mod.EnvelopeTensors.from_values(
        max_effort=25.0, max_actuator_velocity=3.0, speed_effort_gradient=0.05, dtype=torch.float32
    )
    response, step = torch.full(shape, 20.0), 0.005
    manual, fused, by_size = (dt_mod.FreeVelocity(torch.zeros(shape)) for _ in range(3))
    v = torch.zeros(shape)
    for _ in range(3):
        request = torch.as_tensor(rng.normal(0.0, 40.0, shape), dtype=torch.float32)
        expected = dt_mod.clip_effort(params, request, manual.predict(v, response, step), response, step)
        manual.record(expected)
        got = fused.clip(params, request, v, response, step, fused=True)
        sized = by_size.clip(params, request, v, response, step)
        np.testing.assert_allclose(got.numpy(), expected.numpy(), rtol=2e-6, atol=1e-5)
        np.testing.assert_array_equal(sized.numpy(), expected.numpy())  # the eager path: to the bit
        v = v + step * response * expected + 0.01  # a load the history must pick up
    assert dt_mod.FUSE_MIN_ELEMENTS == 4096 and math.prod(shape) < dt_mod.FUSE_MIN_ELEMENTS


def test_failed_compile_warns_once_and_stays_eager(monkeypatch: pytest.MonkeyPatch) -> None:
    """Where torch.compile fails, one RuntimeWarning names the error and the eager numbers come back."""
    from drive_envelope._src.kernels import torch_clip

    def broken() -> object:
        def run(*_: object) -> object:
            raise RuntimeError("no C++ compiler\nsecond line")

        return run

    monkeypatch.setattr(torch_clip, "_compiled", broken)
    monkeypatch.setattr(torch_clip, "_COMPILE_FAILED", [])
    params = dt_mod.EnvelopeTensors.from_values(max_effort=30.0, max_actuator_velocity=2.0)
    with pytest.warns(RuntimeWarning, match=r"torch\.compile failed \(RuntimeError: no C\+\+ compiler\)"):
        first = dt_mod.clip_effort(params, torch.tensor([40.0]), torch.tensor([0.0]), 20.0, 0.005, fused=True)
    assert first.tolist() == pytest.approx([20.0])  # the line at 2 rad/s after 5 ms at r = 20: 2/(20*0.005)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = dt_mod.clip_effort(
            params, torch.tensor([-10.0]), torch.tensor([2.5]), 20.0, 0.005, fused=True
        )
    assert again.tolist() == [-10.0]  # braking from above the line back inside: given whole, no new warning

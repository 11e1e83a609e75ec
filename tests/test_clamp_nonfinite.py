"""NaN, infinity and bad arguments in the batched backends (NumPy, Warp, torch; CPU only).

One rule everywhere for the explicit clamp and the effort limit: a NaN effort or velocity gives 0; an
infinite velocity the limit at infinite speed: 0 when ``R > 0`` or ``v_max`` is finite, else
``max_effort``; an infinite effort the limit; without a RuntimeWarning. A negative ``response`` on
the host is refused by all three backends (a Warp array or torch tensor is not read: that would
sync with the device), and so is a time step that is not finite and > 0.

A backend is a test parameter with its engine marker (tests/_backends.py), or its test skips with
``pytest.importorskip``: each skips cleanly where its package is missing. A bad time step in every
backend: tests/test_kernels_backends.py.
"""

from __future__ import annotations

import itertools
import math
import warnings
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from _backends import EVERY, Backend
from drive_envelope.errors import InputError

F32_MAX = float(np.finfo(np.float32).max)
NAMES = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient")


def _torch() -> Any:
    pytest.importorskip("torch")
    import drive_envelope.torch as dt

    return dt


def _warp() -> Any:
    wp = pytest.importorskip("warp")
    wp.config.quiet = True
    import drive_envelope.warp as dw

    return dw


def _same(a: Any, b: Any) -> bool:
    """Equal element for element (-0.0 equals 0.0), no NaN allowed on either side."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return bool(np.array_equal(a, b)) and not np.isnan(a).any()


def _close(a: Any, b: Any, rtol: float) -> bool:
    """Equal within ``rtol`` (zeros, infinities and the limits' end points exactly), no NaN."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return bool(np.allclose(a, b, rtol=rtol, atol=0.0)) and not np.isnan(a).any()


def _rounded(env: de.PerformanceEnvelope) -> de.PerformanceEnvelope:
    """``env`` with its four values as float32 holds them (what a float32 backend computes with)."""
    return de.PerformanceEnvelope(**{n: float(np.float32(getattr(env, n))) for n in NAMES})


def _one_line(error: pytest.ExceptionInfo[InputError], *parts: str) -> None:
    text = str(error.value)
    assert "\n" not in text
    for part in parts:
        assert part in text, (part, text)


# -- the rule, written out independently of any backend ------------------------------------------


def _expected_limit(env: de.PerformanceEnvelope, velocity: float) -> float:
    """The effort limit by the documented rule (float64, scalar)."""
    if math.isnan(velocity):
        return 0.0
    speed = abs(velocity)
    if math.isinf(speed):
        bounded = env.velocity_dependent_resistance > 0.0 or math.isfinite(env.max_actuator_velocity)
        return 0.0 if bounded else env.max_effort
    return float(env.effort_limit(speed))  # the finite formula is checked in test_envelope_model


def _expected_clamp(env: de.PerformanceEnvelope, effort: float, velocity: float) -> float:
    if math.isnan(effort):
        return 0.0
    limit = _expected_limit(env, velocity)
    return min(max(effort, -limit), limit)


RULE_ENVELOPES = [
    de.PerformanceEnvelope(max_effort=2.0),  # neither line: max_effort at any speed
    de.PerformanceEnvelope(max_effort=2.0, speed_effort_gradient=0.5),  # G without a speed limit
    de.PerformanceEnvelope(max_effort=2.0, velocity_dependent_resistance=0.1),
    de.PerformanceEnvelope(max_effort=2.0, velocity_dependent_resistance=1e-300),  # R*v_max < max_effort
    de.PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=3.0),  # G = 0: the yes/no test
    de.PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=3.0, speed_effort_gradient=0.5),
    de.PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=F32_MAX),  # PhysX's FLT_MAX "no limit"
    de.PerformanceEnvelope(
        max_effort=2.0,
        max_actuator_velocity=3.0,
        velocity_dependent_resistance=0.1,
        speed_effort_gradient=0.5,
    ),
]
RULE_VELOCITIES = [0.0, 1.0, -2.5, 3.0, 4.0, math.inf, -math.inf, math.nan]
RULE_EFFORTS = [0.0, 1.0, -5.0, math.inf, -math.inf, math.nan]


def _rule_grid() -> tuple[list[de.PerformanceEnvelope], np.ndarray, np.ndarray]:
    rows = list(itertools.product(RULE_ENVELOPES, RULE_EFFORTS, RULE_VELOCITIES))
    return [r[0] for r in rows], np.array([r[1] for r in rows]), np.array([r[2] for r in rows])


def _expected_grid(
    float32: bool = False,
) -> tuple[list[de.PerformanceEnvelope], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rule's grid and its expected clamp and limit (for float32: on the float32 envelope values)."""
    envs, effort, velocity = _rule_grid()
    if float32:  # R = 1e-300 is 0 in float32: the envelope then has neither line
        envs = [_rounded(e) for e in envs]
    clamped = np.array([_expected_clamp(e, x, v) for e, x, v in zip(envs, effort, velocity, strict=True)])
    limit = np.array([_expected_limit(e, v) for e, v in zip(envs, velocity, strict=True)])
    return envs, effort, velocity, clamped, limit


# -- NaN and infinity ---------------------------------------------------------------------------------


def test_numpy_follows_the_nan_and_infinity_rule_without_warnings() -> None:
    """Give 0 for a NaN effort or velocity and the limit at infinite speed, in NumPy, warning-free."""
    envs, effort, velocity, clamped, limit = _expected_grid()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = [float(de.clamp_effort(e, x, v)) for e, x, v in zip(envs, effort, velocity, strict=True)]
        got_limit = [float(e.effort_limit(v)) for e, v in zip(envs, velocity, strict=True)]
        # vectorized too (one envelope, many states)
        vector = de.clamp_effort(RULE_ENVELOPES[0], np.array(RULE_EFFORTS), np.array([math.inf] * 6))
    assert _same(got, clamped)
    assert _same(got_limit, limit)
    assert _same(vector, [0.0, 1.0, -2.0, 2.0, -2.0, 0.0])


def test_numpy_reported_cases() -> None:
    """The reported rows: NaN effort -> 0 (was NaN); effort 5 at infinite velocity -> 0, no warning."""
    env = de.PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=3.0, speed_effort_gradient=0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert float(de.clamp_effort(env, effort=math.nan, velocity=1.0)) == 0.0
        assert float(de.clamp_effort(env, effort=5.0, velocity=np.inf)) == 0.0
        assert (
            float(de.clamp_effort(de.PerformanceEnvelope(max_effort=2.0), effort=5.0, velocity=np.inf)) == 2.0
        )
        assert float(env.effort_limit(math.nan)) == 0.0


@pytest.mark.parametrize(
    ("name", "dtype"),
    [
        pytest.param("warp", "float32", marks=pytest.mark.warp, id="warp-float32"),
        pytest.param("torch", "float32", marks=pytest.mark.torch, id="torch-float32"),
        pytest.param("torch", "float64", marks=pytest.mark.torch, id="torch-float64"),
    ],
)
def test_ports_follow_the_rule(name: str, dtype: str) -> None:
    """Give the rule's numbers from Warp's launches and torch's ops for effort_limit and clamp_effort."""
    port = Backend(name=name)
    envs, effort, velocity, clamped, limit = _expected_grid(float32=dtype == "float32")
    rtol = 1e-6 if dtype == "float32" else 1e-15
    params = port.params(envs, dtype=dtype)
    # torch gets tensors of its dtype, Warp host arrays its launch wrappers upload
    e, v = (
        (effort, velocity) if name == "warp" else port.upload([effort.astype(dtype), velocity.astype(dtype)])
    )
    assert _close(port.host(port.module.clamp_effort(params, e, v)), clamped, rtol)
    assert _close(port.host(port.module.effort_limit(params, v)), limit, rtol)


def test_warp_funcs_follow_the_rule_in_float64() -> None:
    """Give the rule's numbers from the generic @wp.func building blocks in float64 (Newton's solve)."""
    _warp()
    import warp as wp

    from drive_envelope._src.kernels import warp_funcs

    clamp_func, limit_func = warp_funcs.clamp_effort_func, warp_funcs.effort_limit_func

    @wp.kernel
    def rule(
        env: wp.array2d(dtype=wp.float64),
        effort: wp.array(dtype=wp.float64),
        velocity: wp.array(dtype=wp.float64),
        out: wp.array2d(dtype=wp.float64),
    ):
        i = wp.tid()
        out[i, 0] = clamp_func(env[i, 0], env[i, 1], env[i, 2], env[i, 3], effort[i], velocity[i])
        out[i, 1] = limit_func(env[i, 0], env[i, 1], env[i, 2], env[i, 3], velocity[i])

    envs, effort, velocity, clamped, limit = _expected_grid()
    rows = np.array([[getattr(e, n) for n in NAMES] for e in envs])
    out = wp.zeros((len(envs), 2), dtype=wp.float64, device="cpu")
    inputs = [wp.array(a, dtype=wp.float64, device="cpu") for a in (rows, effort, velocity)]
    wp.launch(rule, dim=len(envs), inputs=inputs, outputs=[out], device="cpu")
    assert _same(out.numpy()[:, 0], clamped)
    assert _same(out.numpy()[:, 1], limit)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_torch_follows_the_rule_while_recording_and_in_its_buffers(dtype: str) -> None:
    """Give the rule's numbers with and without autograd recording, both CPU code paths."""
    dt = _torch()
    import torch

    from drive_envelope._src.kernels import torch_ops

    envs, effort, velocity, clamped, limit = _expected_grid(float32=dtype == "float32")
    kind = getattr(torch, dtype)
    rtol = 1e-6 if dtype == "float32" else 1e-15
    params = dt.EnvelopeTensors.from_envelopes(envs, dtype=kind)
    e, v = torch.tensor(effort, dtype=kind), torch.tensor(velocity, dtype=kind)
    result, result_limit = dt.clamp_effort(params, e, v), dt.effort_limit(params, v)
    assert _close(result, clamped, rtol)  # the plain path: test_ports_follow_the_rule
    assert _close(result_limit, limit, rtol)
    tracked = e.clone().requires_grad_(True)
    assert _same(dt.clamp_effort(params, tracked, v).detach(), result)
    with torch.enable_grad():
        assert _same(dt.effort_limit(params, v.clone().requires_grad_(True)).detach(), result_limit)
    views = torch.broadcast_tensors(v, *params.as_tuple())  # the in-place buffers behind both
    plain, _ = torch_ops._limit_buffers(*views)
    assert _same(plain.nan_to_num(nan=0.0), result_limit)


def test_backends_agree_on_random_states_and_special_values() -> None:
    """Give the NumPy reference's numbers from torch float64 and Warp's from torch float32 (a few ulps).

    The special values (NaN, infinite, huge) come out exactly; torch's CPU ``addcmul`` may fuse
    ``max_effort - R*|v|`` into one rounding where NumPy and Warp round twice (one ulp).
    """
    rng = np.random.default_rng(11)
    n = 3000
    special = np.array([0.0, math.inf, -math.inf, math.nan, 3.0, 1e38, -1e38])
    velocity = np.where(rng.random(n) < 0.1, rng.choice(special, n), rng.normal(0.0, 4.0, n))
    effort = np.where(rng.random(n) < 0.1, rng.choice(special, n), rng.normal(0.0, 6.0, n))
    envs = [RULE_ENVELOPES[i] for i in rng.integers(0, len(RULE_ENVELOPES), n)]
    reference = np.array(
        [float(de.clamp_effort(e, x, v)) for e, x, v in zip(envs, effort, velocity, strict=True)]
    )
    assert not np.isnan(reference).any()
    try:
        dt = _torch()
    except pytest.skip.Exception:
        dt = None
    if dt is not None:
        import torch

        p64 = dt.EnvelopeTensors.from_envelopes(envs, dtype=torch.float64)
        assert _close(dt.clamp_effort(p64, effort, velocity), reference, 1e-15)
    try:
        dw = _warp()
    except pytest.skip.Exception:
        return
    warp32 = dw.clamp_effort(dw.EnvelopeArrays.from_envelopes(envs, device="cpu"), effort, velocity).numpy()
    assert not np.isnan(warp32).any()
    if dt is not None:
        p32 = dt.EnvelopeTensors.from_envelopes(envs)
        torch32 = dt.clamp_effort(p32, effort.astype(np.float32), velocity.astype(np.float32))
        assert _close(torch32, warp32, 1e-6)


# -- arguments checked on the host -----------------------------------------------------------------

ENV = de.PerformanceEnvelope(
    max_effort=12.0, max_actuator_velocity=10.0, velocity_dependent_resistance=0.1, speed_effort_gradient=0.5
)


@pytest.fixture(params=[p for p in EVERY if "cuda" not in str(p.id)])
def every(request: pytest.FixtureRequest) -> Backend:
    """The NumPy reference and the ports on the CPU (this file's checks are on the host)."""
    name, device = request.param
    return Backend(name=name, device=device)


def test_negative_response_is_refused_on_the_host_in_every_backend(every: Backend) -> None:
    """Refuse a negative response given as a number or NumPy array in NumPy, Warp and torch alike."""
    params = every.params(ENV, count=2)
    for request, response, shown in [
        (1.0, -1.0, "-1.0"),
        (np.array([1.0, 1.0], dtype=np.float32), np.array([2.0, -0.5]), "-0.5"),
    ]:
        with pytest.raises(InputError) as error:
            every.ops().clamp_effort_implicit(params, request, 0.0, response, 0.01)
        _one_line(error, "response", ">= 0", shown)


def test_device_response_is_not_read_and_gives_the_guarded_result() -> None:
    """Read no device value: a negative response in a Warp array or a tensor gives a guarded result."""
    request = np.array([5.0, -50.0, 50.0, 3.0], dtype=np.float32)
    velocity = np.array([0.0, 2.0, -9.0, 1.0], dtype=np.float32)
    response = np.array([-2.0, -50.0, -1e3, math.nan], dtype=np.float32)
    results = []
    try:
        dw = _warp()
        import warp as wp

        params = dw.EnvelopeArrays.from_envelopes(ENV, count=4, device="cpu")
        device_response = wp.array(response, dtype=wp.float32, device="cpu")
        results.append(dw.clamp_effort_implicit(params, request, velocity, device_response, 0.01).numpy())
    except pytest.skip.Exception:
        pass
    try:
        dt = _torch()
        import torch

        params = dt.EnvelopeTensors.from_envelopes(ENV, count=4)
        tensor_response = torch.from_numpy(response)
        results.append(dt.clamp_effort_implicit(params, request, velocity, tensor_response, 0.01).numpy())
    except pytest.skip.Exception:
        pass
    if not results:
        pytest.skip("neither warp nor torch is installed")
    for result in results:
        assert not np.isnan(result).any()
        assert (np.abs(result) <= ENV.max_effort).all()
        assert (result * request >= 0.0).all() and (np.abs(result) <= np.abs(request)).all()
        assert result[3] == 0.0  # a NaN response lets the drive go, as in NumPy
    assert float(de.clamp_effort_implicit(ENV, 3.0, 1.0, math.nan, 0.01)) == 0.0
    if len(results) == 2:
        np.testing.assert_allclose(results[0], results[1], rtol=1e-5, atol=1e-4)

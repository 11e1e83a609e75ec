"""Warp backend (drive_envelope.warp) against the NumPy reference, on Warp's CPU device and CUDA.

Tolerances: ``clamp_drive_impulse`` is compared bit for bit with the reference run in float32
(``dtype=numpy.float32``), which reproduces PhysX's float arithmetic, and with PhysX's own results
(tests/golden); the effort-level kernels, whose float32 results are compared with the float64
reference, within ``rtol = 1e-5`` plus ``atol = 1e-5`` times the effort scale (a few float32 ulps
of the largest intermediate).
"""

from __future__ import annotations

import inspect
import subprocess
import sys
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from _kernel_vectors import IMPULSE_ARGS, edge_impulse_args, envelope_cases, physx_golden, random_impulse_args
from drive_envelope.errors import InputError

pytestmark = pytest.mark.warp

DEVICES = ["cpu", pytest.param("cuda:0", marks=pytest.mark.gpu)]
RTOL = 1e-5
ATOL_SCALE = 1e-5


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal element for element, NaN matching NaN, -0.0 matching 0.0."""
    return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))


@pytest.fixture(params=DEVICES)
def device(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def _upload(args: list[np.ndarray], device: str) -> list[object]:
    import warp as wp

    return [wp.array(a, dtype=wp.float32, device=device) for a in args]


def test_signature_matches_core() -> None:
    """Keep clamp_drive_impulse's parameters in the core's names and order."""
    import drive_envelope.warp as dw

    core = list(inspect.signature(de.clamp_drive_impulse).parameters)
    assert list(inspect.signature(dw.clamp_drive_impulse).parameters) == core
    assert core[:8] == list(IMPULSE_ARGS)


@pytest.mark.parametrize("vectors", ["random", "edge"])
def test_clamp_drive_impulse_matches_float32_reference(device: str, vectors: str) -> None:
    """Reproduce the float32 reference bit for bit on random and edge-case vectors (NaN included)."""
    import drive_envelope.warp as dw

    args = random_impulse_args() if vectors == "random" else edge_impulse_args()
    for exact in (False, True):
        result = dw.clamp_drive_impulse(*_upload(args, device), physx_exact=exact).numpy()
        assert _same(result, de.clamp_drive_impulse(*args, dtype=np.float32, physx_exact=exact))


def test_clamp_drive_impulse_matches_physx_golden(device: str) -> None:
    """Reproduce real PhysX's float32 results (tests/golden) bit for bit."""
    import drive_envelope.warp as dw

    golden = physx_golden()
    if golden is None:
        pytest.skip("tests/golden/physx_clamp_drive_impulse.npz not present")
    args, expected = golden
    exact = dw.clamp_drive_impulse(*_upload(args, device), physx_exact=True).numpy()
    assert _same(exact, expected)
    assert np.array_equal(exact.view(np.uint32), expected.view(np.uint32))  # zeros' signs, NaN bits
    guarded = dw.clamp_drive_impulse(*_upload(args, device)).numpy()
    assert _same(guarded, de.clamp_drive_impulse(*args, dtype=np.float32))


def test_clamp_drive_impulse_accepts_numpy_and_scalars() -> None:
    """Broadcast NumPy arrays and scalars like the core and return what numpy.asarray reads."""
    import drive_envelope.warp as dw

    velocity = np.linspace(-3.0, 3.0, 12, dtype=np.float32).reshape(3, 4)
    result = np.asarray(dw.clamp_drive_impulse(velocity, 0.0, 1.0, 2.0, 2.5, 0.8, 0.3, 0.05))
    expected = de.clamp_drive_impulse(velocity, 0.0, 1.0, 2.0, 2.5, 0.8, 0.3, 0.05, dtype=np.float32)
    assert result.shape == (3, 4)
    assert _same(result, expected)


def test_clamp_drive_impulse_close_to_float64_reference() -> None:
    """Stay within float32 tolerance of the float64 reference on random vectors."""
    import drive_envelope.warp as dw

    args = random_impulse_args()
    result = np.asarray(dw.clamp_drive_impulse(*args), dtype=np.float64)
    expected = de.clamp_drive_impulse(*[a.astype(np.float64) for a in args])
    np.testing.assert_allclose(result, expected, rtol=RTOL, atol=ATOL_SCALE * 2.0)


@pytest.mark.parametrize("case", envelope_cases(), ids=lambda c: "-".join(sorted(c)))
def test_effort_kernels_match_reference(device: str, case: dict[str, float]) -> None:
    """Match effort_limit, the explicit clamp and the implicit clamp of the float64 reference."""
    import drive_envelope.warp as dw

    env = de.PerformanceEnvelope(**case)
    rng = np.random.default_rng(3)
    n = 4000
    velocity = rng.normal(0.0, 4.0, n).astype(np.float32)
    effort = rng.normal(0.0, 6.0, n).astype(np.float32)
    applied = rng.normal(0.0, 1.0, n).astype(np.float32)
    response = rng.uniform(0.0, 80.0, n).astype(np.float32)
    params = dw.EnvelopeArrays.from_envelopes(env, count=n, device=device)
    v64, e64, a64, r64 = (a.astype(np.float64) for a in (velocity, effort, applied, response))
    atol = ATOL_SCALE * max(env.max_effort, 1.0)

    limit = dw.effort_limit(params, velocity).numpy()
    np.testing.assert_allclose(limit, env.effort_limit(v64), rtol=RTOL, atol=atol)
    explicit = dw.clamp_effort(params, effort, velocity).numpy()
    np.testing.assert_allclose(explicit, de.clamp_effort(env, e64, v64), rtol=RTOL, atol=atol)
    implicit = dw.clamp_effort_implicit(params, effort, velocity, response, 0.01, applied).numpy()
    expected = de.clamp_effort_implicit(env, e64, v64, r64, 0.01, a64)
    np.testing.assert_allclose(implicit, expected, rtol=1e-4, atol=1e-4 * max(env.max_effort, 1.0))


def test_explicit_clamp_lets_go_on_nan() -> None:
    """Turn a NaN effort or velocity into 0 (the drive lets go), as the reference does (was: NaN)."""
    import drive_envelope.warp as dw

    env = de.PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=3.0, speed_effort_gradient=0.5)
    effort = np.array([np.nan, 1.0, 5.0], dtype=np.float32)
    velocity = np.array([0.0, np.nan, 1.0], dtype=np.float32)
    params = dw.EnvelopeArrays.from_envelopes(env, count=3, device="cpu")
    result = dw.clamp_effort(params, effort, velocity).numpy()
    assert _same(result, de.clamp_effort(env, effort, velocity))
    assert result.tolist() == [0.0, 0.0, 2.0]


def test_funcs_work_inside_user_kernels() -> None:
    """Call the @wp.func building blocks from a user kernel and get the launch wrappers' numbers."""
    import warp as wp

    import drive_envelope.warp as dw

    clamp_effort_func, clamp_effort_implicit_func = dw.clamp_effort_func, dw.clamp_effort_implicit_func

    @wp.kernel
    def user_kernel(
        tau: wp.array(dtype=wp.float32),
        qd: wp.array(dtype=wp.float32),
        out: wp.array(dtype=wp.float32, ndim=2),
    ):
        i = wp.tid()
        out[i, 0] = clamp_effort_func(2.0, 3.0, 0.1, 0.5, tau[i], qd[i])
        out[i, 1] = clamp_effort_implicit_func(2.0, 3.0, 0.1, 0.5, tau[i], qd[i], 50.0, 0.01, 0.0)

    tau = np.linspace(-5.0, 5.0, 101, dtype=np.float32)
    qd = np.linspace(4.0, -4.0, 101, dtype=np.float32)
    out = wp.zeros((101, 2), dtype=wp.float32, device="cpu")
    wp.launch(user_kernel, dim=101, inputs=_upload([tau, qd], "cpu"), outputs=[out], device="cpu")
    env = de.PerformanceEnvelope(
        max_effort=2.0,
        max_actuator_velocity=3.0,
        velocity_dependent_resistance=0.1,
        speed_effort_gradient=0.5,
    )
    params = dw.EnvelopeArrays.from_envelopes(env, count=101, device="cpu")
    result = out.numpy()
    assert _same(result[:, 0], dw.clamp_effort(params, tau, qd).numpy())
    assert _same(result[:, 1], dw.clamp_effort_implicit(params, tau, qd, 50.0, 0.01).numpy())


def test_out_buffer_is_reused() -> None:
    """Write into a caller's buffer (in place on the effort itself) instead of allocating."""
    import warp as wp

    import drive_envelope.warp as dw

    params = dw.EnvelopeArrays.from_values(max_effort=[1.0, 2.0, 3.0])
    effort = wp.array([5.0, -5.0, 0.5], dtype=wp.float32, device=params.device)
    result = dw.clamp_effort(params, effort, 0.0, out=effort)
    assert result is effort
    np.testing.assert_array_equal(effort.numpy(), [1.0, -2.0, 0.5])


def test_bad_input_raises_input_error() -> None:
    """Reject a bad dtype, non-broadcasting shapes, a bad dt and invalid parameters with InputError."""
    import warp as wp

    import drive_envelope.warp as dw

    with pytest.raises(InputError, match="dtype"):
        dw.clamp_drive_impulse(0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, dtype=np.float64)
    with pytest.raises(InputError, match="broadcast"):
        dw.clamp_drive_impulse(np.zeros(3), np.zeros(4), 1.0, 1.0, 1.0, 1.0, 0.0, 0.0)
    params = dw.EnvelopeArrays.from_values(max_effort=1.0, count=4)
    with pytest.raises(InputError, match="dt"):
        dw.clamp_effort_implicit(params, 1.0, 0.0, 1.0, 0.0)
    with pytest.raises(InputError, match="velocity"):
        dw.clamp_effort(params, 1.0, wp.zeros(5, dtype=wp.float32, device=params.device))
    with pytest.raises(InputError, match="speed_effort_gradient"):
        dw.EnvelopeArrays.from_values(max_effort=1.0, speed_effort_gradient=[0.0, -1.0])
    with pytest.raises(InputError, match="max_effort"):
        dw.EnvelopeArrays.from_values(max_effort=np.inf, count=2)
    with pytest.raises(InputError, match="shapes differ"):
        dw.EnvelopeArrays(
            max_effort=wp.zeros(2, dtype=wp.float32),
            max_actuator_velocity=wp.zeros(3, dtype=wp.float32),
            velocity_dependent_resistance=wp.zeros(2, dtype=wp.float32),
            speed_effort_gradient=wp.zeros(2, dtype=wp.float32),
        )


def test_import_is_light() -> None:
    """Import drive_envelope.warp without importing Warp."""
    code = "import sys, drive_envelope.warp\nprint('warp' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


# zero DOFs (kernel finding 3)

ENV = de.PerformanceEnvelope(
    max_effort=12.0, max_actuator_velocity=10.0, velocity_dependent_resistance=0.1, speed_effort_gradient=0.5
)


def _warp() -> Any:
    wp = pytest.importorskip("warp")
    wp.config.quiet = True
    import drive_envelope.warp as dw

    return dw


def _one_line(error: pytest.ExceptionInfo[InputError], *parts: str) -> None:
    text = str(error.value)
    assert "\n" not in text
    for part in parts:
        assert part in text, (part, text)


def test_warp_accepts_zero_dofs() -> None:
    """Build empty EnvelopeArrays (count 0) and get empty results from every launch."""
    dw = _warp()
    import warp as wp

    for params in (
        dw.EnvelopeArrays.from_envelopes(ENV, count=0, device="cpu"),
        dw.EnvelopeArrays.from_values(max_effort=1.0, count=0, device="cpu"),
        dw.EnvelopeArrays.from_values(max_effort=[], device="cpu"),
    ):
        assert params.count == 0
        empty = np.zeros(0, dtype=np.float32)
        assert dw.effort_limit(params, empty).shape == (0,)
        assert dw.clamp_effort(params, empty, 0.0).shape == (0,)
        assert dw.clamp_effort_implicit(params, 1.0, empty, 2.0, 0.01).shape == (0,)
        out = wp.empty(0, dtype=wp.float32, device="cpu")
        assert dw.clamp_effort(params, empty, empty, out=out) is out
    with pytest.raises(InputError) as error:
        dw.EnvelopeArrays.from_envelopes(ENV, count=-1, device="cpu")
    _one_line(error, "count", ">= 0", "-1")
    with pytest.raises(InputError) as error:
        dw.EnvelopeArrays.from_values(max_effort=1.0, count=-2, device="cpu")
    _one_line(error, "count", ">= 0", "-2")

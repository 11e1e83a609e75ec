"""One test per behaviour of the batched backends, the backend a parameter (as Newton does devices).

The torch and Warp ports (``drive_envelope.torch``, ``drive_envelope.warp``), on the CPU and CUDA,
against the NumPy reference; the NumPy reference itself where the behaviour has numbers of its own
(a NaN lets go, zero DOFs, a bad time step). Each parameter carries its engine marker, so it skips
cleanly where the extra is absent (tests/conftest.py); CUDA ones skip without a device.

Tolerances: ``clamp_drive_impulse`` on float32 is compared bit for bit with the reference run in
float32 (``dtype=numpy.float32``, PhysX's arithmetic) and with PhysX's own results (tests/golden);
against the float64 reference within ``rtol = 1e-5`` plus ``atol = 2e-5``. The effort-level ops in
float32 against the float64 reference: ``rtol = 1e-5`` plus ``atol = 1e-5`` times the effort scale
(implicit: ``1e-4`` and ``1e-4``).

What only one backend has stays in its file: torch's dtypes, autograd and float64 impulse
(tests/test_kernels_torch.py), Warp's ``@wp.func`` blocks and ``out=`` buffers
(tests/test_kernels_warp.py); the NaN/infinity rule over a grid is tests/test_clamp_nonfinite.py.
"""

from __future__ import annotations

import inspect
import math
import subprocess
import sys
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from _backends import DEVICES, EVERY, PORTS, Backend
from _kernel_vectors import IMPULSE_ARGS, edge_impulse_args, envelope_cases, physx_golden, random_impulse_args
from drive_envelope.errors import InputError

RTOL = 1e-5
ATOL_SCALE = 1e-5


@pytest.fixture(params=PORTS)
def port(request: pytest.FixtureRequest) -> Backend:
    return Backend(name=str(request.param))


@pytest.fixture(params=DEVICES)
def backend(request: pytest.FixtureRequest) -> Backend:
    name, device = request.param
    return Backend(name=name, device=device)


@pytest.fixture(params=EVERY)
def every(request: pytest.FixtureRequest) -> Backend:
    name, device = request.param
    return Backend(name=name, device=device)


def _same(a: Any, b: Any) -> bool:
    """Equal element for element, NaN matching NaN, -0.0 matching 0.0."""
    return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))


def _one_line(error: pytest.ExceptionInfo[InputError], *parts: str) -> None:
    text = str(error.value)
    assert "\n" not in text
    for part in parts:
        assert part in text, (part, text)


# -- one name, one signature ------------------------------------------------------------------------

OPS = ("effort_limit", "clamp_effort", "clamp_effort_implicit", "clamp_drive_impulse")
WARP_ONLY = ("out",)
"""Warp's keyword-only extra: a caller's buffer to write into (torch returns new tensors)."""


def _parameters(function: Any, drop: tuple[str, ...] = ()) -> list[tuple[str, Any, Any]]:
    """(name, kind, default) of each parameter; ``dtype``'s default is each backend's own float."""
    return [
        (p.name, p.kind, None if p.name == "dtype" else p.default)
        for p in inspect.signature(function).parameters.values()
        if p.name not in drop
    ]


@pytest.mark.parametrize("name", OPS)
def test_every_backend_gives_a_name_one_signature(name: str) -> None:
    """Give each op the same parameters (names, order, kinds, defaults) in torch, Warp and the core."""
    import drive_envelope.torch as dt
    import drive_envelope.warp as dw

    assert name in dt.__all__ and name in dw.__all__
    torch_args = _parameters(getattr(dt, name))
    assert _parameters(getattr(dw, name), drop=WARP_ONLY) == torch_args
    if name == "clamp_drive_impulse":  # PhysX's arguments in PhysX's order everywhere
        assert _parameters(de.clamp_drive_impulse) == torch_args
        assert _parameters(dt.fused_clamp_drive_impulse) == torch_args
        assert [a[0] for a in torch_args[:8]] == list(IMPULSE_ARGS)
    else:  # the core takes the envelope where the ports take their per-DOF parameters
        reference = de.PerformanceEnvelope.effort_limit if name == "effort_limit" else getattr(de, name)
        core = _parameters(reference)
        assert core[0][0] == ("self" if name == "effort_limit" else "envelope")
        assert torch_args[0][0] == "params" and core[1:] == torch_args[1:]


@pytest.mark.parametrize(
    ("module", "heavy"),
    [
        pytest.param("drive_envelope.torch", ("torch",), marks=pytest.mark.torch, id="torch"),
        pytest.param("drive_envelope.warp", ("warp",), marks=pytest.mark.warp, id="warp"),
        pytest.param("drive_envelope.newton", ("newton", "warp"), marks=pytest.mark.newton, id="newton"),
    ],
)
def test_import_is_light(module: str, heavy: tuple[str, ...]) -> None:
    """Import the backend's facade without importing its package (each function does)."""
    code = f"import sys, {module}\nprint(any(name in sys.modules for name in {heavy!r}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


# -- clamp_drive_impulse ----------------------------------------------------------------------------


@pytest.mark.parametrize("vectors", ["random", "edge"])
def test_clamp_drive_impulse_matches_float32_reference(backend: Backend, vectors: str) -> None:
    """Reproduce the float32 reference bit for bit on random and edge-case vectors (NaN included)."""
    args = random_impulse_args() if vectors == "random" else edge_impulse_args()
    for exact in (False, True):
        result = backend.host(backend.module.clamp_drive_impulse(*backend.upload(args), physx_exact=exact))
        assert _same(result, de.clamp_drive_impulse(*args, dtype=np.float32, physx_exact=exact))


def test_clamp_drive_impulse_near_the_float_range_matches_the_reference(backend: Backend) -> None:
    """Finite ``dev -+ limit`` that overflow take the split quotients, as in the NumPy core.

    Velocities and limits of 1e38-3.3e38 in float32: some of these elements give another result
    when every bound is formed as PhysX forms it (what the Warp kernel's fast path does).
    """
    rng = np.random.default_rng(1)
    n, f = 4000, np.float32
    args = [
        (rng.uniform(1e38, 3.3e38, n) * rng.choice([-1, 1], n)).astype(f),
        np.zeros(n, f),
        rng.uniform(-3e38, 3e38, n).astype(f),
        rng.uniform(1.0, 3.0, n).astype(f),
        rng.uniform(1e38, 3.3e38, n).astype(f),
        rng.uniform(1e37, 3e38, n).astype(f),
        rng.uniform(0.0, 2.0, n).astype(f),
        rng.uniform(0.0, 1.0, n).astype(f),
    ]
    expected = de.clamp_drive_impulse(*args, dtype=np.float32)
    assert np.count_nonzero(expected) > n // 3  # the clamp binds, not only lets go
    assert _same(backend.host(backend.module.clamp_drive_impulse(*backend.upload(args))), expected)


def test_clamp_drive_impulse_matches_physx_golden(backend: Backend) -> None:
    """Reproduce real PhysX's float32 results (tests/golden) bit for bit."""
    golden = physx_golden()
    if golden is None:
        pytest.skip("tests/golden/physx_clamp_drive_impulse.npz not present")
    args, expected = golden
    clamp = backend.module.clamp_drive_impulse
    exact = backend.host(clamp(*backend.upload(args), physx_exact=True))
    assert _same(exact, expected)
    assert np.array_equal(exact.view(np.uint32), expected.view(np.uint32))  # zeros' signs, NaN bits
    guarded = backend.host(clamp(*backend.upload(args)))
    assert _same(guarded, de.clamp_drive_impulse(*args, dtype=np.float32))


def test_clamp_drive_impulse_accepts_numpy_and_scalars(port: Backend) -> None:
    """Broadcast NumPy arrays and scalars like the core and return what numpy.asarray reads."""
    velocity = np.linspace(-3.0, 3.0, 12, dtype=np.float32).reshape(3, 4)
    result = np.asarray(port.module.clamp_drive_impulse(velocity, 0.0, 1.0, 2.0, 2.5, 0.8, 0.3, 0.05))
    expected = de.clamp_drive_impulse(velocity, 0.0, 1.0, 2.0, 2.5, 0.8, 0.3, 0.05, dtype=np.float32)
    assert result.shape == (3, 4)
    assert _same(result, expected)


def test_clamp_drive_impulse_close_to_float64_reference(port: Backend) -> None:
    """Stay within float32 tolerance of the float64 reference on random (float32) vectors."""
    args = random_impulse_args()
    result = np.asarray(port.module.clamp_drive_impulse(*args), dtype=np.float64)
    expected = de.clamp_drive_impulse(*[a.astype(np.float64) for a in args])
    np.testing.assert_allclose(result, expected, rtol=RTOL, atol=ATOL_SCALE * 2.0)


# -- the effort-level ops ---------------------------------------------------------------------------


@pytest.mark.parametrize("case", envelope_cases(), ids=lambda c: "-".join(sorted(c)))
def test_effort_ops_match_reference(backend: Backend, case: dict[str, float]) -> None:
    """Match effort_limit, the explicit clamp and the implicit clamp of the float64 reference.

    States as device arrays (torch tensors, ``wp.array``) and, for Warp, as NumPy arrays that the
    launch wrappers upload.
    """
    ops = backend.module
    env = de.PerformanceEnvelope(**case)
    rng = np.random.default_rng(3)
    n = 4000
    velocity, effort, applied = (rng.normal(0.0, s, n).astype(np.float32) for s in (4.0, 6.0, 1.0))
    response = rng.uniform(0.0, 80.0, n).astype(np.float32)
    params = backend.params(env, count=n)
    assert tuple(params.max_effort.shape) == (n,)
    if backend.name == "torch":
        import torch

        assert params.dtype == torch.float32 and params.shape == (n,)
    v64, e64, a64, r64 = (x.astype(np.float64) for x in (velocity, effort, applied, response))
    atol = ATOL_SCALE * max(env.max_effort, 1.0)
    forms = [backend.upload([velocity, effort, applied, response])]
    if backend.name == "warp":
        forms.append([velocity, effort, applied, response])
    for v, e, a, r in forms:
        limit = backend.host(ops.effort_limit(params, v))
        np.testing.assert_allclose(limit, env.effort_limit(v64), rtol=RTOL, atol=atol)
        explicit = backend.host(ops.clamp_effort(params, e, v))
        np.testing.assert_allclose(explicit, de.clamp_effort(env, e64, v64), rtol=RTOL, atol=atol)
        implicit = backend.host(ops.clamp_effort_implicit(params, e, v, r, 0.01, applied_effort=a))
        expected = de.clamp_effort_implicit(env, e64, v64, r64, 0.01, a64)
        np.testing.assert_allclose(implicit, expected, rtol=1e-4, atol=10 * atol)


def test_explicit_clamp_lets_go_on_nan(every: Backend) -> None:
    """Turn a NaN effort or velocity into 0 (the drive lets go), in every float dtype (was: NaN)."""
    env = de.PerformanceEnvelope(max_effort=2.0, max_actuator_velocity=3.0, speed_effort_gradient=0.5)
    for dtype in every.dtypes:
        effort = np.array([np.nan, 1.0, 5.0, 1.0], dtype=dtype)
        velocity = np.array([0.0, np.nan, 1.0, 3.0], dtype=dtype)
        params = every.params(env, count=4, dtype=dtype)
        result = every.host(every.ops().clamp_effort(params, effort, velocity))
        assert _same(result, de.clamp_effort(env, effort, velocity))
        assert result.tolist() == [0.0, 0.0, 2.0, 0.0]


def test_zero_dofs_give_empty_results(every: Backend) -> None:
    """Build empty parameters (count 0, or empty values) and get (0,) results from every op."""
    ops = every.ops()
    env = de.PerformanceEnvelope(
        max_effort=12.0,
        max_actuator_velocity=10.0,
        velocity_dependent_resistance=0.1,
        speed_effort_gradient=0.5,
    )
    empty = np.zeros(0, dtype=np.float32)
    if every.name == "numpy":
        built = [env]
    else:
        built = [every.params(env, count=0), every.values(max_effort=[])]
    for params in built:
        assert params is env or tuple(params.max_effort.shape) == (0,)
        states = [empty] if every.name == "numpy" else [empty, every.upload([empty])[0]]
        for state in states:
            assert every.host(ops.clamp_effort(params, state, state)).shape == (0,)
            assert every.host(ops.clamp_effort(params, state, 0.0)).shape == (0,)
            assert every.host(ops.effort_limit(params, state)).shape == (0,)
            assert every.host(ops.clamp_effort_implicit(params, state, state, 2.0, 0.01)).shape == (0,)
            assert every.host(ops.clamp_effort_implicit(params, 1.0, state, 2.0, 0.01)).shape == (0,)
    if every.name != "numpy":
        with pytest.raises(InputError) as error:
            every.params(env, count=-1)
        _one_line(error, "count", ">= 0", "-1")


# -- what is refused --------------------------------------------------------------------------------


@pytest.mark.parametrize("dt_value", [0.0, -0.01, math.inf, math.nan, True])
def test_a_bad_time_step_is_refused(every: Backend, dt_value: float) -> None:
    """Refuse a time step that is not finite and > 0 (or a bool) with one InputError line naming dt."""
    ops = every.ops()
    params = every.params(de.PerformanceEnvelope(max_effort=1.0), count=4)
    with pytest.raises(InputError, match="dt") as error:
        ops.clamp_effort_implicit(params, 1.0, 0.0, 1.0, dt_value)
    _one_line(error, "dt:", "> 0 and finite", repr(dt_value))


def test_bad_params_and_dtype_are_refused(port: Backend) -> None:
    """Refuse parameters of another type and a non-float impulse dtype with InputError."""
    ops = port.module
    with pytest.raises(InputError, match="params"):
        ops.clamp_effort(1.0, 0.0, 1.0)
    with pytest.raises(InputError, match="dtype"):
        ops.clamp_drive_impulse(0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, dtype=np.int32)


def test_bad_values_are_refused_naming_the_value(port: Backend) -> None:
    """Refuse negative, infinite and unit-less values and shapes that do not broadcast in from_values."""
    for values, words in [
        ({"max_effort": [1.0, -1.0]}, ("max_effort", "-1.0", ">= 0")),
        ({"max_effort": 1.0, "speed_effort_gradient": [0.0, -1.0]}, ("speed_effort_gradient", "-1.0")),
        ({"max_effort": np.inf}, ("max_effort", "inf", "finite")),
        ({"max_effort": 1.0, "max_actuator_velocity": "5 Hz"}, ("max_actuator_velocity", "angle")),
        ({"max_effort": [1.0, 2.0], "speed_effort_gradient": [0.1, 0.2, 0.3]}, ("broadcast", "(2,)", "(3,)")),
    ]:
        with pytest.raises(InputError) as error:
            port.values(**values)
        _one_line(error, "from_values", *words)


def test_a_none_value_is_named_as_none_not_nan(port: Backend) -> None:
    """``max_effort=None`` (alone or in a list) was read as NaN and reported as ``max_effort = nan``."""
    for values, written in [
        ({"max_effort": None}, "max_effort = None"),
        ({"max_effort": [3.0, None]}, "max_effort = [3.0, None]"),
        ({"max_effort": 1.0, "max_actuator_velocity": None}, "max_actuator_velocity = None"),
    ]:
        with pytest.raises(InputError) as error:
            port.values(**values)
        _one_line(error, "from_values", written, "expected SI numbers or strings with units")


def test_shapes_that_do_not_broadcast_are_named(backend: Backend) -> None:
    """Refuse states whose shapes do not broadcast with the parameters, one line naming both shapes."""
    ops = backend.module
    params = backend.params(de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0), count=5)
    five, three = backend.upload([np.zeros(5, dtype=np.float32), np.zeros(3, dtype=np.float32)])
    implicit = "clamp_effort_implicit"
    for call, name, where in [
        (lambda: ops.clamp_effort(params, three, five), "effort", "clamp_effort"),
        (lambda: ops.clamp_effort(params, 1.0, three), "velocity", "clamp_effort"),
        (lambda: ops.effort_limit(params, three), "velocity", "effort_limit"),
        (lambda: ops.clamp_effort_implicit(params, five, five, three, 0.01), "response", implicit),
    ]:
        with pytest.raises(InputError) as error:
            call()
        _one_line(error, name, "(5,)", "(3,)")
        if backend.name == "torch":  # torch broadcasts states and names the op; Warp wants (N,) arrays
            _one_line(error, where, "broadcast")


def test_numpy_shapes_that_do_not_broadcast_are_named() -> None:
    """The reference names a shape mismatch as the ports do (it raised NumPy's bare ValueError)."""
    env = de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0)
    five, three = np.zeros(5), np.zeros(3)
    implicit = "clamp_effort_implicit"
    for call, where, named in [
        (lambda: de.clamp_effort(env, three, five), "clamp_effort", ("effort=(3,)", "velocity=(5,)")),
        (lambda: de.clamp_effort_implicit(env, five, five, three, 0.01), implicit, ("response=(3,)",)),
        (lambda: de.clamp_drive_impulse(three, five, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0), "clamp_drive_impulse",
         ("joint_vel0=(3,)", "drive_impulse0=(5,)")),
    ]:  # fmt: skip
        with pytest.raises(InputError) as error:
            call()
        _one_line(error, f"{where}: shapes do not broadcast", *named)


def test_impulse_shapes_that_do_not_broadcast_are_named(port: Backend) -> None:
    """Refuse impulse arguments whose shapes do not broadcast, naming each (torch: was a RuntimeError)."""
    with pytest.raises(InputError) as error:
        port.module.clamp_drive_impulse(np.zeros(3), np.zeros(4), 1.0, 1.0, 1.0, 1.0, 0.0, 0.0)
    _one_line(error, "clamp_drive_impulse: shapes do not broadcast", "joint_vel0=(3,)", "drive_impulse0=(4,)")

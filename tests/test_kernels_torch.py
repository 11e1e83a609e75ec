"""PyTorch-only behaviour of drive_envelope.torch: dtypes, autograd, float64 impulses, from_values.

What every backend does (the impulse and effort ops against the NumPy reference on the CPU and
CUDA, NaN, zero DOFs, refused input, one signature per name) is tests/test_kernels_backends.py,
with the backend a parameter. Tolerances: ``clamp_drive_impulse`` is compared bit for bit (the
compiled kernel with the eager port, float64 tensors with the float64 reference).

torch is opt-in (see docs/kernels.md): these tests skip when it is not installed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from _kernel_vectors import edge_impulse_args, physx_golden, random_impulse_args
from drive_envelope.errors import InputError

pytestmark = pytest.mark.torch


def _same(a: Any, b: Any) -> bool:
    return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))


def _tensors(args: list[np.ndarray], device: str) -> list[Any]:
    import torch

    return [torch.from_numpy(a).to(device) for a in args]


@pytest.mark.slow
def test_fused_clamp_drive_impulse_matches_eager_port() -> None:
    """Give the eager port's numbers from the torch.compile'd kernel (edge cases, PhysX golden, random)."""
    import drive_envelope.torch as dt

    golden = physx_golden()
    parts = [edge_impulse_args(), random_impulse_args(2000), *([golden[0]] if golden else [])]
    args = [np.concatenate([p[k] for p in parts]) for k in range(8)]
    try:
        fused = dt.fused_clamp_drive_impulse(*_tensors(args, "cpu")).numpy()  # the default mode
    except Exception as exc:  # torch.compile needs a working C++ toolchain; report, don't fail
        pytest.skip(f"torch.compile unavailable here: {type(exc).__name__}: {exc}")
    assert _same(fused, de.clamp_drive_impulse(*args, dtype=np.float32))


def test_clamp_drive_impulse_float64_matches_reference() -> None:
    """Match the float64 reference bit for bit when asked for float64 (NumPy inputs accepted)."""
    import drive_envelope.torch as dt

    args = [a.astype(np.float64) for a in random_impulse_args()]
    assert _same(dt.clamp_drive_impulse(*args, dtype=np.float64).numpy(), de.clamp_drive_impulse(*args))
    exact = dt.clamp_drive_impulse(*args, dtype=np.float64, physx_exact=True).numpy()
    assert _same(exact, de.clamp_drive_impulse(*args, physx_exact=True))


def test_explicit_ops_broadcast_scalars_and_arrays() -> None:
    """Broadcast scalar and per-DOF arguments either way round, like the reference."""
    import torch

    import drive_envelope.torch as dt

    caps = torch.tensor([1.0, 2.0, 3.0])
    per_dof = dt.EnvelopeTensors.from_values(
        max_effort=caps, max_actuator_velocity=4.0, speed_effort_gradient=1.0
    )
    np.testing.assert_array_equal(dt.effort_limit(per_dof, 0.5), [1.0, 2.0, 3.0])
    box = dt.EnvelopeTensors.from_values(max_effort=2.0)
    np.testing.assert_array_equal(dt.clamp_effort(box, 5.0, torch.zeros(3)), [2.0, 2.0, 2.0])
    np.testing.assert_array_equal(dt.clamp_effort(box, torch.tensor([5.0, -5.0]), 0.0), [2.0, -2.0])
    caps_only = dt.EnvelopeTensors.from_values(max_effort=caps)
    np.testing.assert_array_equal(dt.clamp_effort(caps_only, -5.0, 1.0), [-1.0, -2.0, -3.0])


def test_envelope_tensors_build_and_validate() -> None:
    """Build EnvelopeTensors from envelopes or values (units read once); refuse mixed dtypes."""
    import torch

    import drive_envelope.torch as dt

    env = de.PerformanceEnvelope(max_effort=3.0, max_actuator_velocity=4.0)
    one = dt.EnvelopeTensors.from_envelopes(env)
    assert one.shape == () and one.dtype == torch.float32
    assert dt.EnvelopeTensors.from_envelopes(env, count=5).shape == (5,)
    listed = dt.EnvelopeTensors.from_envelopes(
        [env, de.PerformanceEnvelope(max_effort=1.0)], dtype=torch.float64
    )
    assert listed.max_effort.tolist() == [3.0, 1.0] and listed.max_actuator_velocity[1] == np.inf
    grid = dt.EnvelopeTensors.from_values(
        max_effort=[[1.0, 2.0, 3.0]],
        max_actuator_velocity="60 rpm",
        speed_effort_gradient=["0.5 rad/s/(N*m)", 0.5, 1],
    )
    assert grid.shape == (1, 3)
    assert float(grid.max_actuator_velocity) == pytest.approx(2.0 * np.pi)
    assert dt.effort_limit(grid, torch.zeros(4, 3)).shape == (4, 3)
    # bad values: test_kernels_backends.py::test_bad_values_are_refused_naming_the_value
    with pytest.raises(InputError, match="one dtype"):
        dt.EnvelopeTensors(
            max_effort=torch.zeros(2),
            max_actuator_velocity=torch.zeros(2, dtype=torch.float64),
            velocity_dependent_resistance=torch.zeros(2),
            speed_effort_gradient=torch.zeros(2),
        )


# API findings of a new user (issue 23): from_values keeps the tensor and its graph, dt as a host number

ENV = de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0, speed_effort_gradient=0.5)


def test_torch_from_values_keeps_the_tensor_and_its_gradient() -> None:
    torch = pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort

    m = torch.tensor(12.0, requires_grad=True)
    params = EnvelopeTensors.from_values(max_effort=m, max_actuator_velocity=10.0)
    assert params.max_effort is m
    out = clamp_effort(params, torch.tensor([20.0, 5.0]), torch.tensor([1.0, 1.0]))
    assert out.requires_grad
    out[0].backward()  # clipped with R = 0: the result is max_effort itself
    assert m.grad is not None and m.grad.item() == 1.0
    m.grad = None
    clamp_effort(params, torch.tensor(5.0), torch.tensor(1.0)).backward()  # inside: no dependence
    assert m.grad is not None and m.grad.item() == 0.0


def test_torch_from_values_casts_with_the_graph_and_still_validates() -> None:
    torch = pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort

    m = torch.tensor([12.0, 3.0], dtype=torch.float64, requires_grad=True)
    params = EnvelopeTensors.from_values(max_effort=m, dtype=torch.float32)
    assert params.max_effort.dtype == torch.float32 and params.max_effort.requires_grad
    clamp_effort(params, torch.tensor([20.0, -5.0]), torch.tensor([0.0, 1.0])).sum().backward()
    assert m.grad is not None and m.grad.tolist() == [1.0, -1.0]
    bad = torch.tensor([-1.0], requires_grad=True)
    with pytest.raises(InputError, match=r"from_values: max_effort = -1\.0; expected >= 0"):
        EnvelopeTensors.from_values(max_effort=bad)
    assert bad.grad is None and bad.grad_fn is None


def test_torch_dt_tensor_is_refused_naming_the_expected_type() -> None:
    torch = pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort_implicit

    params = EnvelopeTensors.from_envelopes(ENV)
    with pytest.raises(
        InputError, match=r"^dt: expected a Python float time step \[s\], got a torch\.Tensor"
    ):
        clamp_effort_implicit(params, 5.0, 0.0, 1.0, torch.tensor(0.01))
    with pytest.raises(
        InputError, match=r"^dt: expected a Python float time step \[s\], got a numpy\.ndarray"
    ):
        clamp_effort_implicit(params, 5.0, 0.0, 1.0, np.array(0.01))
    with pytest.raises(InputError, match=r"^dt: expected a time step > 0 and finite \[s\], got 0\.0"):
        clamp_effort_implicit(params, 5.0, 0.0, 1.0, 0.0)


def test_numpy_and_torch_take_a_numpy_integer_dt() -> None:
    torch = pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort_implicit

    expected = float(de.clamp_effort_implicit(ENV, 5.0, 1.0, 0.01, 1))
    assert float(de.clamp_effort_implicit(ENV, 5.0, 1.0, 0.01, np.int64(1))) == expected
    got = clamp_effort_implicit(
        EnvelopeTensors.from_envelopes(ENV, dtype=torch.float64), 5.0, 1.0, 0.01, np.int64(1)
    )
    assert float(got) == pytest.approx(expected)


# torch dtypes and autograd, shapes that do not broadcast under autograd (kernel findings 1 and 3)

AUTOGRAD_ENV = de.PerformanceEnvelope(
    max_effort=12.0, max_actuator_velocity=10.0, velocity_dependent_resistance=0.1, speed_effort_gradient=0.5
)


def _torch() -> Any:
    pytest.importorskip("torch")
    import drive_envelope.torch as dt

    return dt


def _same_no_nan(a: Any, b: Any) -> bool:
    """Equal element for element (-0.0 equals 0.0), no NaN allowed on either side."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return bool(np.array_equal(a, b)) and not np.isnan(a).any()


def _one_line(error: pytest.ExceptionInfo[InputError], *parts: str) -> None:
    text = str(error.value)
    assert "\n" not in text
    for part in parts:
        assert part in text, (part, text)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_torch_results_have_the_envelope_dtype(dtype: str) -> None:
    """Return the EnvelopeTensors' dtype from every effort-level op (float64 is no longer lost)."""
    dt = _torch()
    import torch

    kind = getattr(torch, dtype)
    params = dt.EnvelopeTensors.from_envelopes(AUTOGRAD_ENV, device="cpu", dtype=kind)
    x = torch.tensor([5.0, 20.0], dtype=kind)
    v = torch.tensor([1.0, -3.0], dtype=kind)
    assert dt.clamp_effort(params, x, v).dtype == kind
    assert dt.effort_limit(params, v).dtype == kind
    assert dt.clamp_effort_implicit(params, x, v, torch.ones(2, dtype=kind), 0.01).dtype == kind
    # host values are read in the envelope's dtype
    assert dt.clamp_effort(params, [5.0, 20.0], np.array([1.0, -3.0])).dtype == kind
    if kind == torch.float64:  # the float64 reference's numbers, bit for bit
        assert _same_no_nan(
            dt.clamp_effort(params, x, v), de.clamp_effort(AUTOGRAD_ENV, x.numpy(), v.numpy())
        )
        implicit = dt.clamp_effort_implicit(params, x, v, 2.0, 0.01)
        np.testing.assert_allclose(
            implicit, de.clamp_effort_implicit(AUTOGRAD_ENV, x.numpy(), v.numpy(), 2.0, 0.01)
        )


@pytest.mark.parametrize("bad", ["float64", "float16", "bfloat16", "int64", "bool"])
def test_torch_refuses_a_tensor_of_another_dtype(bad: str) -> None:
    """Refuse a tensor whose dtype is not the envelope's, naming the argument and both dtypes."""
    dt = _torch()
    import torch

    params = dt.EnvelopeTensors.from_envelopes(AUTOGRAD_ENV, device="cpu")  # float32
    wrong = torch.ones(2).to(getattr(torch, bad))
    good = torch.ones(2)
    for call, name in [
        (lambda: dt.clamp_effort(params, wrong, good), "effort"),
        (lambda: dt.clamp_effort(params, good, wrong), "velocity"),
        (lambda: dt.effort_limit(params, wrong), "velocity"),
        (lambda: dt.clamp_effort_implicit(params, wrong, good, good, 0.01), "requested_effort"),
        (lambda: dt.clamp_effort_implicit(params, good, good, wrong, 0.01), "response"),
        (lambda: dt.clamp_effort_implicit(params, good, good, good, 0.01, wrong), "applied_effort"),
    ]:
        with pytest.raises(InputError) as error:
            call()
        _one_line(error, f"{name}:", f"torch.{bad}", "torch.float32")
        if getattr(torch, bad).is_floating_point:
            _one_line(error, f"dtype=torch.{bad}")


def test_torch_explicit_clamp_differentiates() -> None:
    """Let autograd through the explicit clamp: d/d effort 1 inside, 0 clipped; the same numbers."""
    dt = _torch()
    import torch

    params = dt.EnvelopeTensors.from_envelopes(AUTOGRAD_ENV, device="cpu")
    v = torch.tensor([0.0, 0.0, 2.0, -2.0, 11.0, math.nan])
    effort = torch.tensor([5.0, 20.0, -20.0, 3.0, 1.0, 1.0], requires_grad=True)
    clamped = dt.clamp_effort(params, effort, v)  # was: RuntimeError: maximum(): functions with out=...
    clamped.sum().backward()
    assert effort.grad is not None
    assert effort.grad.tolist() == [1.0, 0.0, 0.0, 1.0, 0.0, 0.0]
    with torch.no_grad():
        assert torch.equal(clamped, dt.clamp_effort(params, effort, v))
    # the reported call
    x = torch.tensor([5.0, 20.0], requires_grad=True)
    dt.clamp_effort(params, x, torch.tensor([1.0, 1.0])).sum().backward()
    assert x.grad is not None and x.grad.tolist() == [1.0, 0.0]


def test_torch_gradients_through_velocity_and_parameters() -> None:
    """Differentiate w.r.t. velocity and envelope tensors (float64 gradcheck), finite at non-finite v."""
    dt = _torch()
    import torch

    def clip(max_e: Any, max_v: Any, resist: Any, grad: Any, v: Any) -> Any:
        params = dt.EnvelopeTensors(
            max_effort=max_e,
            max_actuator_velocity=max_v,
            velocity_dependent_resistance=resist,
            speed_effort_gradient=grad,
        )
        return dt.clamp_effort(params, torch.tensor([30.0, -30.0, 30.0], dtype=torch.float64), v)

    # smooth points: eq. 1 binds at |v| = 1, eq. 2 at |v| = 6 and 9 (away from every kink)
    args = [
        torch.tensor(x, dtype=torch.float64, requires_grad=True)
        for x in ([12.0] * 3, [10.0] * 3, [0.1] * 3, [0.5] * 3, [1.0, -6.0, 9.0])
    ]
    assert torch.autograd.gradcheck(clip, args)
    # a NaN or infinite velocity, or G = 0 (a division by zero in the speed line): finite gradients
    params = [torch.tensor([12.0, 12.0, 12.0], dtype=torch.float64, requires_grad=True) for _ in range(2)]
    params += [torch.zeros(3, dtype=torch.float64, requires_grad=True) for _ in range(2)]
    params[1] = torch.tensor([10.0, math.inf, 10.0], dtype=torch.float64, requires_grad=True)
    v = torch.tensor([math.nan, math.inf, 3.0], dtype=torch.float64, requires_grad=True)
    out = clip(*params, v)
    out.sum().backward()
    for tensor in [*params, v]:
        assert tensor.grad is not None and torch.isfinite(tensor.grad).all()
    assert out.tolist() == [0.0, -12.0, 12.0]


def test_torch_no_grad_path_records_nothing() -> None:
    """Run in place without a graph where nothing requires grad (also under inference_mode)."""
    dt = _torch()
    import torch

    params = dt.EnvelopeTensors.from_envelopes(AUTOGRAD_ENV, count=4)
    out = dt.clamp_effort(params, torch.full((4,), 20.0), torch.zeros(4))
    assert out.grad_fn is None and out.tolist() == [12.0] * 4
    with torch.inference_mode():
        assert dt.clamp_effort(params, torch.full((4,), 20.0), torch.zeros(4)).tolist() == [12.0] * 4


def test_torch_implicit_clamp_accepts_tensors_requiring_grad() -> None:
    """Run the implicit clamp on a request that requires grad (no out= there), float64 kept."""
    dt = _torch()
    import torch

    params = dt.EnvelopeTensors.from_envelopes(AUTOGRAD_ENV, dtype=torch.float64)
    request = torch.tensor([5.0, 50.0], dtype=torch.float64, requires_grad=True)
    effort = dt.clamp_effort_implicit(params, request, torch.zeros(2, dtype=torch.float64), 2.0, 0.01)
    effort.sum().backward()
    assert effort.dtype == torch.float64 and request.grad is not None


def test_torch_names_shapes_that_do_not_broadcast_under_autograd() -> None:
    """Name both shapes when a state that requires grad does not broadcast (the recording path).

    The other ops and states: test_kernels_backends.py::test_shapes_that_do_not_broadcast_are_named.
    """
    dt = _torch()
    import torch

    params = dt.EnvelopeTensors.from_envelopes(AUTOGRAD_ENV, count=5)
    five, three = torch.zeros(5), torch.zeros(3)
    with pytest.raises(InputError) as error:
        dt.clamp_effort(params, five, three.requires_grad_(True))
    _one_line(error, "clamp_effort", "(5,)", "(3,)", "broadcast")

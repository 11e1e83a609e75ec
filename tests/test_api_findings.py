"""Regression tests for API findings of a new user: autograd through ``EnvelopeTensors.from_values``,
``dt`` as a host number in every backend, the sign of a let-go zero, and Newton's wrong-argument
errors (a finalized builder, a non-builder, a non-path source, a non-model).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

ENV = de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0, speed_effort_gradient=0.5)
BOX = de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0)  # R = G = 0: |v| > 10 gives 0
EFFORTS = (5.0, -5.0, 0.0, -0.0, 30.0, -30.0, math.inf, -math.inf, math.nan)
VELOCITIES = (0.0, 3.0, -3.0, 20.0, -20.0, math.nan, math.inf, -math.inf)


def _grid(repeat: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Every effort at every velocity, repeated so that SIMD lanes and scalar tails both see each."""
    effort, velocity = (a.ravel() for a in np.meshgrid(EFFORTS, VELOCITIES))
    return np.tile(effort, repeat), np.tile(velocity, repeat)


# -- 1. torch: from_values keeps the tensor and its graph -------------------------------------------


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


# -- 2. dt: a host number in every backend; a tensor is refused with a clear line -------------------


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


def test_numpy_and_torch_take_a_numpy_integer_dt() -> None:
    torch = pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort_implicit

    expected = float(de.clamp_effort_implicit(ENV, 5.0, 1.0, 0.01, 1))
    assert float(de.clamp_effort_implicit(ENV, 5.0, 1.0, 0.01, np.int64(1))) == expected
    got = clamp_effort_implicit(
        EnvelopeTensors.from_envelopes(ENV, dtype=torch.float64), 5.0, 1.0, 0.01, np.int64(1)
    )
    assert float(got) == pytest.approx(expected)


def test_every_backend_refuses_a_tensor_dt() -> None:
    torch = pytest.importorskip("torch")
    with pytest.raises(InputError, match=r"^dt: "):
        de.clamp_effort_implicit(ENV, 5.0, 0.0, 1.0, torch.tensor(0.01))  # type: ignore[arg-type]
    pytest.importorskip("warp")
    import drive_envelope.warp as dw

    params = dw.EnvelopeArrays.from_envelopes(ENV, count=1, device="cpu")
    with pytest.raises(InputError, match=r"^dt: "):
        dw.clamp_effort_implicit(params, 5.0, 0.0, 1.0, torch.tensor(0.01))


# -- 3. the sign of a let-go zero: +0.0 in every backend ---------------------------------------------


@pytest.mark.parametrize("envelope", [ENV, BOX], ids=["line", "box"])
def test_numpy_let_go_is_positive_zero(envelope: de.PerformanceEnvelope) -> None:
    for velocity in (math.nan, math.inf, -math.inf, 20.0):
        for effort in (5.0, -5.0, math.inf, -math.inf, math.nan):
            got = de.clamp_effort(envelope, effort, velocity)  # L = 0: NaN, infinite or beyond v_max
            assert got == 0.0 and not np.signbit(got), (effort, velocity, got)
    assert np.signbit(de.clamp_effort(envelope, -0.0, 1.0))  # inside the limit an effort is kept as is


@pytest.mark.parametrize("envelope", [ENV, BOX], ids=["line", "box"])
def test_backends_agree_on_every_zero_sign(envelope: de.PerformanceEnvelope) -> None:
    effort, velocity = _grid()
    reference = de.clamp_effort(envelope, effort, velocity)
    let_go = envelope.effort_limit(velocity) == 0.0
    assert not np.signbit(reference[let_go]).any()
    torch = pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort

    params = EnvelopeTensors.from_envelopes(envelope, dtype=torch.float64)
    eager = clamp_effort(params, torch.tensor(effort), torch.tensor(velocity)).numpy()
    tracked_effort = torch.tensor(effort, requires_grad=True)
    tracked = clamp_effort(params, tracked_effort, torch.tensor(velocity)).detach().numpy()
    for got in (eager, tracked):
        np.testing.assert_array_equal(got, reference)
        np.testing.assert_array_equal(np.signbit(got), np.signbit(reference))
    pytest.importorskip("warp")
    import drive_envelope.warp as dw

    arrays = dw.EnvelopeArrays.from_envelopes(envelope, count=effort.size, device="cpu")
    warp = dw.clamp_effort(arrays, effort.astype(np.float32), velocity.astype(np.float32)).numpy()
    np.testing.assert_array_equal(warp, reference.astype(np.float32))
    np.testing.assert_array_equal(np.signbit(warp), np.signbit(reference))


# -- 4. Newton: wrong arguments are one-line InputErrors ----------------------------------------------


def test_newton_add_envelopes_refuses_a_finalized_builder(tmp_path: Path) -> None:
    newton = pytest.importorskip("newton")
    from drive_envelope.newton import add_envelopes_from_usd

    builder = newton.ModelBuilder()
    builder.finalize(device="cpu")
    with pytest.raises(
        InputError, match=r"builder: already finalized.*call add_envelopes_from_usd before finalize"
    ):
        add_envelopes_from_usd(builder, tmp_path / "robot.usda")


def test_newton_add_envelopes_takes_a_builder_with_worlds(tmp_path: Path) -> None:
    """``begin_world``/``end_world`` are not taken for ``finalize`` (the check reads past them)."""
    newton = pytest.importorskip("newton")
    from drive_envelope.newton import add_envelopes_from_usd

    builder = newton.ModelBuilder()
    builder.begin_world()
    builder.end_world()
    with pytest.raises(InputError, match=r"missing\.usda: no such file"):
        add_envelopes_from_usd(builder, tmp_path / "missing.usda")


def test_newton_add_envelopes_names_wrong_argument_types(tmp_path: Path) -> None:
    newton = pytest.importorskip("newton")
    from drive_envelope.newton import add_envelopes_from_usd

    with pytest.raises(InputError, match=r"builder: expected a newton\.ModelBuilder, got NoneType"):
        add_envelopes_from_usd(None, tmp_path / "robot.usda")
    with pytest.raises(InputError, match=r"source: expected a USD file path .* or a Usd\.Stage, got int"):
        add_envelopes_from_usd(newton.ModelBuilder(), 42)


def test_newton_bias_and_clamp_name_wrong_argument_types() -> None:
    newton = pytest.importorskip("newton")
    import warp as wp

    from drive_envelope.newton import BiasForce, resolve_envelope_arguments

    with pytest.raises(
        InputError, match=r"BiasForce: model: expected a finalized newton\.Model, got ModelBuilder"
    ):
        BiasForce(newton.ModelBuilder())
    with pytest.raises(InputError, match=r"BiasForce: model: expected a finalized newton\.Model, got int"):
        BiasForce(3)
    with pytest.raises(InputError, match=r"args: expected a dict of envelope arguments.*got float"):
        resolve_envelope_arguments(12.0)  # type: ignore[arg-type]
    from drive_envelope.newton import ClampingPerformanceEnvelope

    with pytest.raises(InputError, match=r"max_effort: expected a float32 wp\.array.*got float"):
        ClampingPerformanceEnvelope(12.0)
    builder = newton.ModelBuilder()
    body = builder.add_link(mass=1.0, inertia=wp.mat33(np.eye(3) * 0.01))
    joint = builder.add_joint_revolute(-1, body, axis=(0.0, 0.0, 1.0))
    builder.add_articulation([joint])
    model = builder.finalize(device="cpu")
    bias = BiasForce(model)
    with pytest.raises(InputError, match=r"BiasForce\.compute: state: expected a newton\.State, got Model"):
        bias.compute(model)
    with pytest.raises(InputError, match=r"external: expected None or a float32 wp\.array.*got list"):
        bias.compute(model.state(), external=[0.0])

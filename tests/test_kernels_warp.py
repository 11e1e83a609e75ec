"""Warp-only behaviour of drive_envelope.warp: the ``@wp.func`` blocks, ``out=`` buffers, its refusals.

What every backend does (the impulse and effort ops against the NumPy reference on Warp's CPU
device and CUDA, NaN, zero DOFs, refused input, one signature per name) is
tests/test_kernels_backends.py, with the backend a parameter. Tolerance: the user kernel's numbers
are the launch wrappers' bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

pytestmark = pytest.mark.warp


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal element for element, NaN matching NaN, -0.0 matching 0.0."""
    return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))


def _upload(args: list[np.ndarray], device: str) -> list[object]:
    import warp as wp

    return [wp.array(a, dtype=wp.float32, device=device) for a in args]


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


def test_an_out_that_is_not_a_warp_array_is_refused() -> None:
    """A NumPy array or a torch tensor as ``out`` is one line: it was uploaded, the copy written.

    The caller's array kept its old values while the result went to a new Warp array: a
    silently unwritten buffer.
    """
    import drive_envelope.warp as dw

    params = dw.EnvelopeArrays.from_values(max_effort=[1.0, 2.0, 3.0])
    buffer = np.full(3, -7.0, dtype=np.float32)
    with pytest.raises(
        InputError,
        match=r"out: expected a float32 Warp array of shape \(3,\) to write into, got a numpy.ndarray",
    ):
        dw.clamp_effort(params, [5.0, -5.0, 0.5], 0.0, out=buffer)
    with pytest.raises(InputError, match=r"got a numpy.ndarray"):
        dw.effort_limit(params, 0.0, out=buffer)
    with pytest.raises(InputError, match=r"got a numpy.ndarray"):
        dw.clamp_effort_implicit(params, [5.0, -5.0, 0.5], 0.0, 20.0, 0.01, out=buffer)
    np.testing.assert_array_equal(buffer, [-7.0, -7.0, -7.0])


def test_bad_input_raises_input_error() -> None:
    """Reject float64, an infinite cap and arrays of mixed shapes with InputError.

    A bad dt, states and impulse arguments of the wrong shapes, negative values:
    test_kernels_backends.py, every backend.
    """
    import warp as wp

    import drive_envelope.warp as dw

    with pytest.raises(InputError, match="dtype"):
        dw.clamp_drive_impulse(0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, dtype=np.float64)
    with pytest.raises(InputError, match="max_effort"):
        dw.EnvelopeArrays.from_values(max_effort=np.inf, count=2)
    with pytest.raises(InputError, match="shapes differ"):
        dw.EnvelopeArrays(
            max_effort=wp.zeros(2, dtype=wp.float32),
            max_actuator_velocity=wp.zeros(3, dtype=wp.float32),
            velocity_dependent_resistance=wp.zeros(2, dtype=wp.float32),
            speed_effort_gradient=wp.zeros(2, dtype=wp.float32),
        )


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
    """Build empty EnvelopeArrays from a count of 0, launch on them, write into an empty buffer.

    from_envelopes(count=0), from_values(max_effort=[]) and count -1: test_kernels_backends.py.
    """
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
        dw.EnvelopeArrays.from_values(max_effort=1.0, count=-2, device="cpu")
    _one_line(error, "count", ">= 0", "-2")

"""Newton's implicit effort mode with the envelope: gravity bias, several worlds, chained clamps, retune.

The reference is the envelope itself: in implicit mode a saturated drive's effort must equal the
envelope's limit ``L(v_end)`` at the velocity the step ENDS at (PhysX's semantics), within float32
rounding. The model is a gravity pendulum (1 kg at 0.3 m on a horizontal revolute axis), whose
gravity torque (2.94 N*m) is close to the 3 N*m cap, so a prediction that ignores gravity is
visibly wrong: without ``bias_force`` the effort misses ``L(v_end)`` by about 1e-2 N*m.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope.errors import InputError

pytestmark = pytest.mark.newton

ENVELOPE = {
    "max_effort": 3.0,
    "max_actuator_velocity": 6.0,
    "velocity_dependent_resistance": 0.05,
    "speed_effort_gradient": 1.0,
}
GRAVITY = (0.0, 0.0, -9.81)
DT = 0.01


def _pendulum(worlds: int = 1, clamping: list[tuple[Any, dict[str, float]]] | None = None) -> Any:
    """A pendulum per world: DrivePD (velocity target far above the envelope) clamped by the envelope."""
    import newton
    import warp as wp
    from newton.actuators import DrivePD

    from drive_envelope.newton import ClampingPerformanceEnvelope

    builder = newton.ModelBuilder(gravity=GRAVITY)
    link = builder.add_link(mass=1.0, com=wp.vec3(0.0, 0.3, 0.0), inertia=wp.mat33(np.eye(3) * 0.01))
    joint = builder.add_joint_revolute(
        parent=-1, child=link, axis=newton.Axis.X, target_ke=0.0, target_kd=0.0
    )
    builder.add_articulation([joint])
    chain = clamping if clamping is not None else [(ClampingPerformanceEnvelope, ENVELOPE)]
    builder.add_actuator(DrivePD, index=0, kp=0.0, kd=10.0, clamping=chain)
    if worlds > 1:
        scene = newton.ModelBuilder(gravity=GRAVITY)
        scene.replicate(builder, worlds)
        builder = scene
    return builder.finalize(device="cpu")


def _implicit(model: Any) -> tuple[Any, Any]:
    """Switch the model's actuator to implicit mode; returns (model, its JointSpaceResponse)."""
    from newton.actuators import Actuator, JointSpaceResponse

    response = JointSpaceResponse(model)
    options = Actuator.ImplicitOptions(residual_tol=1e-10, update_tol=1e-10, max_iters=32)
    model.actuators[0].set_effort_mode_implicit(response=response, options=options)
    return model, response


def _run(implicit: tuple[Any, Any], *, use_bias: bool, steps: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """Step the model in implicit mode; returns (efforts, end-of-step velocities), ``(steps, dofs)``."""
    import newton

    from drive_envelope.newton import BiasForce

    model, response = implicit
    actuator = model.actuators[0]
    solver = newton.solvers.SolverFeatherstone(model)
    state, next_state, control = model.state(), model.state(), model.control()
    control.joint_target_qd.assign(np.full(model.joint_dof_count, 50.0, dtype=np.float32))
    bias = BiasForce(model)
    efforts, velocities = [], []
    for _ in range(steps):
        control.joint_f.zero_()
        response.refresh(state)
        actuator.step(state, control, dt=DT, bias_force=bias.compute(state) if use_bias else None)
        efforts.append(control.joint_f.numpy().copy())
        solver.step(state, next_state, control, None, DT)
        state, next_state = next_state, state
        velocities.append(state.joint_qd.numpy().copy())
    return np.array(efforts, dtype=np.float64), np.array(velocities, dtype=np.float64)


def _limit(envelope: dict[str, float], velocity: np.ndarray) -> np.ndarray:
    return de.PerformanceEnvelope(**envelope).effort_limit(velocity)


def test_bias_force_puts_the_gravity_pendulum_on_the_envelope() -> None:
    """Clamp at the true end-of-step velocity with the bias; miss L(v_end) by ~1e-2 N*m without it."""
    effort, velocity = _run(_implicit(_pendulum()), use_bias=True)
    assert np.all(effort[:, 0] > 2.9) and velocity[-1, 0] > 0.2  # driven up against gravity
    np.testing.assert_allclose(effort[:, 0], _limit(ENVELOPE, velocity[:, 0]), rtol=0, atol=1e-6)
    effort, velocity = _run(_implicit(_pendulum()), use_bias=False)
    assert np.abs(effort[:, 0] - _limit(ENVELOPE, velocity[:, 0])).max() > 5e-3


def test_bias_force_is_gravity_plus_coriolis() -> None:
    """Return g(q) + C(q, qd) qd: m*g*l*cos(q) on the pendulum, nothing from Coriolis on one DOF."""
    import newton

    from drive_envelope.newton import BiasForce

    model = _pendulum()
    state = model.state()
    state.joint_q.assign(np.array([0.4], dtype=np.float32))
    state.joint_qd.assign(np.array([2.0], dtype=np.float32))
    newton.eval_fk(model, state.joint_q, state.joint_qd, state)
    bias = BiasForce(model).compute(state).numpy()
    # the COM at 0.3 m along +Y turned by q about +X: gravity's torque about +X is -m*g*0.3*cos(q)
    assert bias[0] == pytest.approx(9.81 * 0.3 * np.cos(0.4), rel=1e-5)
    only_gravity = BiasForce(model, coriolis=False)
    assert only_gravity.coriolis is None
    assert only_gravity.compute(state).numpy()[0] == pytest.approx(bias[0], rel=1e-6)
    import warp as wp

    load = wp.array(np.array([0.5], dtype=np.float32), dtype=wp.float32, device="cpu")
    assert BiasForce(model).compute(state, external=load).numpy()[0] == pytest.approx(bias[0] - 0.5, rel=1e-5)
    with pytest.raises(InputError, match="external has shape"):
        BiasForce(model).compute(state, external=wp.zeros(3, dtype=wp.float32, device="cpu"))


def test_several_worlds_retuned_each_stay_on_their_own_envelope() -> None:
    """Retune the envelope per world after finalize; each world's effort is its own L(v_end)."""
    implicit = _implicit(_pendulum(worlds=3))
    model = implicit[0]
    clamp = model.actuators[0].clamping[0]
    retuned = {
        "max_effort": np.array([3.0, 3.5, 4.0], dtype=np.float32),
        "max_actuator_velocity": np.array([6.0, 1.0, 0.5], dtype=np.float32),
        "speed_effort_gradient": np.array([1.0, 0.2, 0.1], dtype=np.float32),
    }
    for name, values in retuned.items():
        getattr(clamp, name).assign(values)  # the packed parameter columns the solve reads
    effort, velocity = _run(implicit, use_bias=True, steps=150)
    for world in range(3):
        env = {**ENVELOPE, **{name: float(values[world]) for name, values in retuned.items()}}
        np.testing.assert_allclose(effort[:, world], _limit(env, velocity[:, world]), rtol=0, atol=2e-6)
    # the slow worlds run on their own speed lines (v = v_max - G*effort), world 0 on its effort line
    for world in (1, 2):
        on_line = (
            retuned["max_actuator_velocity"][world]
            - retuned["speed_effort_gradient"][world] * effort[-1, world]
        )
        assert velocity[-1, world] == pytest.approx(on_line, abs=1e-5)
    assert velocity[-1, 0] > velocity[-1, 1] > velocity[-1, 2] > 0.0


def test_chained_clamps_give_the_smaller_bound_at_the_end_of_step() -> None:
    """Chain ClampingMaxEffort (2 N*m) and the envelope: the effort is min(2, L(v_end)) every step."""
    from newton.actuators import ClampingMaxEffort

    from drive_envelope.newton import ClampingPerformanceEnvelope

    envelope = {**ENVELOPE, "max_actuator_velocity": 2.5, "speed_effort_gradient": 0.5}
    chain = [(ClampingMaxEffort, {"max_effort": 2.0}), (ClampingPerformanceEnvelope, envelope)]
    model = _pendulum(clamping=chain)
    model.joint_q.assign(np.array([-np.pi / 2], dtype=np.float32))  # hanging: gravity's torque is 0
    effort, velocity = _run(_implicit(model), use_bias=True, steps=120)
    expected = np.minimum(2.0, _limit(envelope, velocity[:, 0]))
    np.testing.assert_allclose(effort[:, 0], expected, rtol=0, atol=2e-6)
    assert np.any(expected < 2.0) and np.any(expected == 2.0)  # both clamps bind during the run


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

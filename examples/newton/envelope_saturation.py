"""A Newton joint saturating on the PhysX performance envelope (CPU device).

One link on a revolute joint (no gravity, no friction) is driven by Newton's PD drive towards a
target velocity far above what the motor can reach. ``ClampingPerformanceEnvelope`` bounds the
drive's effort by the envelope, so the effort falls along the torque-speed line as the joint speeds
up, and the joint ends on the no-load speed. Run twice: Newton's explicit effort mode (clamp at the
measured velocity) and its implicit mode (clamp at the end-of-step velocity, PhysX's semantics).
With this step (``dt/inertia`` times the slope of the speed-torque line above 1) the explicit
clamp overshoots the speed limit in one step and then coasts above it with zero effort; the
implicit clamp settles exactly on it, as PhysX does, and its effort equals ``L(v_end)``.

Run: ``python examples/newton/envelope_saturation.py`` (needs the ``newton`` extra).
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np


def build_model(inertia: float, envelope: dict[str, float], kd: float) -> Any:
    """One link on a revolute joint, PD drive clamped by the envelope (a ``newton.Model``)."""
    import newton
    import warp as wp
    from newton.actuators import DrivePD

    from drive_envelope.newton import ClampingPerformanceEnvelope

    builder = newton.ModelBuilder(gravity=(0.0, 0.0, 0.0))
    link = builder.add_link(
        inertia=wp.mat33(inertia, 0.0, 0.0, 0.0, inertia, 0.0, 0.0, 0.0, inertia), mass=1.0
    )
    joint = builder.add_joint_revolute(parent=-1, child=link, axis=newton.Axis.Z)
    builder.add_articulation([joint])
    builder.add_actuator(DrivePD, index=0, kp=0.0, kd=kd, clamping=[(ClampingPerformanceEnvelope, envelope)])
    return builder.finalize(device="cpu")


def run(implicit: bool, steps: int, dt: float, target_velocity: float) -> list[tuple[float, float, float]]:
    """Simulate ``steps`` steps; rows of (time [s], effort [N*m], end-of-step velocity [rad/s])."""
    import newton
    from newton.actuators import Actuator, JointSpaceResponse

    envelope = {
        "max_effort": 2.0,
        "max_actuator_velocity": 12.0,
        "velocity_dependent_resistance": 0.05,
        "speed_effort_gradient": 1.5,
    }
    model = build_model(inertia=0.01, envelope=envelope, kd=5.0)
    actuator = model.actuators[0]
    response = JointSpaceResponse(model)
    if implicit:
        # Newton stops its solve at an absolute residual of 1e-5 N*m*s by default, which would halt
        # the approach about 5e-4 rad/s short of the speed limit here; tighten it.
        options = Actuator.ImplicitOptions(residual_tol=1e-9, update_tol=1e-9)
        actuator.set_effort_mode_implicit(response=response, options=options)
    solver = newton.solvers.SolverFeatherstone(model)
    state_in, state_out, control = model.state(), model.state(), model.control()
    control.joint_target_qd.assign(np.array([target_velocity], dtype=np.float32))
    rows = []
    for step in range(steps):
        control.joint_f.zero_()
        response.refresh(state_in)
        actuator.step(state_in, control, dt=dt)
        solver.step(state_in, state_out, control, None, dt)
        state_in, state_out = state_out, state_in
        rows.append((step * dt + dt, float(control.joint_f.numpy()[0]), float(state_in.joint_qd.numpy()[0])))
    return rows


def main() -> None:
    from drive_envelope import PerformanceEnvelope

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=30, help="number of steps (default 30)")
    parser.add_argument("--dt", type=float, default=0.02, help="time step [s] (default 0.02)")
    args = parser.parse_args()
    env = PerformanceEnvelope(
        max_effort=2.0,
        max_actuator_velocity=12.0,
        velocity_dependent_resistance=0.05,
        speed_effort_gradient=1.5,
    )
    print(f"envelope: {env}")
    no_load = float(env.velocity_at_effort(np.zeros(1))[0])
    print(
        f"no-load speed {no_load:.3f} rad/s, stall effort {float(env.effort_limit(np.zeros(1))[0]):.3f} N*m"
    )
    for implicit in (False, True):
        rows = run(implicit, args.steps, args.dt, target_velocity=100.0)
        print(f"\n{'implicit' if implicit else 'explicit'} effort mode")
        print(f"{'t [s]':>7} {'effort [N*m]':>13} {'v_end [rad/s]':>14} {'L(v_end) [N*m]':>15}")
        for t, effort, velocity in rows[:: max(1, len(rows) // 8)] + rows[-1:]:
            limit = float(env.effort_limit(np.array([velocity]))[0])
            print(f"{t:7.3f} {effort:13.4f} {velocity:14.4f} {limit:15.4f}")
        final = rows[-1][2]
        print(f"final speed {final:.4f} rad/s ({final - no_load:+.2e} from the no-load speed)")


if __name__ == "__main__":
    main()

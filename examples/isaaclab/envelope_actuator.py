"""Isaac Lab's actuator machinery with the PhysX envelope: PerformanceEnvelopeActuator against DCMotor.

4096 environments each move one joint (0.05 kg*m^2, viscous friction 0.05 N*m*s/rad, no gravity)
with a PD position drive: out to 1.5 rad, then back to 0. The actuators are built the way Isaac
Lab's ``Articulation`` builds them and stepped the way it steps them (``ArticulationActions`` in,
joint efforts out), with the joint integrated semi-implicitly at 200 Hz as PhysX would with a joint
effort. Three actuators with one
torque-speed line (25 N*m, 10 rad/s no-load, 40 N*m stall):

* Isaac Lab's ``DCMotor`` (``saturation_effort = 40``, ``velocity_limit = 10``);
* ``PerformanceEnvelopeActuator`` with the same line (``speed_effort_gradient = 10 / 40``): equal
  while driving, but its braking effort shrinks with speed, as PhysX's envelope does;
* the same with its speed-torque line randomized per environment by the event term
  ``randomize_actuator_envelope`` (gradient scaled by U(0.7, 1.3)).

The envelope brakes less at speed, so its joints overshoot the return (0.26 rad against the DC
motor's 0.006). Without the joint's friction a joint that reached exactly 10 rad/s would never
slow down: the explicit clip at ``v = max_actuator_velocity`` allows no effort either way
(``docs/isaaclab.md``).

Run inside Isaac Lab (``./isaaclab.sh -p examples/isaaclab/envelope_actuator.py``), or with the PyPI
wheel installed ``--no-deps`` (the script then uses the test suite's set-up for the wheel's source
tree: ``tests/conftest.py``).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
INERTIA = 0.05
"""Joint inertia [kg*m^2]."""
VISCOUS = 0.05
"""Joint viscous friction [N*m*s/rad]: a real joint's, outside the actuator."""


def _import_isaaclab() -> None:
    """Make ``isaaclab.actuators`` importable: Isaac Lab itself, or the PyPI wheel's source tree."""
    try:
        if importlib.util.find_spec("isaaclab.actuators") is not None:
            return
    except ImportError:  # the PyPI wheel's bootstrapper imports isaacsim
        pass
    sys.path.insert(0, str(ROOT / "tests"))
    import conftest

    conftest._isaaclab_setup()


def build(cfg: Any, envs: int) -> Any:
    """The actuator as ``Articulation._process_actuators_cfg`` builds it for one joint (USD gains 0)."""
    import torch

    zeros = torch.zeros(envs, 1)
    return cfg.class_type(
        cfg=cfg,
        joint_names=["joint"],
        joint_ids=slice(None),
        num_envs=envs,
        device="cpu",
        stiffness=zeros,
        damping=zeros,
        effort_limit=torch.full((envs, 1), 1e9),
        velocity_limit=torch.full((envs, 1), 100.0),
    )


def run(actuator: Any, envs: int, steps: int, dt: float) -> tuple[Any, Any, Any]:
    """Step the joint as Isaac Lab's ``_apply_actuator_model`` + PhysX would; (position, velocity, effort)."""
    import torch
    from isaaclab.utils.types import ArticulationActions

    q, v = torch.zeros(envs, 1), torch.zeros(envs, 1)
    history = torch.zeros(3, steps, envs)
    for step in range(steps):
        target = torch.full((envs, 1), 1.5 if step < steps // 2 else 0.0)
        action = ArticulationActions(
            joint_positions=target,
            joint_velocities=torch.zeros(envs, 1),
            joint_efforts=torch.zeros(envs, 1),
            joint_indices=slice(None),
        )
        effort = actuator.compute(action, joint_pos=q, joint_vel=v).joint_efforts
        v = v + dt * (effort - VISCOUS * v) / INERTIA
        q = q + dt * v
        history[:, step] = torch.stack([q[:, 0], v[:, 0], effort[:, 0]])
    return history[0], history[1], history[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=4096)
    parser.add_argument("--seconds", type=float, default=1.6)
    args = parser.parse_args()
    _import_isaaclab()
    import torch
    from isaaclab.actuators import DCMotorCfg

    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg, randomize_actuator_envelope

    dt, steps = 1.0 / 200.0, round(args.seconds * 200.0)
    gains = {"joint_names_expr": ["joint"], "stiffness": 300.0, "damping": 5.0, "effort_limit": 25.0}
    line = {"max_actuator_velocity": 10.0, "speed_effort_gradient": 10.0 / 40.0}
    dc = build(DCMotorCfg(**gains, saturation_effort=40.0, velocity_limit=10.0), args.envs)
    envelope = build(PerformanceEnvelopeActuatorCfg(**gains, **line, clip="start_of_step"), args.envs)
    randomized = build(PerformanceEnvelopeActuatorCfg(**gains, **line, clip="start_of_step"), args.envs)
    torch.manual_seed(0)
    scene = SimpleNamespace(scene={"robot": SimpleNamespace(actuators={"joint": randomized})})
    randomize_actuator_envelope(
        scene,
        None,
        SimpleNamespace(name="robot", joint_ids=slice(None)),
        speed_effort_gradient_distribution_params=(0.7, 1.3),
    )
    print(f"{args.envs} envs, {steps} steps of {dt * 1e3:g} ms; 25 N*m cap, 10 rad/s no-load, 40 N*m stall")
    print(f"{'actuator':<22} {'peak speed':>10} {'peak braking':>13} {'overshoot':>10} {'final q':>8}")
    for name, actuator in (("DCMotor", dc), ("envelope", envelope), ("envelope, randomized", randomized)):
        q, v, effort = run(actuator, args.envs, steps, dt)
        back = steps // 2  # the return stroke: braking is effort against the motion
        braking = torch.where(effort[back:] * v[back:] < 0.0, effort[back:].abs(), torch.zeros(()))
        overshoot = (-q[back:]).max(dim=0).values  # past 0 on the way back [rad]
        print(
            f"{name:<22} {v.abs().max():>8.3f} rad/s {braking.max():>7.2f} N*m "
            f"{overshoot.mean():>6.3f} rad {q[-1].mean():>8.3f}"
        )
    top = run(randomized, args.envs, steps, dt)[1].abs().max(dim=0).values
    print(f"randomized gradient: peak speed {top.min():.3f} .. {top.max():.3f} rad/s over the envs")


if __name__ == "__main__":
    main()

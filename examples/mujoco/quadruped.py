"""A 12-DOF quadruped in MuJoCo, every joint driven through the ``drive_envelope.envelope`` plugin.

The robot is built with ``mujoco.MjSpec`` (SI units): a floating torso and four legs of three hinge
joints each (hip abduction, hip flexion, knee). Every joint gets a PhysX drive whose performance
envelope comes from a catalog datasheet: T-Motor AK80-6 at the hips, Harmonic Drive FHA-8C-50 at
the knees. Scripted fast squats ask the knees for more speed and torque than their motors have, so they
run along the envelope; the plot shows each joint's operating points over its envelope. The plugin
solves all 12 drives together each step (the legs are coupled through the torso), and the summary
counts, per joint, the samples outside the envelope (relative margin below -1e-6, the ``check``
command's rule) and the samples where the drive let go because something else pushed the joint past
its no-load speed (PhysX's over-speed release). Contacts are solved after the drives, so an impact
can still move a joint past its envelope for a step: those samples are counted too, never hidden.

Run from the repository root (after ``make setup``)::

    .venv/bin/python examples/mujoco/quadruped.py --plot docs/img/mujoco_quadruped.png

``--mjcf quadruped.xml`` also writes the model as MJCF (open it in MuJoCo's ``simulate`` viewer
after loading the plugin library, or with ``python -m mujoco.viewer``).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from drive_envelope import PerformanceEnvelope
from drive_envelope.datasheet import resolve_envelope

if TYPE_CHECKING:
    import mujoco

    from drive_envelope.analysis import JointCheck
    from drive_envelope.teststand import Trajectory

LEGS = {"fl": (0.22, 0.12), "fr": (0.22, -0.12), "hl": (-0.22, 0.12), "hr": (-0.22, -0.12)}
"""Leg name -> hip position (x, y) on the torso [m]."""
JOINTS = ("hip_abd", "hip_flex", "knee")
"""Joints of one leg, root to tip."""
DATASHEETS = {"hip_abd": "tmotor-ak80-6", "hip_flex": "tmotor-ak80-6", "knee": "harmonic-drive-fha-8c-50"}
"""Catalog actuator of each joint kind."""
GAINS = {"hip_abd": (60.0, 1.5), "hip_flex": (60.0, 1.5), "knee": (40.0, 1.0)}
"""(stiffness [N*m/rad], damping [N*m*s/rad]) of each joint kind."""
STAND = {"hip_abd": 0.0, "hip_flex": 0.6, "knee": -1.2}
"""Standing pose [rad]."""
TIMESTEP = 0.002
"""Simulation step [s]."""


def joint_names() -> list[str]:
    """The 12 joint names in actuator (and control) order: the hips of every leg, then the knees.

    Joints that share a motor and gains share one plugin instance, so they come in groups.
    """
    hips = [f"{leg}_{joint}" for leg in LEGS for joint in ("hip_abd", "hip_flex")]
    return hips + [f"{leg}_knee" for leg in LEGS]


def envelopes() -> dict[str, PerformanceEnvelope]:
    """Each joint's envelope, derived from its catalog datasheet."""
    by_kind = {kind: resolve_envelope(name) for kind, name in DATASHEETS.items()}
    return {name: by_kind[name.split("_", 1)[1]] for name in joint_names()}


def _add_leg(torso: Any, leg: str, x: float, y: float) -> None:
    import mujoco

    hinge = mujoco.mjtJoint.mjJNT_HINGE
    hip = torso.add_body(name=f"{leg}_hip", pos=[x, y, 0.0])
    hip.add_joint(name=f"{leg}_hip_abd", type=hinge, axis=[1, 0, 0], range=[-0.6, 0.6])
    # only the feet and the torso touch the floor; the links never collide with each other
    hip.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.04, 0, 0], mass=0.5, contype=0, conaffinity=0)
    thigh = hip.add_body(name=f"{leg}_thigh", pos=[0.0, 0.0, 0.0])
    thigh.add_joint(name=f"{leg}_hip_flex", type=hinge, axis=[0, 1, 0], range=[-1.5, 1.5])
    thigh.add_geom(
        type=mujoco.mjtGeom.mjGEOM_CAPSULE,
        fromto=[0, 0, 0, 0, 0, -0.2],
        size=[0.025, 0, 0],
        mass=0.6,
        contype=0,
        conaffinity=0,
    )
    shank = thigh.add_body(name=f"{leg}_shank", pos=[0.0, 0.0, -0.2])
    shank.add_joint(name=f"{leg}_knee", type=hinge, axis=[0, 1, 0], range=[-2.6, 0.0])
    shank.add_geom(
        type=mujoco.mjtGeom.mjGEOM_CAPSULE,
        fromto=[0, 0, 0, 0, 0, -0.2],
        size=[0.02, 0, 0],
        mass=0.3,
        contype=0,
        conaffinity=0,
    )
    shank.add_geom(
        type=mujoco.mjtGeom.mjGEOM_SPHERE, pos=[0, 0, -0.2], size=[0.03, 0, 0], mass=0.05, conaffinity=0
    )


def build_quadruped(
    actuators: Literal["plugin", "position"] = "plugin", *, fixed_base: bool = False
) -> mujoco.MjSpec:
    """The quadruped with plugin drives, or with MuJoCo's native position actuators (same gains,
    ``forcerange`` = +-max_effort) for comparison.

    Actuators (and their first controls, the target positions) follow :func:`joint_names`. With
    ``fixed_base`` the torso is welded in the air (no free joint, no contacts): the legs swing
    freely, coupled only through their own links.
    """
    import mujoco

    from drive_envelope.mujoco import add_drives

    spec = mujoco.MjSpec()
    spec.modelname = f"quadruped_{actuators}"
    spec.compiler.degree = False  # joint ranges below are in radians, like everything else here
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1], contype=0, conaffinity=1)
    torso = spec.worldbody.add_body(name="torso", pos=[0, 0, 0.42])
    if fixed_base:
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    else:
        torso.add_freejoint(name="root")
    torso.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.25, 0.1, 0.05], mass=3.0, conaffinity=0)
    for leg, (x, y) in LEGS.items():
        _add_leg(torso, leg, x, y)
    limits = envelopes()
    if actuators == "plugin":
        # the drives of one motor and gains at once: hips (abduction and flexion alike), knees
        names = joint_names()
        for joints in (names[:8], names[8:]):
            stiffness, damping = GAINS[joints[0].split("_", 1)[1]]
            add_drives(
                spec, joints, envelope=limits[joints[0]], stiffness=stiffness, damping=damping,
                effort_sensor=False,
            )  # fmt: skip
        return spec
    for name in joint_names():
        stiffness, damping = GAINS[name.split("_", 1)[1]]
        actuator = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.set_to_position(kp=stiffness, kv=damping)
        actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.forcerange = [-limits[name].max_effort, limits[name].max_effort]
    return spec


def targets(time: float) -> np.ndarray:
    """Scripted joint targets at ``time`` [s]: stand, then fast squats with a side-to-side sway.

    The knees (and the hip flexion that keeps each foot under its hip) follow a 2.5 Hz squat that
    asks the knee motors for more speed and torque than they have; the hip abduction sways slowly.

    Returns:
        The 12 target positions [rad], in :func:`joint_names` order.
    """
    ramp = min(max(time - 0.3, 0.0) / 0.5, 1.0)  # settle standing, then fade the motion in
    knee = STAND["knee"] + ramp * 0.6 * math.sin(2 * math.pi * 2.5 * time)
    sway = ramp * 0.15 * math.sin(2 * math.pi * 0.8 * time)
    value = {"hip_flex": -0.5 * knee, "knee": knee}
    return np.asarray(
        [
            STAND["hip_abd"] + (1.0 if name[1] == "l" else -1.0) * sway  # left legs fl, hl
            if name.endswith("hip_abd")
            else value[name.split("_", 1)[1]]
            for name in joint_names()
        ]
    )


def run(seconds: float = 3.0, *, fixed_base: bool = False) -> dict[str, Trajectory]:
    """Simulate the scripted motion with plugin drives; one operating-point trajectory per joint."""
    import mujoco

    from drive_envelope.teststand import Trajectory

    model = build_quadruped("plugin", fixed_base=fixed_base).compile()
    data = mujoco.MjData(model)
    names = joint_names()
    dofs = [int(model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)]) for n in names]
    qpos = [int(model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)]) for n in names]
    data.qpos[qpos] = targets(0.0)
    steps = round(seconds / TIMESTEP)
    rows = np.zeros((steps + 1, 3, len(names)))  # position, velocity, effort
    rows[0, 0], rows[0, 1] = data.qpos[qpos], data.qvel[dofs]
    for k in range(1, steps + 1):
        data.ctrl[:] = targets(data.time)
        mujoco.mj_step(model, data)
        rows[k] = data.qpos[qpos], data.qvel[dofs], data.actuator_force[: len(names)]
    time = np.arange(steps + 1, dtype=np.float64) * TIMESTEP
    return {
        name: Trajectory(
            time=time,
            position=rows[:, 0, j],
            velocity=rows[:, 1, j],
            effort=rows[:, 2, j],
            engine="mujoco",
            name=name,
        )
        for j, name in enumerate(names)
    }


def checks(trajectories: dict[str, Trajectory]) -> dict[str, JointCheck]:
    """Each joint's samples checked against its envelope (``drive-envelope check``'s rules)."""
    from drive_envelope.analysis import check_samples

    limits = envelopes()
    return {
        name: check_samples(limits[name], traj.velocity[1:], traj.effort[1:], time=traj.time[1:])
        for name, traj in trajectories.items()
    }


def summary(trajectories: dict[str, Trajectory]) -> str:
    """A table: peak |effort| and |velocity| as fractions of the envelope, time on its boundary, and
    the samples outside the envelope and released (the drive let go above its no-load speed)."""
    limits = envelopes()
    header = (
        f"{'joint':14s} {'|effort|/max':>12s} {'|v|/v_max':>10s} {'on boundary':>12s} "
        f"{'outside':>9s} {'released':>9s}"
    )
    lines = [header]
    total = outside = released = 0
    for name, check in checks(trajectories).items():
        env, traj = limits[name], trajectories[name]
        velocity, effort = traj.velocity[1:], traj.effort[1:]
        effort_margin, velocity_margin = env.margins(velocity, effort)
        boundary = (
            np.minimum(effort_margin / env.max_effort, velocity_margin / env.max_actuator_velocity) < 1e-6
        )
        total += check.samples
        outside += check.samples_outside
        released += check.samples_released
        lines.append(
            f"{name:14s} {np.abs(effort).max() / env.max_effort:12.2f} "
            f"{np.abs(velocity).max() / env.max_actuator_velocity:10.2f} "
            f"{100 * boundary.mean():11.1f}% {check.samples_outside:9d} {check.samples_released:9d}"
        )
    lines.append(
        f"all joints: {outside} of {total} samples outside the envelope ({100 * outside / total:.3f} %), "
        f"{released} released"
    )
    return "\n".join(lines)


def plot(trajectories: dict[str, Trajectory], path: str) -> None:
    """Draw each joint's operating points over its envelope (4 x 3 grid) and save it atomically."""
    from matplotlib.figure import Figure

    from drive_envelope.plots import save_figure

    limits = envelopes()
    figure = Figure(figsize=(11.0, 11.0), layout="constrained")
    axes = figure.subplots(len(LEGS), len(JOINTS))
    grid = [f"{leg}_{joint}" for leg in LEGS for joint in JOINTS]
    for ax, name in zip(axes.ravel(), grid, strict=True):
        env, traj = limits[name], trajectories[name]
        polygon = env.boundary()
        ax.fill(polygon[:, 0], polygon[:, 1], color="tab:blue", alpha=0.15, label="envelope")
        ax.plot(*np.vstack([polygon, polygon[:1]]).T, color="tab:blue", lw=1.0)
        points = ax.scatter(traj.velocity[1:], traj.effort[1:], c=traj.time[1:], s=3, cmap="viridis")
        ax.set_title(f"{name} ({DATASHEETS[name.split('_', 1)[1]]})", fontsize=9)
        ax.set_xlabel("joint velocity [rad/s]", fontsize=8)
        ax.set_ylabel("effort [N*m]", fontsize=8)
        ax.tick_params(labelsize=7)
    figure.colorbar(points, ax=axes, shrink=0.4, label="time [s]")
    figure.suptitle("MuJoCo quadruped, drive_envelope.envelope plugin: operating points over each envelope")
    save_figure(figure, path, dpi=70)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: simulate, print the summary, optionally plot and write the MJCF."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated time [s] (default 3)")
    parser.add_argument("--fixed-base", action="store_true", help="weld the torso in the air (no contacts)")
    parser.add_argument("--plot", metavar="PNG", help="write the operating-point plot here")
    parser.add_argument("--mjcf", metavar="XML", help="write the model (plugin actuators) as MJCF here")
    args = parser.parse_args(argv)
    trajectories = run(args.seconds, fixed_base=args.fixed_base)
    print(summary(trajectories))
    if args.plot:
        plot(trajectories, args.plot)
        print(f"wrote {args.plot}")
    if args.mjcf:
        from drive_envelope.mujoco import write_mjcf

        write_mjcf(build_quadruped("plugin", fixed_base=args.fixed_base), args.mjcf)
        print(f"wrote {args.mjcf}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Cost of the drive_envelope.envelope plugin per mj_step, against MuJoCo's position and dcmotor actuators.

The robot is the Menagerie Unitree Go2 on a floor (``../shared/data/menagerie/scene_floor.xml``, 12
hinge joints, free base, foot contacts, joint damping, armature and friction loss), or the example
quadruped (examples/mujoco/quadruped.py) when that file is absent. Its motors are replaced three
ways, with the same gains (kp 60 N*m/rad, kv 2 N*m*s/rad) and effort caps:

* plugin: ``add_drive(..., replace=True)`` per joint (the documented way), each joint its envelope;
* position: MuJoCo's native ``position`` actuator with ``forcerange = +-max_effort``;
* dcmotor: MuJoCo 4's ``dcmotor`` with its on-board PD controller (``input="pos"``) and
  ``saturation = max_effort``.

Each kind moves the robot differently and contacts cost differ with the pose, so every kind steps
from the SAME states: a squat run with the plugin is recorded (time, qpos, qvel), then each kind
takes one step from each recorded state through ``mujoco.rollout`` (a C loop, no Python per step,
in the calling thread). Blocks of all states alternate between the kinds (ABC, CBA, ...) so that
machine load hits them alike; the time per step is THREAD CPU time (``time.thread_time``), and the
median over blocks is reported with the ratios (goals: plugin/position <= 1.05, plugin/dcmotor <=
1.03). A second line pins MuJoCo's constraint solver (4 iterations of 8 line-search steps, tolerances 0):
each kind's forces change how hard the solver works on the same contacts (about 1 us of the first
line's difference), pinned only the actuators differ (and the work of the cone Hessian, which
still depends on the forces). A third line drops the constraints altogether: the difference of the
kinds there is their actuation cost alone. A fourth line lets each kind run its own motion (its own
contacts).

``--robot g1|gen3|anymal-c``: a Menagerie robot (``ROBOTS``: ``../shared/data/menagerie/unitree_g1``,
``kinova_gen3``, ``anybotics_anymal_c``) with its shipped map's drives (``unitree-g1``, ``kinova-gen3``,
``anybotics-anymal-c``) in place of its own ``position`` actuators, on the model's own kp and kv (the
compiled ones: ``mujoco apply --map`` without gains), against those actuators as the model ships them
(issue 28's goals: plugin/position <= 1.10x on the G1, 1.05x on Gen3 and ANYmal C). Every joint
follows its start keyframe plus a sine, phases spread (one radian apart):

* G1 on the floor: keyframe ``stand``, 0.3 rad at 6 rad/s from the first step (29 hinges; it falls);
* Kinova Gen3 (fixed base, implicitfast): keyframe ``home``, 0.3 rad at 4.5 rad/s ramped in over
  0.5 s. Kinova's caps (39 / 9 N*m, 1.3963 / 1.2218 rad/s) are far below the model's forcerange (105 /
  52 N*m); the small actuators reach their speed cap and let go there now and then (zero effort,
  PhysX's rule); at 5 rad/s the arm falls onto its joint limits.
  Menagerie's base_link and shoulder_link meshes overlap in every pose (12 mm, 4 contacts), so
  joint 1 would grind on its base: both kinds exclude that pair, as the Gen3's users do. With the
  contacts, the model's stiff gains (kp 2000, kv 100) fight them: the coupled drives took 3.9
  Newton iterations per step on average and let go in 1,631 of 10,500 samples; without them no drive
  reaches its envelope (docs/mujoco.md, "Cost");
* ANYmal C on the floor (Euler, elliptic cones): the keyframe ``standing`` of Menagerie's
  anymal_c_mjx.xml (anymal_c.xml has none; added here), 0.3 rad at 10 rad/s ramped in over 0.5 s:
  up to 3 rad/s, past the ANYdrive's 2.5 rad/s corner, so 11 of the 12 drives reach their envelope
  (about 40 % of the steps have one there); it stays on its feet (base 0.56 -> 0.42 m in 3 s). The
  model's actuators are kp 100, kv 0 with forcerange 80 N*m, the drives the same gains and 80 N*m on
  the line to 7.5 rad/s.

The output has three lines: same states, same states without constraints, own motion.

``--solver pgs|tgs`` (with ``--iterations P V``) runs the plugin's drives as PhysX's articulation
iterates them (``drive_envelope.mujoco.set_solver``) instead of the exact coupled solve.

    .venv/bin/python benchmarks/bench_mujoco.py [--robot go2|g1|gen3|anymal-c] [--blocks 31] [--states 1500]
        [--solver tgs --iterations 4 1]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MENAGERIE = ROOT.parent / "shared" / "data" / "menagerie"
GO2 = MENAGERIE / "scene_floor.xml"
KINDS = ("plugin", "position", "dcmotor")
KP, KV = 60.0, 2.0
HOME = np.array([0.0, 0.9, -1.8] * 4)


@dataclass(frozen=True, kw_only=True)
class Robot:
    """One Menagerie robot of ``--robot``: its scene, its shipped map, the goal and the motion."""

    label: str
    """Name in the output."""
    scene: Path
    """The scene file (robot and floor)."""
    joint_map: str
    """The shipped map (``drive-envelope catalog --maps``) whose drives replace its actuators."""
    goal: float
    """Issue 28's goal for plugin / position [1]."""
    nu: int
    """Its actuators, all position actuators on hinges."""
    keyframe: str
    """The keyframe of the start pose, also the centre of the targets."""
    amplitude: float
    """Target amplitude about the start pose [rad]."""
    rate: float
    """Target angular frequency [rad/s]."""
    ramp: float = 0.0
    """Time over which the amplitude rises from 0, linearly [s]; 0: the waves start at full amplitude."""
    key_qpos: tuple[float, ...] | None = None
    """The start pose's qpos, added as ``keyframe`` when the scene file has no keyframe."""
    exclude: tuple[tuple[str, str], ...] = ()
    """Body pairs whose contacts are excluded (``<contact><exclude>``), as the model's users add them."""


# Menagerie's anymal_c_mjx.xml keyframe "standing" ("A higher standing position"); anymal_c.xml has none
ANYMAL_STANDING = (
    0.0, 0.0, 0.56, 1.0, 0.0, 0.0, 0.0,
    0.0, 0.5235987755982988, -0.7853981, 0.0, 0.5235987755982988, -0.7853981,
    0.0, -0.5235987755982988, 0.7853981, 0.0, -0.5235987755982988, 0.7853981,
)  # fmt: skip
ROBOTS = {
    # issue 28's goals: the plugin within 1.10x the G1's own position actuators, 1.05x Gen3's and ANYmal C's
    "g1": Robot(
        label="Menagerie G1 on a floor",
        scene=MENAGERIE / "unitree_g1" / "scene.xml",
        joint_map="unitree-g1",
        goal=1.10,
        nu=29,
        keyframe="stand",
        amplitude=0.3,
        rate=6.0,
    ),
    "gen3": Robot(
        label="Menagerie Kinova Gen3",
        scene=MENAGERIE / "kinova_gen3" / "scene.xml",
        joint_map="kinova-gen3",
        goal=1.05,
        nu=7,
        keyframe="home",
        amplitude=0.3,
        # 1.35 rad/s at most, past the small actuators' 1.2218 cap: they reach it and let go for a
        # step now and then (PhysX's rule, 35 of 10,500 samples); at 5 rad/s the arm falls onto its
        # joint limits
        rate=4.5,
        ramp=0.5,
        # the meshes overlap in every pose (12 mm, 4 contacts): with them joint 1 grinds on its base,
        # lags its target and saturates (3.9 Newton iterations per step, 1,631 of 10,500 samples let
        # go); without them no drive reaches its envelope. Gen3 users exclude the pair
        exclude=(("base_link", "shoulder_link"),),
    ),
    "anymal-c": Robot(
        label="Menagerie ANYmal C on a floor",
        scene=MENAGERIE / "anybotics_anymal_c" / "scene.xml",
        joint_map="anybotics-anymal-c",
        goal=1.05,
        nu=12,
        keyframe="standing",
        amplitude=0.3,
        rate=10.0,  # 3 rad/s at most: past the ANYdrive's corner (2.5 rad/s), on its speed-torque line
        ramp=0.5,
        key_qpos=ANYMAL_STANDING,
    ),
}


def _envelope(joint: str) -> Any:
    from drive_envelope import PerformanceEnvelope

    # Go2's motors: 23.7 N*m at hip and thigh, 45.43 N*m at the knee (its ctrlrange), ~30 rad/s
    knee = "calf" in joint or "knee" in joint
    return PerformanceEnvelope(
        max_effort=45.43 if knee else 23.7,
        max_actuator_velocity=15.7 if knee else 30.1,
        velocity_dependent_resistance=0.05,
        speed_effort_gradient=0.3 if knee else 1.2,
        name=joint,
    )


def _base_spec() -> tuple[Any, str]:
    import mujoco

    if GO2.is_file():
        spec = mujoco.MjSpec.from_file(str(GO2))
        for key in list(spec.keys):
            spec.delete(key)
        return spec, "Menagerie Go2 on a floor"
    sys.path.insert(0, str(ROOT / "examples" / "mujoco"))
    import quadruped

    spec = quadruped.build_quadruped("position")
    for actuator in list(spec.actuators):
        actuator.set_to_motor()
    return spec, "example quadruped (../shared/data absent)"


def build(
    kind: str, solver: Any = "exact", iterations: tuple[int, int] = (4, 1)
) -> tuple[Any, list[str], str]:
    """The model with its motors replaced by ``kind``; returns (model, joint names, robot label)."""
    import mujoco

    from drive_envelope.mujoco import add_drive, set_solver

    spec, label = _base_spec()
    joints = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    for joint in joints:
        env = _envelope(joint)
        if kind == "plugin":
            add_drive(spec, joint, envelope=env, stiffness=KP, damping=KV, replace=True, effort_sensor=False)
            continue
        actuator = next(a for a in spec.actuators if a.target == joint)
        if kind == "position":
            actuator.set_to_position(kp=KP, kv=KV)
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.forcerange = [-env.max_effort, env.max_effort]
        else:
            # stateless DC motor, torque-space PD controller, torque saturated at max_effort
            actuator.set_to_dcmotor(
                [1.0, 1.0],
                0.3,
                saturation=[env.max_effort, 0, 0],
                controller=[KP, 0, KV, 0, 0, 48],
                ctrlspec=1,
            )
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    if kind == "plugin" and solver != "exact":
        set_solver(spec, solver, position_iterations=iterations[0], velocity_iterations=iterations[1])
    return spec.compile(), joints, label


def _add_keyframe(spec: Any, robot: Robot) -> None:
    """The robot's start pose as a keyframe, where its scene file has none (ANYmal C)."""
    if robot.key_qpos is not None:
        spec.add_key(name=robot.keyframe, qpos=list(robot.key_qpos))


def build_robot(robot: Robot, kind: str, solver: Any = "exact", iterations: tuple[int, int] = (4, 1)) -> Any:
    """A Menagerie robot, compiled: its own position actuators, or its map's drives in their place."""
    import mujoco

    model = robot_spec(robot, kind, solver, iterations).compile()
    hinges = model.jnt_type[model.actuator_trnid[:, 0]] == mujoco.mjtJoint.mjJNT_HINGE
    assert model.nu == robot.nu and all(hinges)
    return model


def robot_spec(robot: Robot, kind: str, solver: Any = "exact", iterations: tuple[int, int] = (4, 1)) -> Any:
    """A Menagerie robot's ``MjSpec``: its own position actuators, or its map's drives in their place.

    The drives replace each ``position`` actuator in place and keep its kp and kv (``mujoco apply
    --map <robot's map>`` without gains), so both kinds have the model's own gains.
    """
    from drive_envelope._src.adapters.mujoco.mjcf import Assignment, apply_drives, driven_joints, load_spec
    from drive_envelope._src.adapters.usd.joint_map import match_joints, read_map, resolve_envelopes
    from drive_envelope._src.datasheet.maps import robot_map_path
    from drive_envelope.mujoco import set_solver

    spec = load_spec(robot.scene)
    _add_keyframe(spec, robot)
    for body1, body2 in robot.exclude:
        spec.add_exclude(bodyname1=body1, bodyname2=body2)
    if kind == "plugin":
        # dampratio="1" positions: write each compiled kv (and kp) so the drives keep those gains
        compiled = spec.compile()
        for actuator in spec.actuators:
            index = compiled.actuator(actuator.name).id
            kp, kv = compiled.actuator_gainprm[index, 0], -compiled.actuator_biasprm[index, 2]
            actuator.set_to_position(kp=float(kp), kv=float(kv))
        match = match_joints(read_map(str(robot_map_path(robot.joint_map))), driven_joints(spec))
        items = [
            Assignment(joint=item.joint, envelope=item.envelope, where=item.entry.where)
            for item in resolve_envelopes(match)
            if item.envelope is not None
        ]
        apply_drives(spec, items)
        if solver != "exact":
            set_solver(spec, solver, position_iterations=iterations[0], velocity_iterations=iterations[1])
    return spec


def robot_targets(model: Any, robot: Robot, times: np.ndarray) -> np.ndarray:
    """The start pose, each joint waving ``robot.amplitude`` at ``robot.rate``, phases spread; (steps, nu)."""
    key = model.key(robot.keyframe)
    qpos = key.qpos[model.jnt_qposadr[model.actuator_trnid[:, 0]]]
    phase = np.arange(model.nu)[None, :]
    t = times[:, None]
    gain = np.minimum(t / robot.ramp, 1.0) if robot.ramp > 0 else 1.0
    return qpos[None, :] + gain * robot.amplitude * np.sin(robot.rate * t + phase)


def _robot_state(model: Any, robot: Robot) -> np.ndarray:
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(robot.keyframe).id)
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return state


def main_robot(args: argparse.Namespace) -> int:
    """A Menagerie robot's workload: plugin (its map's drives) against the robot's own position actuators."""
    import mujoco
    from mujoco import rollout

    robot = ROBOTS[args.robot]
    iterations = tuple(args.iterations)
    models = {kind: build_robot(robot, kind, args.solver, iterations) for kind in ("plugin", "position")}
    times = np.arange(args.states) * models["plugin"].opt.timestep
    control = robot_targets(models["plugin"], robot, times)
    own = {}
    for kind, model in models.items():
        own[kind] = (
            model,
            mujoco.MjData(model),
            _robot_state(model, robot)[None],
            control[None],
            args.states,
        )
    model, data, state0, _, _ = own["plugin"]
    recorded, _ = rollout.rollout(model, data, state0, control[None])
    same = {}
    for kind, (m, d, _, _, _) in own.items():
        same[kind] = (m, d, _convert(m, recorded[0], model), control[:, None, :], args.states)
    solver = args.solver if args.solver == "exact" else "{} {}/{}".format(args.solver, *args.iterations)
    print(
        f"mujoco {mujoco.__version__}, {robot.label}: nv = {model.nv}, {robot.nu} hinges "
        f"({robot.joint_map} map, the model's kp/kv), {mujoco.mjtIntegrator(model.opt.integrator).name}, "
        f"dt = {model.opt.timestep * 1e3:g} ms, {args.blocks} blocks x {args.states} steps, "
        f"plugin solver {solver}; median thread CPU time per mj_step:"
    )
    alone = {}
    for kind, (m, _, starts, c, steps) in same.items():
        free = _unconstrained(m)
        alone[kind] = (free, mujoco.MjData(free), starts, c, steps)
    for name, runs in (("same states", same), ("  no constr.", alone), ("own motion", own)):
        median = _medians(runs, args.blocks)
        print(
            f"  {name:12s} plugin {median['plugin'] * 1e6:6.2f} us"
            f"   position {median['position'] * 1e6:6.2f} us"
            f"   plugin/position = {median['plugin'] / median['position']:.3f} (goal <= {robot.goal:.2f})"
            f"   plugin - native = {(median['plugin'] - median['position']) * 1e6:+.2f} us"
        )
    return 0


def targets(times: np.ndarray) -> np.ndarray:
    """Squats that push the knees and thighs onto their envelopes; (len(times), 12) [rad]."""
    t = times[:, None]
    ramp = np.minimum(t / 0.3, 1.0)
    wave = np.concatenate([0.2 * np.sin(9 * t), 0.5 * np.sin(14 * t), 0.8 * np.sin(14 * t + 1)], axis=1)
    return HOME + ramp * np.tile(wave, (1, 4))


def _initial_state(model: Any, joints: list[str]) -> np.ndarray:
    import mujoco

    data = mujoco.MjData(model)
    qpos = [int(model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j)]) for j in joints]
    data.qpos[qpos] = HOME
    if model.nq > len(joints):
        data.qpos[2] = 0.3
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return state


def _convert(model: Any, states: np.ndarray, source: Any) -> np.ndarray:
    """``source``'s recorded FULLPHYSICS states as ``model``'s FULLPHYSICS states (time, qpos, qvel)."""
    import mujoco

    spec = int(mujoco.mjtState.mjSTATE_TIME | mujoco.mjtState.mjSTATE_QPOS | mujoco.mjtState.mjSTATE_QVEL)
    size = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    out = np.zeros((len(states), size))
    part = np.zeros(mujoco.mj_stateSize(source, spec))
    data = mujoco.MjData(model)
    for i, state in enumerate(states):
        mujoco.mj_extractState(source, state, int(mujoco.mjtState.mjSTATE_FULLPHYSICS), part, spec)
        mujoco.mj_setState(model, data, part, spec)
        mujoco.mj_getState(model, data, out[i], mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return out


def _pinned(model: Any) -> Any:
    """A copy of ``model`` whose constraint solver always does 4 iterations of 8 line-search steps."""
    import copy

    fixed = copy.copy(model)
    fixed.opt.iterations, fixed.opt.tolerance = 4, 0.0
    fixed.opt.ls_iterations, fixed.opt.ls_tolerance = 8, 0.0
    return fixed


def _unconstrained(model: Any) -> Any:
    """A copy of ``model`` without constraints: what is left to differ is the actuation alone."""
    import copy

    import mujoco

    free = copy.copy(model)
    free.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    return free


def _medians(runs: dict[str, tuple[Any, ...]], blocks: int) -> dict[str, float]:
    """Median thread CPU time per step of each kind; kinds alternate order from block to block."""
    from mujoco import rollout

    per_step: dict[str, list[float]] = {kind: [] for kind in runs}
    with rollout.Rollout(nthread=0) as runner:
        for block in range(blocks + 2):
            order = list(runs) if block % 2 == 0 else list(reversed(list(runs)))
            for kind in order:
                model, data, state, control, steps = runs[kind]
                start = time.thread_time()
                runner.rollout(model, data, state, control)
                elapsed = time.thread_time() - start
                if block >= 2:  # the first blocks warm the caches
                    per_step[kind].append(elapsed / steps)
    return {kind: statistics.median(values) for kind, values in per_step.items()}


def main() -> int:
    parser = argparse.ArgumentParser(description="mj_step cost: plugin vs native position and dcmotor")
    parser.add_argument("--blocks", type=int, default=31, help="timed blocks per kind (default 31)")
    parser.add_argument("--states", type=int, default=1500, help="recorded states (steps) per block")
    parser.add_argument(
        "--solver", choices=("exact", "pgs", "tgs"), default="exact", help="the plugin's solver"
    )
    parser.add_argument(
        "--iterations", type=int, nargs=2, default=(4, 1), metavar=("P", "V"), help="pgs/tgs iterations"
    )
    parser.add_argument("--robot", choices=("go2", *ROBOTS), default="go2", help="workload (default go2)")
    args = parser.parse_args()
    if args.robot in ROBOTS:
        from drive_envelope.mujoco import load_plugin

        load_plugin()
        return main_robot(args)

    import mujoco
    from mujoco import rollout

    from drive_envelope.mujoco import load_plugin

    load_plugin()
    built = {kind: build(kind, args.solver, tuple(args.iterations)) for kind in KINDS}
    solver = args.solver if args.solver == "exact" else "{} {}/{}".format(args.solver, *args.iterations)
    joints, label = built["plugin"][1], built["plugin"][2]
    times = np.arange(args.states) * built["plugin"][0].opt.timestep
    control = targets(times)
    own = {}
    for kind, (model, _, _) in built.items():
        data = mujoco.MjData(model)
        own[kind] = (model, data, _initial_state(model, joints)[None], control[None], args.states)

    # same states: the plugin run's states, one step from each
    model, data, state0, _, _ = own["plugin"]
    recorded, _ = rollout.rollout(model, data, state0, control[None])
    same = {}
    for kind, (m, d, _, _, _) in own.items():
        starts = _convert(m, recorded[0], model)
        same[kind] = (m, d, starts, control[:, None, :], args.states)

    print(
        f"mujoco {mujoco.__version__}, {label}: nv = {model.nv}, 12 actuated hinges, "
        f"{mujoco.mjtIntegrator(model.opt.integrator).name}, dt = {model.opt.timestep * 1e3:g} ms, "
        f"{args.blocks} blocks x {args.states} steps, plugin solver {solver}; "
        "median thread CPU time per mj_step:"
    )
    # same states with the constraint solver pinned to a fixed amount of work: each kind's forces
    # change how hard MuJoCo's solver works on the same contacts; pinned, only the actuators differ
    pinned, alone = {}, {}
    for kind, (m, _, starts, c, steps) in same.items():
        fixed, free = _pinned(m), _unconstrained(m)
        pinned[kind] = (fixed, mujoco.MjData(fixed), starts, c, steps)
        alone[kind] = (free, mujoco.MjData(free), starts, c, steps)
    workloads = (("same states", same), ("  pinned", pinned), ("  no constr.", alone), ("own motion", own))
    for name, runs in workloads:
        median = _medians(runs, args.blocks)
        cells = "   ".join(f"{kind} {median[kind] * 1e6:6.2f} us" for kind in KINDS)
        extra = median["plugin"] - min(median["position"], median["dcmotor"])
        print(
            f"  {name:12s} {cells}   plugin/position = {median['plugin'] / median['position']:.3f} "
            f"(goal <= 1.05)   plugin/dcmotor = {median['plugin'] / median['dcmotor']:.3f} (goal <= 1.03)"
            f"   plugin - native = {extra * 1e6:+.2f} us"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

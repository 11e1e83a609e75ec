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

``--robot g1``: the Menagerie G1 (29 DOF, on the floor; ``../shared/data/menagerie/unitree_g1``)
with the ``unitree-g1`` map's drives on the model's own gains, against its own ``position``
actuators (goal <= 1.10x, issue 28).

``--solver pgs|tgs`` (with ``--iterations P V``) runs the plugin's drives as PhysX's articulation
iterates them (``drive_envelope.mujoco.set_solver``) instead of the exact coupled solve.

    .venv/bin/python benchmarks/bench_mujoco.py [--blocks 31] [--states 1500] [--solver tgs --iterations 4 1]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
GO2 = ROOT.parent / "shared" / "data" / "menagerie" / "scene_floor.xml"
G1 = ROOT.parent / "shared" / "data" / "menagerie" / "unitree_g1" / "scene.xml"
G1_GOAL = 1.10  # issue 28: the plugin within 1.10x the G1's own position actuators
KINDS = ("plugin", "position", "dcmotor")
KP, KV = 60.0, 2.0
HOME = np.array([0.0, 0.9, -1.8] * 4)


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


def build_g1(kind: str, solver: Any = "exact", iterations: tuple[int, int] = (4, 1)) -> Any:
    """The Menagerie G1 (29 hinges, floor): its own position actuators, or the ``unitree-g1`` map's drives.

    The drives replace each ``position`` actuator in place and keep its kp and kv (``mujoco apply
    --map unitree-g1`` without gains), so both kinds have the model's own gains.
    """
    import mujoco

    from drive_envelope._src.adapters.mujoco.mjcf import Assignment, apply_drives, driven_joints, load_spec
    from drive_envelope._src.adapters.usd.joint_map import match_joints, read_map, resolve_envelopes
    from drive_envelope._src.datasheet.maps import robot_map_path
    from drive_envelope.mujoco import set_solver

    spec = load_spec(G1)
    if kind == "plugin":
        # dampratio="1" positions: write each compiled kv (and kp) so the drives keep those gains
        compiled = spec.compile()
        for actuator in spec.actuators:
            index = compiled.actuator(actuator.name).id
            kp, kv = compiled.actuator_gainprm[index, 0], -compiled.actuator_biasprm[index, 2]
            actuator.set_to_position(kp=float(kp), kv=float(kv))
        match = match_joints(read_map(str(robot_map_path("unitree-g1"))), driven_joints(spec))
        items = [
            Assignment(joint=item.joint, envelope=item.envelope, where=item.entry.where)
            for item in resolve_envelopes(match)
            if item.envelope is not None
        ]
        apply_drives(spec, items)
        if solver != "exact":
            set_solver(spec, solver, position_iterations=iterations[0], velocity_iterations=iterations[1])
    model = spec.compile()
    assert model.nu == 29 and all(model.jnt_type[model.actuator_trnid[:, 0]] == mujoco.mjtJoint.mjJNT_HINGE)
    return model


def g1_targets(model: Any, times: np.ndarray) -> np.ndarray:
    """The stand pose with every joint waving 0.3 rad at 6 rad/s, phases spread; (len(times), 29)."""
    key = model.key("stand")
    qpos = key.qpos[model.jnt_qposadr[model.actuator_trnid[:, 0]]]
    phase = np.arange(model.nu)[None, :]
    return qpos[None, :] + 0.3 * np.sin(6 * times[:, None] + phase)


def _g1_state(model: Any) -> np.ndarray:
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("stand").id)
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return state


def main_g1(args: argparse.Namespace) -> int:
    """The G1 workload: plugin (the map's drives) against the G1's own position actuators."""
    import mujoco
    from mujoco import rollout

    models = {kind: build_g1(kind, args.solver, tuple(args.iterations)) for kind in ("plugin", "position")}
    times = np.arange(args.states) * models["plugin"].opt.timestep
    control = g1_targets(models["plugin"], times)
    own = {}
    for kind, model in models.items():
        own[kind] = (model, mujoco.MjData(model), _g1_state(model)[None], control[None], args.states)
    model, data, state0, _, _ = own["plugin"]
    recorded, _ = rollout.rollout(model, data, state0, control[None])
    same = {}
    for kind, (m, d, _, _, _) in own.items():
        same[kind] = (m, d, _convert(m, recorded[0], model), control[:, None, :], args.states)
    solver = args.solver if args.solver == "exact" else "{} {}/{}".format(args.solver, *args.iterations)
    print(
        f"mujoco {mujoco.__version__}, Menagerie G1 on a floor: nv = {model.nv}, 29 hinges "
        f"(unitree-g1 map, the model's kp/kv), {mujoco.mjtIntegrator(model.opt.integrator).name}, dt = "
        f"{model.opt.timestep * 1e3:g} ms, {args.blocks} blocks x {args.states} steps, "
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
            f"   plugin/position = {median['plugin'] / median['position']:.3f} (goal <= {G1_GOAL:.2f})"
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
    parser.add_argument("--robot", choices=("go2", "g1"), default="go2", help="workload (default go2)")
    args = parser.parse_args()
    if args.robot == "g1":
        from drive_envelope.mujoco import load_plugin

        load_plugin()
        return main_g1(args)

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

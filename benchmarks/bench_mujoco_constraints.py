"""MuJoCo's constraints solved with the drives (``set_solver(..., constraints=True)``): gain and cost.

Three Menagerie robots (``../shared/data/menagerie``), each with catalog envelopes from a joint map and
the model's own gains (``drive-envelope mujoco apply --map ...`` without gains; dampratio positions
keep their compiled kv), Euler at the model's time step, every driven joint following
``home + A*sin(w*t + j)`` with ``A*w = 2 * max_actuator_velocity`` (twice its speed limit), 3000 steps:

* ANYmal C on the floor (``anybotics_anymal_c/scene.xml``, dropped from its default pose, elliptic
  cones): ``examples/newton/anymal_map.toml`` (hips RMD-X8-120, knees RMD-X12-320), A = 0.3 rad;
* Kinova Gen3 (``kinova_gen3/scene.xml``, keyframe ``home``, joint limits on joints 2, 4, 6, and
  Menagerie's base_link and shoulder_link meshes overlapping in every pose: 4 contacts on joint 1): no
  Kinova datasheet in the catalog, so stand-ins of its two actuator classes (the model's 105 / 52 N*m
  force ranges): joints 1-4 the RMD-X8-120, 5-7 the RobStride RS03, A = 0.5 rad;
* Unitree G1 on the floor (``unitree_g1/scene.xml``, keyframe ``stand``): the ``unitree-g1`` map, A = 0.3.

Each sample (drive, step) is checked at the velocity MuJoCo integrated (``data.qvel`` after
``mj_step``) with ``drive-envelope check``'s rule: outside = a relative margin below -1e-6 of its cap,
released = zero effort above the no-load speed (counted apart); worst = the largest relative excess.
"law gap" counts samples strictly inside whose effort is more than 1 % of max_effort from the PD law
at that velocity (where a constraint held the joint back: the drive under-delivers).

Cost: median thread CPU time per ``mj_step`` of each setting running its own 3000-step motion
through ``mujoco.rollout`` (a C loop), blocks interleaved (AB, BA, ...); "solves" is the mean number
of constraint solves the plugin ran itself per step (``drive_envelope_constraint_solves``).

    .venv/bin/python benchmarks/bench_mujoco_constraints.py [--steps 3000] [--blocks 9] [--robot anymal]
"""

from __future__ import annotations

import argparse
import ctypes
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MENAGERIE = ROOT.parent / "shared" / "data" / "menagerie"
GEN3_MAP = """[joints]
"joint_[1-4]" = "myactuator-rmd-x8-120"
"joint_[5-7]" = "robstride-rs03"
"""
GOAL_OUTSIDE, GOAL_COST = 0.001, 2.0  # issue 22: ANYmal C at most 0.1 % outside, at most 2x the step


@dataclass(frozen=True, kw_only=True)
class Stand:
    """One robot of the benchmark."""

    name: str
    """Label in the output."""
    scene: Path
    """The Menagerie scene file."""
    joint_map: str
    """A map file, or the text of one."""
    keyframe: str | None
    """Keyframe of the start pose, None: the model's default pose."""
    amplitude: float
    """Sinusoid amplitude around the start pose [rad]."""


STANDS = {
    "anymal": Stand(
        name="ANYmal C, floor",
        scene=MENAGERIE / "anybotics_anymal_c" / "scene.xml",
        joint_map=str(ROOT / "examples" / "newton" / "anymal_map.toml"),
        keyframe=None,
        amplitude=0.3,
    ),
    "gen3": Stand(
        name="Kinova Gen3",
        scene=MENAGERIE / "kinova_gen3" / "scene.xml",
        joint_map=GEN3_MAP,
        keyframe="home",
        amplitude=0.5,
    ),
    "g1": Stand(
        name="Unitree G1, floor",
        scene=MENAGERIE / "unitree_g1" / "scene.xml",
        joint_map="unitree-g1",
        keyframe="stand",
        amplitude=0.3,
    ),
}


def _map_path(stand: Stand, folder: Path) -> str:
    from drive_envelope._src.datasheet.maps import robot_map_path

    if "\n" in stand.joint_map:
        path = folder / f"{stand.name.split(',')[0].replace(' ', '_')}.toml"
        path.write_text(stand.joint_map, encoding="utf-8")
        return str(path)
    if stand.joint_map.endswith(".toml"):
        return stand.joint_map
    return str(robot_map_path(stand.joint_map))


def build(stand: Stand, constraints: bool) -> tuple[Any, list[Any], list[int]]:
    """The stand's model (Euler), its envelopes and drive actuators, with ``constraints`` set."""
    import mujoco

    from drive_envelope._src.adapters.mujoco.mjcf import Assignment, apply_drives, driven_joints, load_spec
    from drive_envelope._src.adapters.usd.joint_map import match_joints, read_map, resolve_envelopes
    from drive_envelope.mujoco import set_solver

    spec = load_spec(stand.scene)
    compiled = spec.compile()
    for actuator in spec.actuators:  # dampratio positions: write the compiled kp and kv
        index = compiled.actuator(actuator.name).id
        kp, kv = compiled.actuator_gainprm[index, 0], -compiled.actuator_biasprm[index, 2]
        actuator.set_to_position(kp=float(kp), kv=float(kv))
    with tempfile.TemporaryDirectory() as folder:
        match = match_joints(read_map(_map_path(stand, Path(folder))), driven_joints(spec))
        items = resolve_envelopes(match)
    assignments = [
        Assignment(joint=item.joint, envelope=item.envelope, where=item.entry.where)
        for item in items
        if item.envelope is not None
    ]
    apply_drives(spec, assignments)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    set_solver(spec, "exact", constraints=constraints)
    model = spec.compile()
    envelopes, actuators = [], []
    for item in assignments:
        joint = model.joint(item.joint).id
        actuators.append(int(np.flatnonzero(model.actuator_trnid[:, 0] == joint)[0]))
        envelopes.append(item.envelope)
    return model, envelopes, actuators


def _start(model: Any, stand: Stand) -> Any:
    import mujoco

    data = mujoco.MjData(model)
    if stand.keyframe is not None:
        mujoco.mj_resetDataKeyframe(model, data, model.key(stand.keyframe).id)
    return data


def controls(model: Any, stand: Stand, envelopes: list[Any], actuators: list[int], steps: int) -> np.ndarray:
    """Every drive's target, (steps, nu): twice each joint's speed limit around the start pose [rad]."""
    data = _start(model, stand)
    qpos = data.qpos[model.jnt_qposadr[model.actuator_trnid[actuators, 0]]]
    omega = np.array([2 * env.max_actuator_velocity / stand.amplitude for env in envelopes])
    times = np.arange(steps)[:, None] * model.opt.timestep
    phase = np.arange(len(actuators))[None, :]
    out = np.zeros((steps, model.nu))
    wave = stand.amplitude * np.sin(omega * times + phase)
    out[:, model.actuator_ctrladr[actuators]] = qpos[None, :] + wave
    return out


def _constraint_solves(model: Any, data: Any) -> int:
    from drive_envelope._src.adapters.mujoco.loader import plugin_library, plugin_slot

    leader = next(j for j in range(model.nplugin) if int(model.plugin[j]) == plugin_slot())
    function = plugin_library().drive_envelope_constraint_solves
    function.restype = ctypes.c_int
    function.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_int)]
    count = ctypes.c_int(0)
    function(int(data.plugin_data[leader]), ctypes.byref(count))
    return count.value


def check(
    model: Any, stand: Stand, envelopes: list[Any], actuators: list[int], control: np.ndarray
) -> dict[str, float]:
    """Step the stand and check every drive after every step (see the module docstring)."""
    import mujoco

    from drive_envelope.mujoco import get_gains

    data = _start(model, stand)
    joints = model.actuator_trnid[actuators, 0]
    dof, qadr = model.jnt_dofadr[joints], model.jnt_qposadr[joints]
    gains = np.array([get_gains(model, a) for a in actuators])
    caps = np.array([env.max_effort for env in envelopes])
    h = model.opt.timestep
    samples = outside = released = gap = solves = 0
    worst = 0.0
    for step in range(len(control)):
        data.ctrl[:] = control[step]
        target, q0 = control[step, model.actuator_ctrladr[actuators]], data.qpos[qadr].copy()
        mujoco.mj_step(model, data)
        solves += _constraint_solves(model, data)
        v1, tau = data.qvel[dof], data.actuator_force[actuators]
        law = gains[:, 0] * (target - q0 - h * v1) - gains[:, 1] * v1
        for i, env in enumerate(envelopes):
            effort_margin, velocity_margin = env.margins(v1[i], tau[i])
            relative = min(effort_margin / env.max_effort, velocity_margin / env.max_actuator_velocity)
            samples += 1
            if tau[i] == 0.0 and abs(v1[i]) > env.no_load_velocity():
                released += 1
            elif relative < -1e-6:
                outside += 1
                worst = max(worst, -relative)
            elif relative > 1e-6 and abs(law[i] - tau[i]) > 0.01 * caps[i]:
                gap += 1
    return {
        "samples": samples,
        "outside": outside / samples,
        "released": released / samples,
        "worst": worst,
        "gap": gap / samples,
        "solves": solves / len(control),
    }


def step_costs(runs: dict[str, tuple[Any, Any, np.ndarray, np.ndarray]], blocks: int) -> dict[str, float]:
    """Median thread CPU time per step of each setting's own motion; the order alternates per block."""
    from mujoco import rollout

    per_step: dict[str, list[float]] = {kind: [] for kind in runs}
    with rollout.Rollout(nthread=0) as runner:
        for block in range(blocks + 1):
            order = list(runs) if block % 2 == 0 else list(reversed(list(runs)))
            for kind in order:
                model, data, state, control = runs[kind]
                start = time.thread_time()
                runner.rollout(model, data, state, control)
                elapsed = time.thread_time() - start
                if block >= 1:  # the first block warms the caches
                    per_step[kind].append(elapsed / control.shape[1])
    return {kind: statistics.median(values) for kind, values in per_step.items()}


def run(key: str, steps: int, blocks: int) -> dict[str, Any]:
    """Both settings on one stand: the checks and the step costs."""
    import mujoco

    stand = STANDS[key]
    result: dict[str, Any] = {"stand": stand}
    runs = {}
    for kind, flag in (("default", False), ("constraints", True)):
        model, envelopes, actuators = build(stand, flag)
        control = controls(model, stand, envelopes, actuators, steps)
        result[kind] = check(model, stand, envelopes, actuators, control)
        data = _start(model, stand)
        state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
        mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        runs[kind] = (model, mujoco.MjData(model), state[None], control[None])
        result["nv"], result["drives"] = model.nv, len(actuators)
    result["cost"] = step_costs(runs, blocks)
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description="constraints=True: samples outside and step cost")
    parser.add_argument("--steps", type=int, default=3000, help="steps per run (default 3000)")
    parser.add_argument("--blocks", type=int, default=9, help="timed blocks per setting (default 9)")
    parser.add_argument("--robot", choices=(*STANDS, "all"), default="all", help="stand (default all)")
    args = parser.parse_args()
    if not MENAGERIE.is_dir():
        print(f"skipped: {MENAGERIE} is absent")
        return 0
    import mujoco

    from drive_envelope.mujoco import load_plugin

    load_plugin()
    keys = list(STANDS) if args.robot == "all" else [args.robot]
    print(
        f"mujoco {mujoco.__version__}, Euler, sinusoids at 2x the speed limit, {args.steps} steps; "
        f"cost: median thread CPU time per mj_step, {args.blocks} blocks"
    )
    failed = False
    for key in keys:
        result = run(key, args.steps, args.blocks)
        cost = result["cost"]
        print(f"{result['stand'].name}: nv {result['nv']}, {result['drives']} drives")
        for kind in ("default", "constraints"):
            r = result[kind]
            print(
                f"  {kind:11s} outside {100 * r['outside']:6.3f} %  "
                f"worst {100 * r['worst']:6.2f} % of the cap  "
                f"released {100 * r['released']:5.2f} %  law gap {100 * r['gap']:5.2f} %  "
                f"solves/step {r['solves']:.2f}  {cost[kind] * 1e6:7.1f} us/step"
            )
        ratio = cost["constraints"] / cost["default"]
        print(f"  cost ratio constraints/default = {ratio:.2f}")
        if key == "anymal":
            met = result["constraints"]["outside"] <= GOAL_OUTSIDE and ratio <= GOAL_COST
            failed |= not met
            verdict = "met" if met else "NOT met"
            print(f"  goal (<= {100 * GOAL_OUTSIDE:g} % outside, <= {GOAL_COST:g}x): {verdict}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

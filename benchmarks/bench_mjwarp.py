"""Cost of envelope drives per MJWarp step, against the same model with motor and position actuators.

The robot is the Menagerie Unitree Go2 (``../shared/data/menagerie/scene_floor.xml``: 12 hinge
joints, free base, foot contacts, joint damping, armature and friction loss). Its motors are
equipped three ways, stepped by MuJoCo Warp (``mujoco_warp.step``) on the default Warp device:

* envelope: ``add_drive(..., replace=True)`` per joint (kp 60, kv 2, each joint its envelope), put
  on the device with ``drive_envelope.mjwarp.put_model`` (the coupled implicit drive in Warp);
* motor: the Go2's own ``motor`` actuators (torque controls, here constant);
* position: MuJoCo's ``position`` actuator (same gains) with ``forcerange = +-max_effort``.

Two workloads: ``floor`` (the robot on the floor, each kind in its own motion, squat targets) and
``fixed`` (free joint removed, contacts, limits and friction loss off: only the actuation differs).
Blocks of ``--steps`` steps alternate between the kinds (ABC, CBA, ...) so that machine load hits
them alike; the time per step is the calling thread's CPU time after ``wp.synchronize`` (Warp's
CPU device runs the kernels in the calling thread, so other processes' load does not count; on a
GPU use wall time); the median over blocks is reported with the ratios. The goal
(envelope <= 1.10x position on the GPU) was set for a GPU; on the CPU it is reported as measured.

    .venv/bin/python benchmarks/bench_mjwarp.py [--nworld 1,64] [--blocks 15] [--steps 20]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
GO2 = ROOT.parent / "shared" / "data" / "menagerie" / "scene_floor.xml"
KINDS = ("envelope", "motor", "position")
KP, KV = 60.0, 2.0
HOME = np.array([0.0, 0.9, -1.8] * 4)


def _envelope(joint: str) -> Any:
    from drive_envelope import PerformanceEnvelope

    knee = "calf" in joint
    return PerformanceEnvelope(
        max_effort=45.43 if knee else 23.7,
        max_actuator_velocity=15.7 if knee else 30.1,
        velocity_dependent_resistance=0.05,
        speed_effort_gradient=0.3 if knee else 1.2,
    )


def _spec(workload: str) -> Any:
    import mujoco

    spec = mujoco.MjSpec.from_file(str(GO2))
    for key in list(spec.keys):
        spec.delete(key)
    if workload == "fixed":
        for joint in list(spec.body("base").joints):
            spec.delete(joint)
        spec.option.disableflags |= int(
            mujoco.mjtDisableBit.mjDSBL_CONTACT
            | mujoco.mjtDisableBit.mjDSBL_LIMIT
            | mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS
        )
    return spec


def build(kind: str, workload: str) -> tuple[Any, Any, list[int]]:
    """(MJWarp model, MjModel, control address of each hinge) of the Go2 equipped as ``kind``."""
    import mujoco
    import mujoco_warp

    from drive_envelope.mjwarp import put_model
    from drive_envelope.mujoco import add_drive, load_plugin

    spec = _spec(workload)
    joints = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    for joint in joints:
        env = _envelope(joint)
        if kind == "envelope":
            add_drive(spec, joint, envelope=env, stiffness=KP, damping=KV, replace=True, effort_sensor=False)
        elif kind == "position":
            actuator = next(a for a in spec.actuators if a.target == joint)
            actuator.set_to_position(kp=KP, kv=KV)
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.forcerange = [-env.max_effort, env.max_effort]
            actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    if kind == "envelope":
        load_plugin()
        mj_model = spec.compile()
        model = put_model(spec)
    else:
        mj_model = spec.compile()
        model = mujoco_warp.put_model(mj_model)
    trnid = mj_model.actuator_trnid[:, 0]
    ctrl = [int(mj_model.actuator_ctrladr[np.flatnonzero(trnid == mj_model.joint(j).id)[0]]) for j in joints]
    return model, mj_model, ctrl


def _data(mj_model: Any, nworld: int) -> Any:
    import mujoco
    import mujoco_warp

    data = mujoco.MjData(mj_model)
    hinge = [i for i in range(mj_model.njnt) if mj_model.jnt_type[i] == mujoco.mjtJoint.mjJNT_HINGE]
    data.qpos[mj_model.jnt_qposadr[hinge]] = HOME
    if mj_model.nq > len(hinge):
        data.qpos[2] = 0.3
    # room for every foot contact of every world (MJWarp's defaults overflow on the floor)
    return mujoco_warp.put_data(mj_model, data, nworld=nworld, nconmax=32, njmax=256)


def _clock() -> float:
    """Thread CPU time on Warp's CPU device (other processes' load does not count), else wall time."""
    import warp as wp

    return time.perf_counter() if wp.get_device().is_cuda else time.thread_time()


def _block(
    kind: str, model: Any, data: Any, ctrl: list[int], nu: int, step0: int, steps: int, h: float
) -> float:
    """Seconds per step of ``steps`` steps (targets set on the device before each, not timed)."""
    import mujoco_warp
    import warp as wp

    total = 0.0
    for step in range(step0, step0 + steps):
        t = step * h
        values = np.zeros((data.nworld, nu), dtype=np.float32)
        if kind != "motor":
            wave = np.tile([0.2 * np.sin(9 * t), 0.5 * np.sin(14 * t), 0.8 * np.sin(14 * t + 1)], 4)
            values[:, ctrl] = HOME + min(t / 0.3, 1.0) * wave
        data.ctrl.assign(values)
        wp.synchronize()
        start = _clock()
        mujoco_warp.step(model, data)
        wp.synchronize()
        total += _clock() - start
    return total / steps


def run(workload: str, nworld: int, blocks: int, steps: int) -> dict[str, float]:
    """Median seconds per step of each kind over interleaved blocks."""
    built = {kind: build(kind, workload) for kind in KINDS}
    datas = {kind: _data(built[kind][1], nworld) for kind in KINDS}
    times: dict[str, list[float]] = {kind: [] for kind in KINDS}
    for kind in KINDS:  # compile every kernel first
        model, mj_model, ctrl = built[kind]
        _block(kind, model, datas[kind], ctrl, mj_model.nu, 0, 2, mj_model.opt.timestep)
    for b in range(blocks):
        for kind in KINDS if b % 2 == 0 else reversed(KINDS):
            model, mj_model, ctrl = built[kind]
            seconds = _block(
                kind, model, datas[kind], ctrl, mj_model.nu, 2 + b * steps, steps, mj_model.opt.timestep
            )
            times[kind].append(seconds)
    return {kind: statistics.median(values) for kind, values in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nworld", default="1,64", help="comma-separated world counts")
    parser.add_argument("--blocks", type=int, default=21)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--workload", default="floor,fixed", help="floor, fixed or both")
    args = parser.parse_args()
    if not GO2.is_file():
        print(f"skipped: needs the Menagerie Go2 at {GO2} (../shared/data)")
        return
    import warp as wp

    wp.config.quiet = True
    device = wp.get_device()
    print(f"device {device} ({'GPU' if device.is_cuda else 'CPU: GPU numbers not measured'}), "
          f"{args.blocks} blocks x {args.steps} steps, medians")  # fmt: skip
    for workload in args.workload.split(","):
        for nworld in (int(n) for n in args.nworld.split(",")):
            result = run(workload, nworld, args.blocks, args.steps)
            ms = {kind: 1e3 * seconds for kind, seconds in result.items()}
            per_step = ", ".join(f"{kind} {ms[kind]:.3f} ms" for kind in KINDS)
            ratios = f"envelope/position {ms['envelope'] / ms['position']:.3f}x, "
            ratios += f"envelope/motor {ms['envelope'] / ms['motor']:.3f}x"
            print(f"{workload:5s} nworld {nworld:4d}: {per_step} per step; {ratios}")


if __name__ == "__main__":
    main()

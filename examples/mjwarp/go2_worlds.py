"""The Menagerie Go2 with envelope drives in MuJoCo Warp, a different knee envelope in each world.

Equips the Go2 (``../shared/data/menagerie/go2.xml``, base welded, contacts off) with one envelope
drive per joint (``drive_envelope.mujoco.add_drive``), puts it on the Warp device with
``drive_envelope.mjwarp.put_model`` (one ``actuator_dynprm`` row per world), draws each world's
knee envelope (max_effort +-30 %, max_actuator_velocity +-15 %) with ``set_envelope(world=...)``,
runs fast squats (30 rad/s) in every world at once and prints each world's knee envelope beside the knees'
peak effort and speed. Runs on the CPU (Warp's CPU device) or a GPU.

    .venv/bin/python examples/mjwarp/go2_worlds.py [--nworld 8] [--steps 600]
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import numpy as np

from drive_envelope import PerformanceEnvelope
from drive_envelope.mjwarp import put_model, set_envelope
from drive_envelope.mujoco import add_drive, load_plugin

GO2 = Path(__file__).resolve().parents[3] / "shared" / "data" / "menagerie" / "go2.xml"
HIP = PerformanceEnvelope(max_effort=23.7, max_actuator_velocity=30.1, speed_effort_gradient=0.5)
KNEE = PerformanceEnvelope(max_effort=35.55, max_actuator_velocity=20.07, velocity_dependent_resistance=0.1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nworld", type=int, default=8)
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--model", type=Path, default=GO2, help=f"the Menagerie go2.xml (default {GO2})")
    args = parser.parse_args()
    import mujoco
    import mujoco_warp
    import warp as wp

    if not args.model.is_file():
        raise SystemExit(
            f"needs the Menagerie Go2 at {args.model}: get unitree_go2/go2.xml from mujoco_menagerie "
            "and give it with --model"
        )
    wp.config.log_level = logging.WARNING  # stdout: only what the example prints
    load_plugin()
    spec = mujoco.MjSpec.from_file(str(args.model))
    for joint in list(spec.body("base").joints):
        spec.delete(joint)
    for key in list(spec.keys):
        spec.delete(key)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    joints = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    for joint in joints:
        envelope = KNEE if "calf" in joint else HIP
        add_drive(spec, joint, envelope=envelope, stiffness=300, damping=3, replace=True, effort_sensor=False)
    mj_model = spec.compile()
    m = put_model(spec, batch_sizes={"actuator_dynprm": args.nworld})

    rng = np.random.default_rng(0)
    # each joint's drive is the actuator it replaced (same name, e.g. FL_calf)
    trnid = mj_model.actuator_trnid[:, 0]
    drive_of = {
        j: mj_model.actuator(int(np.flatnonzero(trnid == mj_model.joint(j).id)[0])).name for j in joints
    }
    knees = [j for j in joints if "calf" in j]
    drawn = []
    for world in range(args.nworld):
        envelope = PerformanceEnvelope(
            max_effort=KNEE.max_effort * rng.uniform(0.7, 1.3),
            max_actuator_velocity=KNEE.max_actuator_velocity * rng.uniform(0.85, 1.15),
            velocity_dependent_resistance=KNEE.velocity_dependent_resistance,
        )
        for knee in knees:
            set_envelope(m, drive_of[knee], envelope, world=world)
        drawn.append(envelope)

    d = mujoco_warp.make_data(mj_model, nworld=args.nworld)
    ids = [mj_model.joint(j).id for j in joints]
    qpos = np.tile(mj_model.qpos0, (args.nworld, 1))
    qpos[:, mj_model.jnt_qposadr[ids]] = np.array([0.0, 0.9, -1.8] * 4)
    d.qpos.assign(qpos.astype(np.float32))
    knee_dof = mj_model.jnt_dofadr[[mj_model.joint(j).id for j in knees]]
    knee_act = [mj_model.actuator(drive_of[j]).id for j in knees]
    peak_effort = np.zeros(args.nworld)
    peak_speed = np.zeros(args.nworld)
    h = mj_model.opt.timestep
    for step in range(args.steps):
        t = step * h
        wave = np.tile([0.4 * np.sin(9 * t), 0.8 * np.sin(30 * t), 0.9 * np.sin(30 * t + 1)], 4)
        ctrl = np.zeros((args.nworld, mj_model.nu), dtype=np.float32)
        ctrl[:, mj_model.actuator_ctrladr[[mj_model.actuator(drive_of[j]).id for j in joints]]] = (
            np.array([0.0, 0.9, -1.8] * 4) + min(t / 0.2, 1.0) * wave
        )
        d.ctrl.assign(ctrl)
        mujoco_warp.step(m, d)
        peak_effort = np.maximum(peak_effort, np.abs(d.actuator_force.numpy()[:, knee_act]).max(axis=1))
        peak_speed = np.maximum(peak_speed, np.abs(d.qvel.numpy()[:, knee_dof]).max(axis=1))
    print("world  knee max_effort [N*m]  peak |effort|  knee max_actuator_velocity [rad/s]  peak |speed|")
    for world, envelope in enumerate(drawn):
        print(
            f"{world:5d}  {envelope.max_effort:22.2f}  {peak_effort[world]:13.2f}  "
            f"{envelope.max_actuator_velocity:35.2f}  {peak_speed[world]:12.2f}"
        )


if __name__ == "__main__":
    main()

"""How well the plugin keeps a legged robot inside its envelopes: samples outside, per integrator.

The Menagerie Unitree Go2 (``../shared/data/menagerie``; the example quadruped when that is absent)
gets one ``add_drive`` per joint (kp 300 N*m/rad, kv 3 N*m*s/rad; 23.7 N*m / 30.1 rad/s at hips and
thighs with a speed-torque gradient, 35.55 N*m / 20.07 rad/s at the knees with a velocity-dependent
resistance) and squats at 14 rad/s and at 30 rad/s (beyond what its knees can follow). Each run is
3000 steps of 2 ms, checked with ``drive_envelope.analysis.check_samples`` (the ``check`` command's
rule: outside = a margin below -1e-6 of its cap; released = zero effort above the no-load speed).

* fixed base: the free joint removed, contacts off (joint damping, armature, friction loss and
  limits kept, and also without friction loss and limits): the drives are the only actuation, so
  the coupled solve is exact up to MuJoCo's constraints (goal <= 0.1 % outside).
* floor: the free base on the floor; contacts are solved after the actuators, so an impact can move
  a joint past its envelope for a step: the fraction is reported, not a goal.

    .venv/bin/python benchmarks/bench_mujoco_envelope.py
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MENAGERIE = ROOT.parent / "shared" / "data" / "menagerie"
HOME = np.array([0.0, 0.9, -1.8] * 4)


def _envelopes(joints: list[str]) -> list[Any]:
    from drive_envelope import PerformanceEnvelope

    hip = PerformanceEnvelope(max_effort=23.7, max_actuator_velocity=30.1, speed_effort_gradient=0.5)
    knee = PerformanceEnvelope(
        max_effort=35.55, max_actuator_velocity=20.07, velocity_dependent_resistance=0.1
    )
    return [knee if ("calf" in j or "knee" in j) else hip for j in joints]


def _spec(base: str, constraints: bool) -> tuple[Any, str]:
    import mujoco

    if MENAGERIE.is_dir():
        spec = mujoco.MjSpec.from_file(str(MENAGERIE / ("go2.xml" if base == "fixed" else "scene_floor.xml")))
        label = "Go2"
        if base == "fixed":
            for joint in list(spec.body("base").joints):
                spec.delete(joint)
    else:
        sys.path.insert(0, str(ROOT / "examples" / "mujoco"))
        import quadruped

        spec = quadruped.build_quadruped("position", fixed_base=base == "fixed")
        label = "example quadruped"
    for key in list(spec.keys):
        spec.delete(key)
    if base == "fixed":
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    if not constraints:
        spec.option.disableflags |= int(
            mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS | mujoco.mjtDisableBit.mjDSBL_LIMIT
        )
    return spec, label


def run(base: str, integrator: str, speed: float, constraints: bool = True) -> dict[str, Any]:
    """One squat run; returns the counts and the worst violation (relative to the cap)."""
    import mujoco

    from drive_envelope.analysis import check_samples
    from drive_envelope.mujoco import add_drive

    spec, label = _spec(base, constraints)
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    joints = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    envelopes = _envelopes(joints)
    for joint, env in zip(joints, envelopes, strict=True):
        add_drive(spec, joint, envelope=env, stiffness=300, damping=3, replace=True, effort_sensor=False)
    model = spec.compile()
    data = mujoco.MjData(model)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
    dof, qadr = model.jnt_dofadr[ids], model.jnt_qposadr[ids]
    actuators = [int(np.flatnonzero(model.actuator_trnid[:, 0] == j)[0]) for j in ids]
    data.qpos[qadr] = HOME
    if base != "fixed":
        data.qpos[2] = 0.3
    steps = 3000
    velocity, effort, sweeps = np.zeros((steps, 12)), np.zeros((steps, 12)), np.zeros(steps)
    for k in range(steps):
        t = data.time
        wave = np.array([0.3 * np.sin(9 * t), 0.6 * np.sin(speed * t), 0.9 * np.sin(speed * t + 1)])
        data.ctrl[model.actuator_ctrladr[actuators]] = HOME + min(t / 0.3, 1.0) * np.tile(wave, 4)
        mujoco.mj_step(model, data)
        velocity[k], effort[k], sweeps[k] = (
            data.qvel[dof],
            data.actuator_force[actuators],
            data.plugin_state[0],
        )
    checks = [check_samples(env, velocity[:, i], effort[:, i]) for i, env in enumerate(envelopes)]
    worst = [c.worst.relative for c in checks if c.worst is not None]
    return {
        "robot": label,
        "samples": sum(c.samples for c in checks),
        "outside": sum(c.samples_outside for c in checks),
        "released": sum(c.samples_released for c in checks),
        "worst": max(worst) if worst else 0.0,
        "sweeps": (float(np.mean(sweeps)), int(sweeps.max())),
    }


def main() -> int:
    import mujoco

    from drive_envelope.mujoco import load_plugin

    load_plugin()
    print(
        f"mujoco {mujoco.__version__}; squats, 3000 steps of 2 ms, 12 drives; "
        "outside = margin < -1e-6 of the cap"
    )
    cases = [
        ("fixed", "euler", 14.0, True),
        ("fixed", "euler", 30.0, True),
        ("fixed", "euler", 30.0, False),
        ("fixed", "implicitfast", 30.0, True),
        ("fixed", "implicit", 30.0, True),
        ("floor", "euler", 14.0, True),
        ("floor", "euler", 30.0, True),
        ("floor", "implicitfast", 30.0, True),
    ]
    for base, integrator, speed, constraints in cases:
        r = run(base, integrator, speed, constraints)
        extra = "" if constraints else ", no friction loss/limits"
        print(
            f"  {r['robot']} {base:5s} {integrator:12s} {speed:4.0f} rad/s{extra:26s}: "
            f"{r['outside']:5d} of {r['samples']} outside ({100 * r['outside'] / r['samples']:.3f} %, "
            f"worst {100 * r['worst']:.2f} % of the cap), {r['released']} released; "
            f"solve iterations mean {r['sweeps'][0]:.2f} max {r['sweeps'][1]}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

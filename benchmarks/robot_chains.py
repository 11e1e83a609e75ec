"""Robot-scale chain scenarios built from real assets (issue 21): the FR3 arm and the Go2 leg set.

The scenarios are generated from the assets in ``../shared/data`` (never copied into the
repository) by the importers, with drives and envelopes from the catalog:

* ``fr3``: Franka FR3, 7 DOF, from Newton's ``newton-assets/fr3/fr3.urdf`` (the same numbers as
  its USD conversion ``fr3_usd/fr3.usda``: ``tests/test_robot_chains.py`` compares them).
  Envelopes ``franka-fr3-joint1-4`` / ``-joint5-7`` / ``-joint6`` (87 N*m 2.62 rad/s, 12 N*m
  5.26 and 4.18 rad/s). Gains 400 N*m/rad and 40 N*m*s/rad on joints 1-4, 50 and 5 on 5-7. From
  an elbow-bent pose, joint 2 (the shoulder pitch) drives 1.4 rad down with gravity helping: it
  saturates at 87 N*m, meets its 2.62 rad/s line and PhysX lets go; the others hold their pose.
* ``go2_legs``: Unitree Go2's four legs (12 DOF, a tree on the base) from Menagerie's
  ``menagerie/go2.xml`` compiled by MuJoCo, the free joint dropped (base fixed in the air),
  armature 0.01 from the model, damping and frictionloss off. Envelopes ``unitree-go-m8010-6``
  (hip and thigh, 23.7 N*m, 30.1 rad/s) and ``unitree-go2-calf`` (45.43 N*m, 15.7 rad/s), gains
  25 N*m/rad and 0.5 N*m*s/rad (Isaac Lab's Go2 values). The front-left leg starts raised
  forward and its calf is driven down with gravity helping: it meets the 15.7 rad/s line and
  lets go; the other legs hold a standing pose.

No contacts and no joint limits (the stands have none). Each scenario comes in PhysX's PGS 1/0
and TGS 4/1. Write one as JSON (a scenario file ``simulate`` reads):

    .venv/bin/python benchmarks/robot_chains.py fr3 --solver tgs -o fr3_tgs.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
FR3_URDF = DATA / "newton-assets" / "fr3" / "fr3.urdf"
FR3_USD = DATA / "newton-assets" / "fr3" / "fr3_usd" / "fr3.usda"
GO2_MJCF = DATA / "menagerie" / "go2.xml"
SOLVERS = {"pgs": (1, 0), "tgs": (4, 1)}
"""PhysX's solver and its (position, velocity) iteration counts for each scenario."""

FR3_POSE = (0.0, 0.3, 0.0, -1.2, 0.0, 1.5, 0.0)
"""FR3 initial joint positions [rad]: the elbow bent, the upper arm slightly forward."""
FR3_DRIVEN = 1
"""The FR3 joint that meets its speed line (joint 2, index 1); its target is 1.4 rad further."""
GO2_POSE = {"hip": 0.0, "thigh": 0.8, "calf": -1.5}
"""Go2 standing joint positions [rad] held by every leg but the driven one."""
GO2_DRIVEN = ("FL_thigh_joint", -1.2, "FL_calf_joint", -2.4, 0.0)
"""The driven leg: its thigh held at -1.2 rad (raised forward), its calf from -2.4 rad (folded)
toward 0 (straight)."""


def _simulation(solver: str, duration: float, dt: float) -> dict[str, Any]:
    position, velocity = SOLVERS[solver]
    return {"dt": dt, "duration": duration, "solver": solver, "position_iterations": position,
            "velocity_iterations": velocity}  # fmt: skip


def fr3_mapping(solver: str = "pgs", urdf: Path = FR3_URDF) -> dict[str, Any]:
    """The FR3 stand as a scenario mapping (``[simulation]`` and ``[[joints]]``)."""
    from drive_envelope._src.scenario.import_urdf import urdf_joints

    entries = urdf_joints(urdf)
    catalog = ["franka-fr3-joint1-4"] * 4 + [
        "franka-fr3-joint5-7",
        "franka-fr3-joint6",
        "franka-fr3-joint5-7",
    ]
    for index, entry in enumerate(entries):
        q0 = FR3_POSE[index]
        stiffness, damping = (400.0, 40.0) if index < 4 else (50.0, 5.0)
        target = q0 + 1.4 if index == FR3_DRIVEN else q0
        entry["initial_position"] = q0
        entry["drive"] = {"stiffness": stiffness, "damping": damping, "target_position": target}
        entry["envelope"] = {"datasheet": catalog[index]}
    return {
        "name": f"FR3 7-DOF ({solver.upper()} {'/'.join(map(str, SOLVERS[solver]))})",
        "description": f"Franka FR3 from {urdf.name}; joint 2 meets its speed line",
        "simulation": _simulation(solver, 0.5, 1.0 / 240.0),
        "joints": entries,
    }


def go2_mapping(solver: str = "pgs", mjcf: Path = GO2_MJCF) -> dict[str, Any]:
    """The Go2 leg set (fixed base) as a scenario mapping."""
    from drive_envelope._src.adapters.mujoco.chain_import import mjcf_joints

    entries = mjcf_joints(mjcf)
    thigh, thigh_q, calf, calf_q, calf_target = GO2_DRIVEN
    for entry in entries:
        name = str(entry["name"])
        kind = next(part for part in GO2_POSE if f"_{part}_" in name)
        q0 = {thigh: thigh_q, calf: calf_q}.get(name, GO2_POSE[kind])
        target = calf_target if name == calf else q0
        entry["initial_position"] = q0
        entry["drive"] = {"stiffness": 25.0, "damping": 0.5, "target_position": target}
        entry["envelope"] = {"datasheet": "unitree-go2-calf" if kind == "calf" else "unitree-go-m8010-6"}
    return {
        "name": f"Go2 legs 12-DOF ({solver.upper()} {'/'.join(map(str, SOLVERS[solver]))})",
        "description": f"Unitree Go2 legs from {mjcf.name}, base fixed; FL calf meets its speed line",
        "simulation": _simulation(solver, 0.4, 1.0 / 200.0),
        "joints": entries,
    }


ROBOTS = {"fr3": (fr3_mapping, FR3_URDF), "go2_legs": (go2_mapping, GO2_MJCF)}
"""Each robot stand: its mapping builder and the asset it needs."""


def available(robot: str) -> bool:
    """Whether the robot's asset is in ../shared/data (a user's clone has none)."""
    return ROBOTS[robot][1].is_file()


def scenario(robot: str, solver: str) -> Any:
    """The robot stand as a :class:`ChainScenario`."""
    from drive_envelope._src.scenario.chain import chain_from_mapping

    build, asset = ROBOTS[robot]
    return chain_from_mapping(build(solver), source=str(asset), base_dir=ROOT, default_name=robot)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", choices=sorted(ROBOTS))
    parser.add_argument("--solver", choices=sorted(SOLVERS), default="pgs")
    parser.add_argument("-o", "--output", default="-", help="JSON file (default: stdout)")
    args = parser.parse_args()
    if not available(args.robot):
        sys.exit(f"{ROBOTS[args.robot][1]}: not found (the assets live in ../shared/data)")
    text = json.dumps(ROBOTS[args.robot][0](args.solver), indent=1, allow_nan=False) + "\n"
    if args.output == "-":
        sys.stdout.write(text)
    else:
        Path(args.output).write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()

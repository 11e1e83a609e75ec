"""ANYmal C in Newton with the PhysX performance envelope of every leg drive, read from its USD.

1. ``drive-envelope usd apply`` writes the envelopes of ``anymal_map.toml`` into a small layer over
   Newton's ``anymal_c.usd`` (the asset itself is not touched).
2. ``builder.add_usd`` loads the robot (base fixed, as on a test rig) and
   ``drive_envelope.newton.add_envelopes_from_usd`` adds ``DrivePD`` + ``ClampingPerformanceEnvelope``
   on each of the 12 leg DOFs, turning Newton's own joint drive off there.
3. The legs swing towards a fast sine target (0.7 rad at 2.5 Hz) with stiff gains in Newton's
   implicit effort mode, with
   gravity passed as ``bias_force`` (``BiasForce``), on ``SolverFeatherstone``.

It prints each leg's peak effort and speed, the steps on which the envelope bounded the effort, and
the largest ``|effort| - L(v_end)``: the envelope's limit at the end-of-step velocity is never
exceeded (float32 rounding aside). A hip whipped by its own leg can pass max_actuator_velocity
(peak |v| above the speed limit): there the envelope allows no effort and the joint coasts, as in
PhysX.

Run: ``python examples/newton/anymal_envelopes.py [--asset PATH/anymal_c.usd]`` (needs the
``newton`` and ``usd`` extras; the asset is in Newton's repository, newton-physics/newton-assets).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DEFAULT_ASSET = HERE.parents[1].parent / "shared" / "data" / "newton-assets" / "anymal_c.usd"


def apply_envelopes(asset: Path, folder: Path) -> Path:
    """Run ``drive-envelope usd apply`` (the command line, as a user would) into ``folder``."""
    layer = folder / "anymal_envelope.usda"
    command = [
        sys.executable,
        "-m",
        "drive_envelope",
        "usd",
        "apply",
        str(asset),
        "--map",
        str(HERE / "anymal_map.toml"),
        "-o",
        str(layer),
    ]
    subprocess.run(command, check=True, capture_output=True, text=True)
    return layer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--asset", type=Path, default=DEFAULT_ASSET, help="anymal_c.usd")
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated time [s] (default 1)")
    parser.add_argument("--dt", type=float, default=0.002, help="time step [s] (default 0.002)")
    args = parser.parse_args()
    if not args.asset.is_file():
        sys.exit(f"{args.asset}: no such file (get anymal_c.usd from newton-physics/newton-assets)")

    import newton
    from newton.actuators import Actuator, JointSpaceResponse

    from drive_envelope.newton import BiasForce, add_envelopes_from_usd
    from drive_envelope.usd import register_schemas

    register_schemas()  # before Newton opens the stage: USD builds its schema registry once
    with tempfile.TemporaryDirectory() as folder:
        layer = apply_envelopes(args.asset, Path(folder))
        builder = newton.ModelBuilder()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Newton's notes on the asset's visual materials
            builder.add_usd(str(layer), floating=False)
        added = sorted(add_envelopes_from_usd(builder, layer), key=lambda a: a.dof_index)
    model = builder.finalize(device="cpu")
    actuator = model.actuators[0]
    actuator.drive.kp.assign(np.full(len(added), 600.0, dtype=np.float32))  # the asset's gains are 0
    actuator.drive.kd.assign(np.full(len(added), 10.0, dtype=np.float32))
    response = JointSpaceResponse(model)
    options = Actuator.ImplicitOptions(residual_tol=1e-9, update_tol=1e-9, max_iters=32)
    actuator.set_effort_mode_implicit(response=response, options=options)
    solver = newton.solvers.SolverFeatherstone(model)
    bias = BiasForce(model)
    state, next_state, control = model.state(), model.state(), model.control()
    dofs = np.array([a.dof_index for a in added])
    coords = np.array([a.coord_index for a in added])
    steps = round(args.seconds / args.dt)
    efforts, speeds = np.zeros((steps, len(added))), np.zeros((steps, len(added)))
    target = np.zeros(model.joint_coord_count, dtype=np.float32)
    for step in range(steps):
        target[coords] = 0.7 * np.sin(2.0 * np.pi * 2.5 * step * args.dt)
        control.joint_target_q.assign(target)
        control.joint_f.zero_()
        response.refresh(state)
        actuator.step(state, control, dt=args.dt, bias_force=bias.compute(state))
        efforts[step] = control.joint_f.numpy()[dofs]
        solver.step(state, next_state, control, None, args.dt)
        state, next_state = next_state, state
        speeds[step] = state.joint_qd.numpy()[dofs]
    print(f"{len(added)} envelope actuators from {args.asset.name}; {steps} steps of {args.dt * 1e3:g} ms")
    print(
        f"{'joint':<24} {'max_effort':>10} {'peak |effort|':>13} {'peak |v|':>9} {'on envelope':>11} "
        f"{'max |effort| - L(v_end)':>23}"
    )
    for k, record in enumerate(added):
        gap = np.abs(efforts[:, k]) - record.envelope.effort_limit(speeds[:, k])
        on = int(np.count_nonzero(gap > -1e-3))  # steps the envelope bounded the effort
        print(
            f"{record.joint_path:<24} {record.envelope.max_effort:>10.4g} "
            f"{np.abs(efforts[:, k]).max():>13.4g} "
            f"{np.abs(speeds[:, k]).max():>9.4g} {on:>11d} {gap.max():>23.2e}"
        )


if __name__ == "__main__":
    main()

"""The Newton route on Isaac Lab 3.0's PhysX-family path: ``NewtonActuatorAdapter.from_usd``, on CPU.

PhysX and OVPhysX have no Newton ``Model``: Isaac Lab builds Newton actuators from the
``NewtonActuator`` prims itself (``isaaclab.actuators.newton.adapter._create_actuators_from_usd``)
and steps them before the PhysX step. A PhysX scene needs Isaac Sim (not on the package index), so
this test takes the route up to the step: Newton's cartpole on an in-memory stage, Isaac Lab's own
authoring of an ``IdealPDActuatorCfg`` (``author_actuator_prims``), ``author_envelope_clamping``,
``from_usd``, then ``adapter.step`` on joint states chosen to cross every side of the envelope.
The reference is computed here by hand: PD ``kp (q* - q) - kd qd``, Isaac Lab's max-effort clip,
then the float64 NumPy envelope clamp.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

pytest.importorskip("isaaclab.actuators.newton", reason="needs Isaac Lab 3.x: scripts/test_isaaclab3.sh")

# registered before any USD stage exists: USD builds its schema registry once, on first use
from drive_envelope.isaaclab import author_envelope_clamping, register_envelope_clamping

register_envelope_clamping()

CARTPOLE = Path(__file__).resolve().parents[3] / "shared" / "data" / "newton-assets" / "cartpole.usda"
ENVELOPE: dict[str, Any] = {
    "max_effort": 5.0,
    "max_actuator_velocity": 3.0,
    "velocity_dependent_resistance": 0.5,
    "speed_effort_gradient": 0.25,
}
KP, KD, CAP, NUM_ENVS = 50.0, 2.0, 10.0, 4


def _stage_with_cartpole() -> Any:
    """An in-memory stage referencing the asset (the file's layer stays untouched)."""
    from pxr import Usd

    stage = Usd.Stage.CreateInMemory()
    stage.DefinePrim("/World/Robot").GetReferences().AddReference(str(CARTPOLE))
    return stage


@pytest.mark.skipif(not CARTPOLE.is_file(), reason=f"needs {CARTPOLE} (Newton's example assets)")
def test_from_usd_builds_and_steps_the_envelope_clamping_stage() -> None:
    """The adapter PhysX/OVPhysX use builds our stage; its output is the hand-computed clamp."""
    import warp as wp
    from isaaclab.actuators import IdealPDActuatorCfg
    from isaaclab.actuators.newton.adapter import NewtonActuatorAdapter
    from isaaclab.sim.schemas.schemas_actuators import author_actuator_prims

    import drive_envelope as de
    from drive_envelope.newton import ClampingPerformanceEnvelope

    stage = _stage_with_cartpole()
    cfg = IdealPDActuatorCfg(joint_names_expr=[".*"], stiffness=KP, damping=KD, actuator_effort_limit=CAP)
    author_actuator_prims(stage, "/World/Robot", {"all": cfg})
    authored = author_envelope_clamping(stage, "/World/Robot", ENVELOPE, joint_names_expr=".*Pole.*")
    assert [p.rsplit("/", 1)[-1] for p in authored] == [
        "all_cartPoleJoint_actuator",
        "all_polePoleJoint_actuator",
    ]
    joints = ["railCartJoint", "cartPoleJoint", "polePoleJoint"]
    adapter = NewtonActuatorAdapter.from_usd(
        stage, joints, NUM_ENVS, 3, "cpu", articulation_prim_path="/World/Robot"
    )
    kinds = sorted(tuple(type(c).__name__ for c in a.clamping or []) for a in adapter.actuators)
    assert kinds == [("ClampingMaxEffort",), ("ClampingMaxEffort", "ClampingPerformanceEnvelope")]
    assert any(
        isinstance(c, ClampingPerformanceEnvelope) for a in adapter.actuators for c in a.clamping or []
    )

    rng = np.random.default_rng(7)
    n = NUM_ENVS * 3
    q = rng.uniform(-1.0, 1.0, n).astype(np.float32)
    # below and above max_actuator_velocity, both signs, at rest: every side of the envelope (n = 12)
    qd = np.array([-4.0, -2.5, -1.0, 0.0, 0.5, 1.5, 2.9, 3.5, 2.0, -0.2, 0.0, 1.0], np.float32)
    target = rng.uniform(-1.0, 1.0, n).astype(np.float32)
    state = SimpleNamespace(joint_q=wp.array(q, device="cpu"), joint_qd=wp.array(qd, device="cpu"))
    control = SimpleNamespace(
        joint_target_pos=wp.array(target, device="cpu"),
        joint_target_vel=wp.zeros(n, dtype=wp.float32, device="cpu"),
        joint_f=wp.zeros(n, dtype=wp.float32, device="cpu"),
    )
    adapter.finalize(control)
    adapter.step(state, control, 1.0 / 120.0)

    pd = KP * (target.astype(np.float64) - q) - KD * qd.astype(np.float64)
    capped = np.clip(pd, -CAP, CAP)
    pole = np.tile([False, True, True], NUM_ENVS)
    reference = np.where(
        pole, de.clamp_effort(de.PerformanceEnvelope(**ENVELOPE), capped, qd.astype(np.float64)), capped
    )
    applied = control.joint_f.numpy().astype(np.float64)
    np.testing.assert_allclose(applied, reference, rtol=1e-5, atol=1e-4)
    assert int((np.abs(applied[pole]) < np.abs(capped[pole]) - 1e-3).sum()) >= 3  # the envelope bound
    np.testing.assert_allclose(adapter.computed_effort_2d.numpy().ravel(), pd, rtol=1e-5, atol=1e-4)


@pytest.mark.skipif(not CARTPOLE.is_file(), reason=f"needs {CARTPOLE} (Newton's example assets)")
def test_errors_where_isaac_lab_cannot_take_the_envelope() -> None:
    """Our explicit cfg is refused on the Newton-actuator path; no prims: a one-line InputError."""
    from isaaclab.sim.schemas.schemas_actuators import validate_newton_native_actuator_cfgs

    from drive_envelope import InputError
    from drive_envelope.isaaclab import PerformanceEnvelopeActuatorCfg

    ours = PerformanceEnvelopeActuatorCfg(
        joint_names_expr=[".*"],
        stiffness=KP,
        damping=KD,
        actuator_effort_limit=5.0,
        max_actuator_velocity=3.0,
    )
    with pytest.raises(ValueError, match=r"does not support 'legs' \(PerformanceEnvelopeActuatorCfg\)"):
        validate_newton_native_actuator_cfgs({"legs": ours})
    stage = _stage_with_cartpole()  # no NewtonActuator prims: use_newton_actuators=False authors none
    with pytest.raises(InputError, match=r"no active NewtonActuator prim under '/World/Robot'"):
        author_envelope_clamping(stage, "/World/Robot", ENVELOPE)
    with pytest.raises(InputError, match=r"articulation_prim_path '/World/Nope': no such prim"):
        author_envelope_clamping(stage, "/World/Nope", ENVELOPE)
    with pytest.raises(InputError, match=r"envelope: .*unknown argument 'max_torque'"):
        author_envelope_clamping(stage, "/World/Robot", {"max_torque": 5.0})


def test_registering_after_usd_built_its_schema_registry_says_so() -> None:
    """USD reads plugins into its schema registry once: too late is a one-line InputError (fresh process)."""
    import subprocess
    import sys

    code = (
        "from pxr import Usd\n"
        "Usd.SchemaRegistry().FindAppliedAPIPrimDefinition('NewtonPDControlAPI')\n"
        "from drive_envelope import InputError\n"
        "from drive_envelope.isaaclab import register_envelope_clamping\n"
        "try:\n"
        "    register_envelope_clamping()\n"
        "except InputError as exc:\n"
        "    print(exc)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    line = out.stdout.strip()
    assert "\n" not in line and line.startswith(
        "register_envelope_clamping: USD's schema registry was built before"
    )
    assert "PXR_PLUGINPATH_NAME=" in line

"""``DriveEnvelopeClampingAPI`` read by plain Newton (``.venv``'s newton, 1.8) through ``add_usd``.

The same schema and component Isaac Lab 3.0's Newton route uses (``tests/isaaclab3`` runs them on
newton 1.6.1): a ``NewtonActuator`` prim authored by hand on Newton's cartpole (no Isaac Lab here),
the envelope applied by ``author_envelope_clamping``, ``ModelBuilder.add_usd`` builds
``model.actuators`` with our stage, and one actuator step gives the float64 NumPy clamp of the PD
effort ``kp (q* - q) - kd qd`` at the joint velocity.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("newton.actuators")
pytest.importorskip("pxr")

# first: USD builds its schema registry once, at the first schema query
from drive_envelope.isaaclab import author_envelope_clamping, register_envelope_clamping

register_envelope_clamping()

CARTPOLE = Path(__file__).resolve().parents[2] / "shared" / "data" / "newton-assets" / "cartpole.usda"
ENVELOPE: dict[str, Any] = {
    "max_effort": 5.0,
    "max_actuator_velocity": 3.0,
    "velocity_dependent_resistance": 0.5,
}
KP, KD = 50.0, 2.0


@pytest.mark.skipif(not CARTPOLE.is_file(), reason=f"needs {CARTPOLE} (Newton's example assets)")
def test_add_usd_builds_the_envelope_stage_and_steps_the_clamp() -> None:
    """One prim, one DOF: Newton's actuator output is the reference clamp over a velocity sweep."""
    import newton
    import warp as wp
    from pxr import Sdf, Usd

    import drive_envelope as de
    from drive_envelope.newton import ClampingPerformanceEnvelope

    stage = Usd.Stage.CreateInMemory()
    stage.DefinePrim("/World/Robot").GetReferences().AddReference(str(CARTPOLE))
    joint = next(p for p in stage.Traverse() if p.GetName() == "cartPoleJoint")
    prim = stage.DefinePrim("/World/Robot/pole_actuator", "NewtonActuator")
    prim.AddAppliedSchema("NewtonPDControlAPI")
    prim.CreateRelationship("newton:targets").SetTargets([joint.GetPath()])
    prim.CreateAttribute("newton:kp", Sdf.ValueTypeNames.Float).Set(KP)
    prim.CreateAttribute("newton:kd", Sdf.ValueTypeNames.Float).Set(KD)
    assert author_envelope_clamping(stage, "/World/Robot", ENVELOPE) == ["/World/Robot/pole_actuator"]

    builder = newton.ModelBuilder()
    builder.add_usd(stage)
    model = builder.finalize(device="cpu")
    (actuator,) = model.actuators
    assert len(actuator.clamping or []) == 1
    assert isinstance(actuator.clamping[0], ClampingPerformanceEnvelope)
    dof = int(actuator.indices.numpy()[0])
    coordinate = int(actuator.pos_indices.numpy()[0])
    target_slot = int(actuator.target_pos_indices.numpy()[0])
    target_attr = actuator.control_target_pos_attr

    envelope = de.PerformanceEnvelope(**ENVELOPE)
    bound = 0
    for qd_value, target in [(0.0, 1.0), (2.0, 1.0), (-2.0, 1.0), (3.5, -1.0), (-1.0, -0.02)]:
        state: Any = model.state()
        control: Any = model.control()
        qd = state.joint_qd.numpy()
        qd[dof] = qd_value
        state.joint_qd = wp.array(qd, dtype=wp.float32, device="cpu")
        tq = getattr(control, target_attr).numpy()
        tq[target_slot] = target
        setattr(control, target_attr, wp.array(tq, dtype=wp.float32, device="cpu"))
        q = float(state.joint_q.numpy()[coordinate])
        actuator.step(state, control, actuator.state(), actuator.state(), dt=1.0 / 120.0)
        pd = KP * (np.float64(np.float32(target)) - q) - KD * qd_value
        reference = float(de.clamp_effort(envelope, np.array([pd]), np.array([qd_value]))[0])
        assert float(control.joint_f.numpy()[dof]) == pytest.approx(reference, rel=1e-5, abs=1e-4)
        bound += abs(reference) < abs(pd) - 1e-3
    assert bound >= 4  # the envelope, not the PD law, set those efforts

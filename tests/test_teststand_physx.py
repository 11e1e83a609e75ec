"""The reference engine against real PhysX (ovphysx 0.7, CPU) on every bundled scenario.

``plain_drive_applied_effort`` (no envelope API) included: ovphysx 0.7 limits drive + applied joint
force together to +-maxForce, as the reference does (ovphysx 0.3.7 clamped the drive alone).

PhysX computes in float32, so agreement is to float32 precision amplified by the dynamics: the
scenarios that brake along eq. 2 amplify 1e-6 noise about a thousandfold, hence the tolerance
relative to each column's range.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.scenario.spec import load_scenario
from drive_envelope._src.scenario.trajectory import Trajectory
from drive_envelope._src.teststand.engines.reference import simulate

pytestmark = [pytest.mark.physx, pytest.mark.usd, pytest.mark.slow]

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
PATHS = sorted(EXAMPLES.glob("*.toml"))


@pytest.mark.parametrize("path", PATHS, ids=lambda p: p.stem)
def test_reference_matches_physx(path: Path, bundled_physx_runs: dict[str, Trajectory]) -> None:
    """Match the reference engine's position, velocity and effort to PhysX's at float32-level precision.

    PhysX's runs are made once per test run (tests/conftest.py), for tests/test_parity_engines.py too.
    """
    reference, physx = simulate(load_scenario(path)), bundled_physx_runs[path.stem]
    for column in ("position", "velocity", "effort"):
        ours, theirs = getattr(reference, column), getattr(physx, column)
        scale = max(1.0, float(np.max(np.abs(ours))))
        np.testing.assert_allclose(theirs, ours, rtol=0.0, atol=3e-3 * scale, err_msg=column)


def _stand_stage(com: float):
    """The stand of a velocity drive at top speed (6 rad/s), the link's centre of mass ``com`` off axis."""
    from pxr import Gf, UsdPhysics

    from drive_envelope import PerformanceEnvelope
    from drive_envelope._src.adapters.physx.scene import LINK_PATH, build_teststand_stage
    from drive_envelope._src.scenario.spec import DriveSpec, JointSpec, Scenario, SimulationSpec

    scenario = Scenario(
        name="top_speed",
        joint=JointSpec(type="revolute", inertia=0.05),
        drive=DriveSpec(damping=1.0e3, target_velocity=100.0, max_effort=10.0),
        envelope=PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=6.0),
        simulation=SimulationSpec(dt=1 / 240, duration=0.5, solver="pgs", position_iterations=4),
    )
    stage = build_teststand_stage(scenario)
    UsdPhysics.MassAPI(stage.GetPrimAtPath(LINK_PATH)).GetCenterOfMassAttr().Set(Gf.Vec3f(com, 0.0, 0.0))
    return scenario, stage


def test_stand_link_has_its_centre_of_mass_on_the_joint_axis() -> None:
    """Build the stand so that PhysX's projected joint force is the drive + applied effort it logs."""
    from pxr import Gf, UsdPhysics

    from drive_envelope._src.adapters.physx.scene import JOINT_PATH, LINK_PATH
    from drive_envelope._src.adapters.physx.stand import EFFORT_SOURCE

    stage = _stand_stage(0.0)[1]
    com = UsdPhysics.MassAPI(stage.GetPrimAtPath(LINK_PATH)).GetCenterOfMassAttr().Get()
    joint = UsdPhysics.RevoluteJoint(stage.GetPrimAtPath(JOINT_PATH))
    assert joint.GetBody1Rel().GetTargets() == [LINK_PATH]
    assert com == Gf.Vec3f(0.0) and joint.GetLocalPos1Attr().Get() in (None, Gf.Vec3f(0.0))
    assert "centre of mass on the joint axis" in EFFORT_SOURCE


def test_projected_force_is_not_the_drive_effort_off_axis() -> None:
    """Show the caveat docs/usd.md states: off the axis, jointProjectedForce is not the drive's effort.

    At top speed the drive's effort is 0 (the velocity stays on maxActuatorVelocity: zero joint
    acceleration on a one-DOF fixed-base stand without gravity, so I_axis * dv/dt = 0); PhysX's
    projected joint force still reads the reaction of the whirling link.
    """
    import numpy as np

    from drive_envelope._src.adapters.physx.runner import PhysxJob, run_jobs

    results = []
    for com in (0.0, 0.3):
        scenario, stage = _stand_stage(com)
        sim = scenario.simulation
        job = PhysxJob(usda=stage.GetRootLayer().ExportToString(), joint="revolute", solver="pgs", dt=sim.dt,
                       steps=sim.steps, initial_position=0.0, initial_velocity=0.0, applied_effort=0.0,
                       external_effort=0.0)  # fmt: skip
        results.append(run_jobs([job])[0])
    on_axis, off_axis = results
    for run in results:
        assert run.velocity[-1] == pytest.approx(6.0, rel=1e-6)
        assert np.abs(np.diff(run.velocity[-20:])).max() == 0.0  # no acceleration: no drive effort
    assert abs(on_axis.effort[-1]) < 1e-9
    assert abs(off_axis.effort[-1]) > 1e-2  # the column would be wrong here: hence the stand's rule

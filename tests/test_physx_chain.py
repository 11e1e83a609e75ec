"""The reference engine for chains held to real PhysX (ovphysx, CPU) every step.

The 3-link arm of issue 21 (PGS 1/0 and TGS 4/1): the reference's joint velocities stay within
1e-5 rad/s of real PhysX's over the whole run (float32 noise: measured 4.7e-6 and 3.3e-6), the
shoulder lets go at the same step, and the drive efforts recovered from PhysX's own states agree
with the reference's. Also the one-joint ``velocity_iterations = 0`` case: PhysX reports the
velocity of one more sweep (viscous friction spin 0.00267 rad/s).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.scenario.chain import ChainScenario, load_stand
from drive_envelope._src.scenario.spec import scenario_from_mapping
from drive_envelope._src.teststand.engines import simulate

pytestmark = [pytest.mark.physx, pytest.mark.usd, pytest.mark.slow]

ARMS = Path(__file__).parent.parent / "examples" / "scenarios" / "chains"


def _release(effort: np.ndarray) -> int:
    return int(np.flatnonzero(np.abs(effort[1:]) < 0.02)[0]) + 1


@pytest.mark.parametrize("name", ["arm3_pgs_1_0", "arm3_tgs_4_1"])
def test_reference_matches_real_physx_on_the_3_link_arm(name: str) -> None:
    scenario = load_stand(ARMS / f"{name}.toml")
    assert isinstance(scenario, ChainScenario)
    reference, physx = simulate(scenario), simulate(scenario, "physx")
    assert physx.engine == "physx" and physx.metadata["precision"] == "float32"
    dv = np.abs(reference.velocity - physx.velocity)
    assert dv.max() < 1e-5, dv.max(axis=0)
    assert np.abs(reference.position - physx.position).max() < 1e-5
    assert _release(physx.effort[:, 0]) == _release(reference.effort[:, 0]) == 12
    # the effort PhysX applied, recovered from its states, is the reference's to float32 noise
    assert np.abs(reference.effort - physx.effort).max() < 2e-3
    assert physx.velocity[:, 0].max() > 2.0  # it let go and fell through the speed line


def test_pgs_without_velocity_iterations_reports_one_more_sweep() -> None:
    data = {
        "joint": {"type": "revolute", "inertia": 0.01, "initial_velocity": 0.01},
        "friction": {"viscous_friction": 0.5},
        "simulation": {"dt": 0.01, "duration": 0.5, "solver": "pgs", "position_iterations": 1,
                       "velocity_iterations": 0},
    }  # fmt: skip
    scenario = scenario_from_mapping(data, default_name="spin")
    reference, physx = simulate(scenario), simulate(scenario, "physx")
    np.testing.assert_allclose(reference.velocity, physx.velocity, rtol=1e-5, atol=1e-9)

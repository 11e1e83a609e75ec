"""The reference engine against real PhysX (ovphysx 0.7, CPU) on every bundled scenario.

``plain_drive_applied_effort`` (no envelope API) included: ovphysx 0.7 limits drive + applied joint
force together to +-maxForce, as the reference does (ovphysx 0.3.7 clamped the drive alone).

PhysX computes in float32, so agreement is to float32 precision amplified by the dynamics: the
scenarios that brake along eq. 2 amplify 1e-6 noise about a thousandfold, hence the tolerance
relative to each column's range.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drive_envelope._src.scenario.spec import load_scenario
from drive_envelope._src.scenario.trajectory import Trajectory
from drive_envelope._src.teststand.engines import engine_module
from drive_envelope._src.teststand.engines.reference import simulate

pytestmark = [pytest.mark.physx, pytest.mark.usd, pytest.mark.slow]

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
PATHS = sorted(EXAMPLES.glob("*.toml"))


@pytest.fixture(scope="module")
def physx_runs() -> dict[str, Trajectory]:
    """Every bundled scenario run once on PhysX, on one PhysX instance."""
    module: Any = engine_module("physx")
    scenarios = [load_scenario(path) for path in PATHS]
    runs = (
        module.simulate_many(scenarios)
        if hasattr(module, "simulate_many")
        else map(module.simulate, scenarios)
    )
    return {path.stem: run for path, run in zip(PATHS, runs, strict=True)}


@pytest.mark.parametrize("path", PATHS, ids=lambda p: p.stem)
def test_reference_matches_physx(path: Path, physx_runs: dict[str, Trajectory]) -> None:
    """Match the reference engine's position, velocity and effort to PhysX's at float32-level precision."""
    reference, physx = simulate(load_scenario(path)), physx_runs[path.stem]
    for column in ("position", "velocity", "effort"):
        ours, theirs = getattr(reference, column), getattr(physx, column)
        scale = max(1.0, float(np.max(np.abs(ours))))
        np.testing.assert_allclose(theirs, ours, rtol=0.0, atol=3e-3 * scale, err_msg=column)

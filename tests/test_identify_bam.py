"""identify on the real BAM bench logs: train on the sidecars' train logs, validate on the holdout.

The 16 logs of ``../shared/data/bam/logs`` (a Dynamixel XL330 swinging 0.49 kg at 0.1 m, four firmware
gains x four trajectories) with the shipped stand ``examples/bam/xl330_pendulum.toml``. BAM's own M1
model fitted on the same 12 training logs (3000 trials, ``benchmarks/bench_identify.py``) scores
48.3 mrad on the 4 held-out logs; the issue's goal is 1.5x that with the envelope model. The test
runs a short search (one restart, 40 generations); the benchmark runs the default one (3 restarts x
60 generations), whose held-out median over seeds 0, 1, 2 is 37.0 mrad (spread 0.16; BAM's M6, 35.2
mrad, is not reached, docs/identify.md). The short search lands on the same optimum (37.0 mrad held
out, 47.8 train on seed 0), so the test holds the held-out error under 40 mrad: a change to the
stand, the engine or the search that loses 3 mrad of it fails here.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.identify.canonical import binding_lines
from drive_envelope.identify import SearchOptions, identify

pytest.importorskip("scipy")

REPO = Path(__file__).resolve().parents[1]
LOGS = REPO.parent / "shared" / "data" / "bam" / "logs"
STAND = REPO / "examples" / "bam" / "xl330_pendulum.toml"
BAM_M1_HOLDOUT = (
    0.0483  # rad: bam.fit --model m1 --trials 3000 on the same training logs, bam.mae on the holdout
)
HELD_OUT_CEILING = 0.040  # rad: this search measured 36.99 mrad (seed 0), the benchmark's median 37.0
FIT = [
    "max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient",
    "damping", "static_friction", "viscous_friction", "armature", "angle_offset",
]  # fmt: skip

pytestmark = pytest.mark.skipif(
    not LOGS.is_dir(), reason="needs ../shared/data/bam (the real BAM bench logs)"
)


def _split() -> dict[str, list[Path]]:
    splits: dict[str, list[Path]] = {"train": [], "holdout": []}
    for sidecar in sorted(LOGS.glob("*.json")):
        splits[json.loads(sidecar.read_text(encoding="utf-8"))["split"]].append(sidecar.with_suffix(".csv"))
    return splits


def test_envelope_model_is_within_1_5x_of_bam_m1_on_held_out_logs() -> None:
    """Identify on the 12 training logs; the 4 held-out logs' mean error stays under 1.5x BAM's M1."""
    splits = _split()
    assert (len(splits["train"]), len(splits["holdout"])) == (12, 4)
    result = identify(
        splits["train"],
        STAND,
        validate=splits["holdout"],
        fit=FIT,
        # the reference runs PhysX's velocity sweep even with 0 velocity iterations (as the XL330
        # stand has): its likelihood surface is narrower, 15 generations of 6 landed at 96 mrad
        options=SearchOptions(generations=40, population=8, polish_evaluations=20, restarts=1),
    )
    holdout = float(np.mean([e.mae_position for e in result.validation]))
    assert holdout < 1.5 * BAM_M1_HOLDOUT, f"held-out MAE {1e3 * holdout:.1f} mrad"
    assert holdout < HELD_OUT_CEILING, f"held-out MAE {1e3 * holdout:.1f} mrad (37.0 measured)"
    values = {name: estimate.value for name, estimate in result.parameters.items()}
    # physically sensible: the effort at rest (canonical max_effort) within a factor 2 of the
    # catalog's 0.77 N*m stall at 7.4 V, rotor inertia a third of the pendulum's, friction a few
    # percent of stall
    assert 0.38 < values["max_effort"] < 1.0
    assert binding_lines(values) == {"eq1": True, "eq2": True}  # canonical: every reported line binds
    assert 5e-4 < values["armature"] < 5e-3
    assert 0.0 < values["static_friction"] < 0.1
    assert len(result.train) == 12 and all(np.isfinite(e.mae_position) for e in result.train)

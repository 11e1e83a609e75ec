"""An envelope on a drive without an effort limit: PhysX's unauthored maxForce (FLT_MAX).

PhysX keeps the envelope's speed line (eq. 2) when maxForce is FLT_MAX; the scenario files read
FLT_MAX as ``inf`` (the one "no limit" rule) and every engine runs it (the mujoco and newton
stands hold it step by step in ``_edge_scenarios.py``). Golden values by hand: a damping-only drive
(D = 20 N*m*s/rad toward 10 rad/s) on 0.05 kg*m^2, dt = 0.01 s, under eq. 2 alone (v_max = 3 rad/s,
G = 0.1 (rad/s)/(N*m)): the implicit request from rest ends the step at
dt*D*10/(I + dt*D) = 8 rad/s, beyond the line, so the clamp gives the effort F = I*v1/dt that ends
the step on eq. 2, v1 = v_max - G*F.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drive_envelope.errors import InputError
from drive_envelope.teststand import load_scenario, scenario_from_mapping, simulate

SCENARIO = """
name = "speed line only"
[joint]
inertia = 0.05
[drive]
damping = 20.0
target_velocity = 10.0
{max_effort}
[envelope]
max_actuator_velocity = 3.0
speed_effort_gradient = 0.1
[simulation]
dt = 0.01
duration = 0.5
solver = "pgs"
position_iterations = 1
velocity_iterations = 1
"""


def _write(tmp_path: Path, max_effort_line: str) -> Path:
    path = tmp_path / "scenario.toml"
    path.write_text(SCENARIO.format(max_effort=max_effort_line))
    return path


@pytest.mark.parametrize("line", ["", "max_effort = 3.4028234663852886e38"], ids=["omitted", "flt_max"])
def test_unlimited_max_effort_under_an_envelope_is_inf(tmp_path: Path, line: str) -> None:
    """Omitted and FLT_MAX both read as no effort limit, the envelope keeping its speed line."""
    scenario = load_scenario(_write(tmp_path, line))
    assert scenario.drive.max_effort == math.inf
    envelope = scenario.effective_envelope()
    assert envelope is not None and envelope.max_effort == math.inf
    assert envelope.max_actuator_velocity == 3.0


def test_reference_meets_the_speed_line_by_hand(tmp_path: Path) -> None:
    """Step 1 ends on eq. 2: v1 = 3 - G*F with F = I*v1/dt, so v1 = 3/(1 + G*I/dt) = 2 rad/s."""
    run = simulate(load_scenario(_write(tmp_path, "")))
    inertia, gradient, dt = 0.05, 0.1, 0.01
    v1 = 3.0 / (1.0 + gradient * inertia / dt)
    assert v1 == pytest.approx(2.0, abs=1e-15)
    np.testing.assert_allclose(run.velocity[1], v1, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(run.effort[1], inertia * v1 / dt, rtol=0.0, atol=1e-9)
    # every later step stays on or under the speed line and tends to it
    assert np.all(run.velocity <= 3.0 + 1e-12)
    assert run.velocity[-1] == pytest.approx(3.0, abs=1e-3)


def test_a_negative_max_effort_is_still_refused() -> None:
    """Negative or NaN max_effort stays an error naming the key."""
    with pytest.raises(InputError, match="max_effort"):
        scenario_from_mapping({"joint": {"inertia": 0.05}, "drive": {"max_effort": -1.0}})


@pytest.mark.physx
@pytest.mark.usd
def test_real_physx_keeps_the_speed_line_without_max_force(tmp_path: Path) -> None:
    """Real PhysX (ovphysx, CPU) with maxForce unauthored-as-FLT_MAX runs the same steps as the reference."""
    from drive_envelope._src.teststand.engines import engine_module

    scenario = load_scenario(_write(tmp_path, ""))
    physx = engine_module("physx").simulate(scenario)
    reference = simulate(scenario)
    np.testing.assert_allclose(physx.velocity, reference.velocity, rtol=0.0, atol=1e-5)
    assert physx.velocity[1] == pytest.approx(2.0, abs=1e-5)

"""One "no limit" rule (issue 23 item 15, issue 29): ``inf`` in Python, -1 only inside the plugin's dynprm.

By hand: with no effort cap (max_effort = inf) and R = 0.5 N*m*s/rad, G = 0.1 (rad/s)/(N*m),
v_max = 30 rad/s, eq. 1 never binds, so the limit at |v| = 10 rad/s is eq. 2's (30 - 10) / 0.1 = 200 N*m;
at an infinite speed nothing is feasible (0), and a NaN speed lets go (0).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from drive_envelope import PerformanceEnvelope


def test_an_envelope_without_an_effort_limit_is_inf() -> None:
    env = PerformanceEnvelope(
        max_effort=math.inf,
        velocity_dependent_resistance=0.5,
        speed_effort_gradient=0.1,
        max_actuator_velocity=30,
    )
    with np.errstate(all="raise"):  # no RuntimeWarning from inf - inf
        np.testing.assert_array_equal(
            env.effort_limit([0.0, 10.0, 31.0, math.inf, math.nan]), [300, 200, 0, 0, 0]
        )
        np.testing.assert_array_equal(env.velocity_at_effort([0.0, 1.0, math.inf]), [30.0, 29.9, 0.0])
    assert PerformanceEnvelope.from_dict({"max_effort": "inf"}).max_effort == math.inf
    free = PerformanceEnvelope(max_effort=math.inf)
    np.testing.assert_array_equal(free.effort_limit([0.0, 1e300]), [math.inf, math.inf])


@pytest.mark.mujoco
def test_mujoco_writes_minus_one_and_reads_back_inf() -> None:
    """add_drive's "or inf" holds for max_effort, and get_envelope of a -1 drive is no limit."""
    from _mujoco_plugin import mujoco_with_plugin

    mujoco: Any = mujoco_with_plugin()
    from drive_envelope.mujoco import add_drive, get_envelope

    spec = mujoco.MjSpec.from_string(
        '<mujoco><worldbody><body><joint name="j" type="hinge"/><geom size="0.1" mass="1"/></body>'
        "</worldbody></mujoco>"
    )
    add_drive(spec, "j", envelope=PerformanceEnvelope(max_effort=math.inf, max_actuator_velocity=5.0),
              stiffness=10, damping=1)  # fmt: skip
    model = spec.compile()
    assert model.actuator_dynprm[0, 0] == -1.0
    env = get_envelope(model, "j")
    assert env.max_effort == math.inf and env.max_actuator_velocity == 5.0

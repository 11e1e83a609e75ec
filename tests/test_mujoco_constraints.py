"""``set_solver(spec, "exact", constraints=True)``: the drives solved with MuJoCo's constraint solve.

The hand case: one hinge (inertia 0.1 kg*m^2, no gravity, Euler) resting 0.2 rad inside its upper
limit, its drive pulling away from it with a request far above max_effort. The limit's soft row
(MuJoCo's efc_J, efc_D, efc_aref at that state, which the drive does not change) pushes the joint out
too, so the end-of-step velocity is, while the row stays active (a quadratic row of MuJoCo's
Newton solve: force = D*(aref - J*qacc) > 0),

    v1(tau) = qvel + h*(tau + J*D*aref)/(I + D*J^2).

The default solve predicts v1 without the row and gives max_effort, which the row then carries past
the speed line. With constraints the effort must end exactly on the speed line
``|v1| = vmax - k*|tau|``, solved by hand for tau from the line above.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _mujoco_plugin import mujoco_with_plugin
from drive_envelope import InputError, PerformanceEnvelope

pytestmark = pytest.mark.mujoco

ROOT = Path(__file__).resolve().parents[1]
ANYMAL = ROOT.parent / "shared" / "data" / "menagerie" / "anybotics_anymal_c" / "scene.xml"

HINGE = """<mujoco><compiler angle="radian"/><option timestep="0.002" integrator="Euler" gravity="0 0 0"/>
<worldbody><body><joint name="j" type="hinge" axis="0 0 1" limited="true" range="-1 1"
solreflimit="0.02 1"/><inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/></body></worldbody>
</mujoco>"""
ENVELOPE = PerformanceEnvelope(max_effort=20.0, max_actuator_velocity=1.5, speed_effort_gradient=0.05)
INERTIA, DT = 0.1, 0.002


@pytest.fixture(scope="module")
def mujoco() -> Any:
    return mujoco_with_plugin()


def _hinge(mujoco: Any, constraints: bool) -> Any:
    from drive_envelope.mujoco import add_drive, set_solver

    spec = mujoco.MjSpec.from_string(HINGE)
    add_drive(spec, "j", envelope=ENVELOPE, stiffness=200.0, damping=0.0, effort_sensor=False)
    set_solver(spec, "exact", constraints=constraints)
    return spec.compile()


def _at_the_limit(mujoco: Any, model: Any) -> Any:
    data = mujoco.MjData(model)
    data.qpos[0] = 1.2  # 0.2 rad into the upper limit
    data.ctrl[0] = -1.0  # the drive asks for 200 * -2.2 N*m, 22 times max_effort
    return data


def test_a_drive_pulled_past_its_speed_line_by_a_joint_limit_ends_on_it(mujoco: Any) -> None:
    default = _hinge(mujoco, False)
    data = _at_the_limit(mujoco, default)
    mujoco.mj_forward(default, data)
    j, weight, aref = float(data.efc_J[0]), float(data.efc_D[0]), float(data.efc_aref[0])
    assert data.nefc == 1 and j == -1.0
    mujoco.mj_step(default, data)
    # the contact-free prediction: -20 N*m ends at -0.4 rad/s, inside; the limit's row adds -0.62
    assert data.actuator_force[0] == -20.0
    assert data.qvel[0] == pytest.approx(-1.02, rel=1e-12)
    assert ENVELOPE.margins(data.qvel[0], data.actuator_force[0])[1] == pytest.approx(-0.52, rel=1e-12)

    model = _hinge(mujoco, True)
    data = _at_the_limit(mujoco, model)
    mujoco.mj_step(model, data)
    share = DT / (INERTIA + weight * j * j)
    vmax, k = ENVELOPE.max_actuator_velocity, ENVELOPE.speed_effort_gradient
    tau = (-vmax - DT * j * weight * aref / (INERTIA + weight * j * j)) / (share + k)
    assert weight == pytest.approx(1.9) and tau == pytest.approx(-500 / 51, rel=1e-9)  # -9.804 N*m
    assert data.actuator_force[0] == pytest.approx(tau, rel=1e-12)
    assert data.qvel[0] == pytest.approx(-(vmax - k * abs(tau)), rel=1e-12)  # on the speed line
    assert data.efc_force[0] > 0  # the row stayed active, as the hand formula assumes


def test_without_constraint_rows_it_is_the_default_bit_for_bit(mujoco: Any) -> None:
    runs = []
    for constraints in (False, True):
        model = _hinge(mujoco, constraints)
        data = mujoco.MjData(model)
        data.ctrl[0] = 0.3  # well inside the range: no limit row while it moves
        rows = []
        for _ in range(200):
            mujoco.mj_step(model, data)
            rows.append([data.qpos[0], data.qvel[0], data.actuator_force[0], data.nefc])
        runs.append(np.array(rows))
    assert runs[0][:, 3].max() == 0
    np.testing.assert_array_equal(runs[0], runs[1])


def test_forward_is_repeatable_and_keeps_mujocos_warmstart(mujoco: Any) -> None:
    model = _hinge(mujoco, True)
    data = _at_the_limit(mujoco, model)
    data.qacc_warmstart[0] = 3.0
    mujoco.mj_forward(model, data)
    first = (data.qacc.copy(), data.actuator_force.copy(), data.efc_force.copy())
    assert data.qacc_warmstart[0] == 3.0  # the loop's own warm starts are undone
    mujoco.mj_forward(model, data)
    for before, after in zip(first, (data.qacc, data.actuator_force, data.efc_force), strict=True):
        np.testing.assert_array_equal(before, after)


def test_the_setting_is_reported_and_checked(mujoco: Any) -> None:
    from drive_envelope.mujoco import SOLVER_NUMERIC, get_solver, set_solver

    model = _hinge(mujoco, True)
    assert get_solver(model).constraints is True
    set_solver(model, "exact")  # back to the default between steps, as every slot
    assert get_solver(model).constraints is False
    spec = mujoco.MjSpec.from_string(HINGE)
    with pytest.raises(InputError, match=r"^set_solver: argument 'constraints' = True with solver 'tgs'"):
        set_solver(spec, "tgs", constraints=True)
    with pytest.raises(InputError, match=r"^set_solver: argument 'constraints' = 1: expected True or False"):
        set_solver(spec, "exact", constraints=1)  # type: ignore[arg-type]

    # the plugin refuses the same in the MJCF (the compiler makes an MjData)
    spec = mujoco.MjSpec.from_string(HINGE)
    from drive_envelope.mujoco import add_drive

    add_drive(spec, "j", envelope=ENVELOPE, stiffness=200.0, damping=0.0, effort_sensor=False)
    spec.add_numeric(name=SOLVER_NUMERIC, data=[1, 4, 1, 1], size=4)
    with pytest.raises(ValueError, match=r"\[3\] \(constraints\) = 1 with solver 1: expected solver 0"):
        spec.compile()


@pytest.mark.skipif(not ANYMAL.is_file(), reason="needs ../shared/data/menagerie/anybotics_anymal_c")
def test_menagerie_anymal_on_the_floor_stays_inside(mujoco: Any) -> None:
    """The benchmark's ANYmal C stand (benchmarks/bench_mujoco_constraints.py), its 3000 steps."""
    import sys
    import warnings

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import bench_mujoco_constraints as bench
    finally:
        sys.path.pop(0)
    stand = bench.STANDS["anymal"]
    results = {}
    for constraints in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the map's caps above the model's forcerange, said by apply
            model, envelopes, actuators = bench.build(stand, constraints)
        control = bench.controls(model, stand, envelopes, actuators, 3000)
        results[constraints] = bench.check(model, stand, envelopes, actuators, control)
    assert results[False]["outside"] > 0.001 and results[False]["worst"] > 0.01
    assert results[True]["outside"] <= 0.001 and results[True]["worst"] < 1e-3
    assert 1.0 <= results[True]["solves"] < 1.5  # one check per step, a re-solve where it is needed


@pytest.mark.warp
def test_mjwarp_refuses_the_setting_in_one_line(mujoco: Any) -> None:
    pytest.importorskip("mujoco_warp")
    import warp as wp

    from drive_envelope.mjwarp import put_model
    from drive_envelope.mujoco import add_drive, set_solver

    wp.config.quiet = True  # type: ignore[attr-defined]
    spec = mujoco.MjSpec.from_string(HINGE)
    add_drive(spec, "j", envelope=ENVELOPE, stiffness=200.0, damping=0.0, effort_sensor=False)
    set_solver(spec, "exact", constraints=True)
    with pytest.raises(InputError, match=r"\(constraints\) = 1: not available in MJWarp") as caught:
        put_model(spec)
    assert "\n" not in str(caught.value)

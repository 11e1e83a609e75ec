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

import argparse
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


# a new user's findings on the MuJoCo adapter: constraint forces act after the drives

MENAGERIE = ROOT.parent / "shared" / "data" / "menagerie"
WHIP = """<mujoco><compiler angle="radian"/><option timestep="0.002" gravity="0 0 0" integrator="Euler"/>
<extension><plugin plugin="drive_envelope.envelope"><instance name="v"><config key="input" value="vel"/>
</instance></plugin></extension>
<worldbody><body><joint name="a" axis="0 0 1" range="-0.2 0.2"/>
<geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.03" mass="1"/>
<body pos="0.5 0 0"><joint name="b" axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.03"
mass="1"/></body></body></worldbody>
<actuator><plugin name="drive" joint="b" instance="v" dynprm="20 1 0 0 0 50"/></actuator></mujoco>"""


def _cli(*argv: str) -> int:
    from drive_envelope._src.cli.commands import mujoco as command

    parser = argparse.ArgumentParser(prog="drive-envelope")
    command.register(parser.add_subparsers())
    args = parser.parse_args(argv)
    return int(args.func(args))


def _menagerie(name: str) -> Path:
    path = MENAGERIE / name
    if not path.is_file():
        pytest.skip(f"needs {path} (../shared/data/menagerie, not part of a user's clone)")
    return path


def _free_step(mujoco: Any, free: Any, free_data: Any, data: Any) -> None:
    """Step ``free`` (constraints disabled) from the state of ``data``."""
    free_data.qpos[:], free_data.qvel[:], free_data.ctrl[:] = data.qpos, data.qvel, data.ctrl
    free_data.time = data.time
    mujoco.mj_step(free, free_data)


def test_a_joint_limit_moves_a_coupled_drive_past_its_envelope(mujoco: Any) -> None:
    """The drive is inside at the velocity it predicts; the limit's impulse, solved after it, is not."""
    model = mujoco.MjModel.from_xml_string(WHIP)
    free = mujoco.MjModel.from_xml_string(WHIP)
    free.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    data, free_data = mujoco.MjData(model), mujoco.MjData(free)
    data.qvel[0], data.ctrl[0] = 4.0, 0.9  # joint a swings into its limit; b's drive holds 0.9 < 1 rad/s
    env = PerformanceEnvelope(max_effort=20.0, max_actuator_velocity=1.0)
    while data.nefc == 0:
        _free_step(mujoco, free, free_data, data)
        mujoco.mj_step(model, data)
        assert data.time < 0.2
    # the step the limit acts: same effort, inside at the predicted velocity, outside after the limit
    assert data.actuator_force[0] == free_data.actuator_force[0] > 0.0
    assert env.contains(free_data.qvel[1], free_data.actuator_force[0]).item()
    assert data.qvel[1] > 2.5 and not env.contains(data.qvel[1], data.actuator_force[0]).item()


def test_panda_leaves_its_envelope_only_through_constraint_forces(mujoco: Any, tmp_path: Path) -> None:
    """The user's Panda run (Euler): outside samples only with constraint rows; 0 replayed without them."""
    from drive_envelope.mujoco import model_drives

    out = tmp_path / "panda_env.xml"
    assert _cli("mujoco", "apply", str(_menagerie("panda.xml")), "--map", "franka-panda", "-o", str(out)) == 0
    model, free = mujoco.MjModel.from_xml_path(str(out)), mujoco.MjModel.from_xml_path(str(out))
    for m in (model, free):
        m.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    free.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    data, free_data = mujoco.MjData(model), mujoco.MjData(free)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    drives = model_drives(model)
    acts = [d.actuator for d in drives]
    dofs = [int(model.jnt_dofadr[model.actuator_trnid[a, 0]]) for a in acts]
    home = data.ctrl[acts].copy()

    def outside(velocity: float, effort: float, env: PerformanceEnvelope) -> float:
        if abs(effort) <= 1e-6 * env.max_effort and abs(velocity) > env.max_actuator_velocity:
            return 0.0  # released
        effort_margin, velocity_margin = env.margins(velocity, effort)
        return float(max(-effort_margin / env.max_effort, -velocity_margin / env.max_actuator_velocity))

    count, worst, free_worst = 0, 0.0, 0.0
    for _ in range(1500):
        data.ctrl[acts] = home + 0.6 * np.sin(2 * np.pi * 3 * data.time)
        _free_step(mujoco, free, free_data, data)
        mujoco.mj_step(model, data)
        np.testing.assert_array_equal(free_data.actuator_force[acts], data.actuator_force[acts])
        for dof, a, drive in zip(dofs, acts, drives, strict=True):
            assert drive.envelope is not None
            free_worst = max(
                free_worst, outside(free_data.qvel[dof], free_data.actuator_force[a], drive.envelope)
            )
            miss = outside(data.qvel[dof], data.actuator_force[a], drive.envelope)
            if miss > 1e-6:
                assert data.nefc > 0
                count, worst = count + 1, max(worst, miss)
    assert free_worst <= 1e-6  # the coupled solve is exact at the velocity it predicts
    assert count > 100 and worst > 0.15  # docs/mujoco.md: 869 of 14000 in 2000 steps, worst 18.8 %


def test_the_docs_give_the_panda_numbers_and_the_cause() -> None:
    """docs/mujoco.md names the constraint rows behind the Panda's samples outside."""
    docs = (ROOT / "docs" / "mujoco.md").read_text()
    section = docs.split("### Constraints act after the drives", 1)[1].split("###", 1)[0]
    for fact in ("869", "18.8 %", "1803", "727", "joint limits", "equality", "0 samples outside"):
        assert fact in section, fact
    assert section.count("|") > 10  # the table

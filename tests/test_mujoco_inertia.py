"""drive_envelope.mujoco.effective_inertia: 1/(M^-1)_ii against an independent computation.

The independent side is MuJoCo's dense mass matrix (``mj_fullM`` after ``mj_forward``) inverted by
NumPy, on the Menagerie Panda and Go2 from ../shared/data (skipped without it), and a two-body
chain whose inverse diagonal is worked out by hand.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drive_envelope import InputError

mujoco = pytest.importorskip("mujoco")

from drive_envelope.mujoco import effective_inertia  # noqa: E402

MENAGERIE = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "menagerie"


def _model(name: str) -> Any:
    path = MENAGERIE / name
    if not path.is_file():
        pytest.skip(f"needs the Menagerie model {path} (../shared/data, not part of a user's clone)")
    return mujoco.MjModel.from_xml_path(str(path))


def _numpy_inverse_diagonal(model: Any, qpos: Any) -> Any:
    """diag(inv(M)) from mj_forward's dense mass matrix, inverted by NumPy."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    return np.diag(np.linalg.inv(full))


def _one_dof(model: Any) -> list[int]:
    kinds = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    return [j for j in range(model.njnt) if int(model.jnt_type[j]) in kinds]


@pytest.mark.parametrize("name", ["panda.xml", "go2.xml"])
def test_menagerie_keyframe_matches_numpy_inverse_of_full_mass_matrix(name: str) -> None:
    """At the first keyframe (home), each hinge and slide's 1/(M^-1)_ii equals NumPy's to 1e-12."""
    model = _model(name)
    inertia = effective_inertia(model)
    joints = _one_dof(model)
    assert list(inertia) == [model.joint(j).name for j in joints]
    diagonal = _numpy_inverse_diagonal(model, model.key_qpos[0])
    expected = [1.0 / diagonal[model.jnt_dofadr[j]] for j in joints]
    assert list(inertia.values()) == pytest.approx(expected, rel=1e-12)


def test_go2_floating_base_couples_the_legs_below_their_own_mass_matrix_entry() -> None:
    """On the free-floating Go2, 1/(M^-1)_ii is below M_ii (the base moves too) and above the armature."""
    model = _model("go2.xml")
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    inertia = effective_inertia(model, data)
    for name, value in inertia.items():
        dof = model.jnt_dofadr[model.joint(name).id]
        assert model.dof_armature[dof] < value < full[dof, dof]


def test_given_data_pose_and_joint_subset_in_the_order_asked() -> None:
    """A bent Panda pose from data, two joints by name and id, in that order; the data is left alone."""
    model = _model("panda.xml")
    data = mujoco.MjData(model)
    data.qpos[:7] = [0.3, -0.5, 0.2, -2.0, 0.1, 1.2, 0.4]
    before = data.qpos.copy()
    inertia = effective_inertia(model, data, ["joint4", 1])
    assert list(inertia) == ["joint4", "joint2"]
    diagonal = _numpy_inverse_diagonal(model, data.qpos)
    expected = [1.0 / diagonal[model.jnt_dofadr[j]] for j in (3, 1)]
    assert list(inertia.values()) == pytest.approx(expected, rel=1e-12)
    assert np.array_equal(data.qpos, before)
    assert not data.M.any()  # the caller's data got no mass matrix: a scratch MjData was used


def _chain() -> Any:
    """Two point-like bodies on parallel hinges: M = [[a, b], [b, c]] with known entries."""
    xml = """
    <mujoco>
      <option gravity="0 0 0"/>
      <worldbody>
        <body name="a">
          <joint name="shoulder" type="hinge" axis="0 0 1" armature="0.01"/>
          <inertial pos="1 0 0" mass="1" diaginertia="1e-6 1e-6 1e-6"/>
          <body name="b" pos="1 0 0">
            <joint name="elbow" type="hinge" axis="0 0 1" armature="0.02"/>
            <inertial pos="1 0 0" mass="1" diaginertia="1e-6 1e-6 1e-6"/>
          </body>
        </body>
        <body name="slider">
          <joint name="rail" type="slide" axis="1 0 0"/>
          <inertial pos="0 0 0" mass="3" diaginertia="1 1 1"/>
        </body>
      </worldbody>
    </mujoco>
    """
    return mujoco.MjModel.from_xml_string(xml)


def test_two_link_chain_by_hand_with_armature() -> None:
    """Stretched 2-link arm of unit masses at 1 m: M = [[5, 2], [2, 1]] + armature (I_zz 1e-6 each).

    M_11 = 1 (first mass at 1 m) + 4 (second at 2 m) + 2e-6 + 0.01, M_12 = 2 + 1e-6, M_22 = 1 + 1e-6
    + 0.02; (M^-1)_11 = M_22/det, (M^-1)_22 = M_11/det. The slide joint alone: 3 kg.
    """
    model = _chain()
    m11, m12, m22 = 5.0 + 2e-6 + 0.01, 2.0 + 1e-6, 1.0 + 1e-6 + 0.02
    det = m11 * m22 - m12 * m12
    inertia = effective_inertia(model)
    assert inertia == pytest.approx({"shoulder": det / m22, "elbow": det / m11, "rail": 3.0}, rel=1e-9)
    folded = effective_inertia(model, joints="elbow", keyframe=None)  # qpos0: no keyframe in the model
    assert folded == pytest.approx({"elbow": det / m11}, rel=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"joints": ["wrist"]}, r"effective_inertia: joint 'wrist' is not in the model"),
        ({"joints": [7]}, r"effective_inertia: joint 7; expected a joint name or an index below 3"),
        ({"keyframe": "home"}, r"effective_inertia: keyframe 'home' is not in the model"),
        ({"keyframe": 2}, r"effective_inertia: keyframe 2 out of range; the model has 0 keyframes"),
        ({"data": "qpos"}, r"argument 'data' is a str; expected a mujoco\.MjData"),
    ],
)
def test_bad_arguments_are_one_line_errors(kwargs: dict[str, Any], message: str) -> None:
    """Name the argument, the value and what was expected."""
    with pytest.raises(InputError, match=message):
        effective_inertia(_chain(), **kwargs)


def test_free_joint_is_refused_by_name() -> None:
    """A free joint has no single effective inertia: refused, naming it."""
    model = _model("go2.xml")
    with pytest.raises(InputError, match=r"is a free or ball joint; expected a hinge or slide joint"):
        effective_inertia(model, joints=[0])

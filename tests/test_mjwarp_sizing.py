"""constraint_sizes: the nconmax / njmax MJWarp needs, measured in C MuJoCo (issue 28)."""

from __future__ import annotations

from pathlib import Path

import pytest

from drive_envelope.errors import InputError

mujoco = pytest.importorskip("mujoco")

G1 = Path(__file__).resolve().parents[2] / "shared" / "data" / "menagerie" / "unitree_g1" / "scene.xml"

BOX_ON_PLANE = """<mujoco><option timestep="0.002"/>
<worldbody><geom type="plane" size="1 1 0.1"/>
<body pos="0 0 0.05"><freejoint/><geom type="box" size="0.1 0.1 0.05" mass="1"/></body></worldbody>
</mujoco>"""


def test_a_resting_box_needs_four_contacts_of_four_rows() -> None:
    """By hand: a box on a plane touches at its 4 corners; condim 3, pyramidal cone: 2*(3-1) rows each."""
    from drive_envelope.mjwarp import constraint_sizes

    model = mujoco.MjModel.from_xml_string(BOX_ON_PLANE)
    sizes = constraint_sizes(model, steps=200, margin=1.5)
    assert (sizes.peak_contacts, sizes.peak_rows) == (4, 16)
    assert (sizes.nconmax, sizes.njmax) == (6, 24)


def test_bad_arguments_are_one_line() -> None:
    from drive_envelope.mjwarp import constraint_sizes

    model = mujoco.MjModel.from_xml_string(BOX_ON_PLANE)
    with pytest.raises(InputError, match="steps: expected an integer >= 1, got 0"):
        constraint_sizes(model, steps=0)
    with pytest.raises(InputError, match=r"margin: expected a finite number >= 1, got 0\.5"):
        constraint_sizes(model, margin=0.5)
    keyed = BOX_ON_PLANE.replace("</mujoco>", '<keyframe><key qpos="0 0 0.05 1 0 0 0"/></keyframe></mujoco>')
    with pytest.raises(InputError, match=r"keyframe: expected an index in \[0, 1\), got 3"):
        constraint_sizes(mujoco.MjModel.from_xml_string(keyed), keyframe=3)


def test_the_menagerie_g1_in_motion_needs_more_rows_than_mjwarp_allocates_by_default() -> None:
    """Standing, the G1 fits MJWarp's default njmax; swinging its joints (sinusoids about the
    keyframe, as a policy would) it needs more than twice as many rows (the drift of issue 28)."""
    if not G1.is_file():
        pytest.skip(f"needs the Menagerie G1 at {G1} (../shared/data)")
    io = pytest.importorskip("mujoco_warp._src.io")
    import numpy as np

    from drive_envelope.mjwarp import constraint_sizes

    model = mujoco.MjModel.from_xml_path(str(G1))
    home = model.key_qpos[0][7 : 7 + model.nu].copy()

    def swing(m: object, d: object) -> None:
        d.ctrl[:] = home + 0.8 * np.sin(6.0 * d.time + np.arange(model.nu))  # type: ignore[attr-defined]

    standing = constraint_sizes(model, steps=300)
    moving = constraint_sizes(model, steps=1500, control=swing)
    default = io._default_njmax(model)
    assert standing.peak_rows <= default < moving.peak_rows
    assert moving.peak_rows > 2 * default
    assert moving.njmax >= moving.peak_rows and moving.nconmax >= moving.peak_contacts

"""``usd apply`` with a map says where the asset's own ratings and the envelope disagree (issue 23, item 3).

The ANYmal C asset (Isaac Sim's URDF import, in ../shared/data/newton-assets) authors maxForce 80 N*m
and physxJoint:maxJointVelocity 20 rad/s (1145.9 deg/s) on every joint. The AK80-6 caps at 12 N*m:
(80 - 12) / 80 = 85 % below; its 37.6991 rad/s is above the joint's 20 rad/s. The RMD-X8's 120 N*m is
above 80 and its 16.5457 rad/s below 20: nothing to say for it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main

pytestmark = pytest.mark.usd

ANYMAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "newton-assets" / "anymal_c.usd"


def test_caps_below_the_asset_maxforce_and_speeds_above_its_joint_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if not ANYMAL.is_file():
        pytest.skip(f"needs {ANYMAL} (../shared/data, not part of a user's clone)")
    joint_map = tmp_path / "map.toml"
    joint_map.write_text(
        '[joints]\n"*_HAA" = "tmotor-ak80-6"\n"*_KFE" = "myactuator-rmd-x8-120"\n', encoding="utf-8"
    )
    assert main(["usd", "apply", str(ANYMAL), "--map", str(joint_map), "-o", str(tmp_path / "out.usda")]) == 0
    err = capsys.readouterr().err
    below = [line for line in err.splitlines() if "below the asset's maxForce" in line]
    assert (
        len(below) == 1
        and "key 'joints.*_HAA': max_effort 12 N*m is 85 % below the asset's maxForce 80 N*m" in below[0]
    )
    fast = [line for line in err.splitlines() if "above the joint's maxJointVelocity" in line]
    # the AK80-6's 37.6991 rad/s is above 20 rad/s; the RMD-X8-120's 16.5457 rad/s is not
    assert len(fast) == 1 and "key 'joints.*_HAA': max_actuator_velocity 37.6991 rad/s is above" in fast[0]

"""The MuJoCo plugin for tests: skip without MuJoCo, build the plugin once if `make setup` did not."""

from __future__ import annotations

from typing import Any

import pytest


def mujoco_with_plugin() -> Any:
    """Return the ``mujoco`` module with drive-envelope's plugin loaded (skips the test without MuJoCo)."""
    module = pytest.importorskip("mujoco")
    from drive_envelope._src.adapters.mujoco import build, loader

    try:
        loader.load_plugin()
    except build.PluginError:
        build.build_plugin(quiet=True)  # `make setup` normally built it
        loader.load_plugin()
    return module


# A three-joint arm with a fixed tendon and a tip site; {extra} adds actuators (tendon, site ones).
TENDON_ARM = """<mujoco model="arm"><compiler angle="radian"/><option timestep="0.002"/>
<worldbody><body name="l1" pos="0 0 1"><joint name="shoulder" axis="0 1 0" range="-1.5 1.5"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="elbow" axis="0 1 0" range="-2 0"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
<body pos="0.3 0 0"><joint name="slider" type="slide" axis="1 0 0" range="-0.1 0.1"/>
<geom type="sphere" size="0.03"/><site name="tip"/></body></body></body></worldbody>
<tendon><fixed name="t"><joint joint="shoulder" coef="1"/><joint joint="elbow" coef="-1"/></fixed></tendon>
<actuator><position name="ps" joint="shoulder" kp="100" kv="5"/><motor name="el" joint="elbow"/>
<motor name="sm" joint="slider"/>{extra}</actuator></mujoco>"""

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

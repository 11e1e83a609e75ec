"""Shared fixtures; engine markers skip cleanly when their optional extra is absent."""

from __future__ import annotations

import importlib.util

import pytest

_MARKER_MODULES = {
    "mujoco": "mujoco",
    "warp": "warp",
    "newton": "newton",
    "torch": "torch",
    "usd": "physx_usd_schemas",
    "physx": "ovphysx",
    "plot": "matplotlib",
}


def _has(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip tests whose engine marker names a package that is not installed."""
    for item in items:
        for marker, module in _MARKER_MODULES.items():
            if item.get_closest_marker(marker) is not None and not _has(module):
                item.add_marker(pytest.mark.skip(reason=f"needs {module} (extra '{marker}')"))
        if item.get_closest_marker("gpu") is not None and not _cuda_available():
            item.add_marker(pytest.mark.skip(reason="needs a CUDA device"))


def _cuda_available() -> bool:
    if _has("torch"):
        import torch

        if torch.cuda.is_available():
            return True
    if _has("warp"):
        import warp as wp

        return bool(wp.is_cuda_available())
    return False

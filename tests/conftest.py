"""Shared fixtures; engine markers skip cleanly when their optional extra is absent.

Isaac Lab (marker ``isaaclab``): Isaac Lab ships inside Isaac Sim; from PyPI, ``pip install --no-deps
isaaclab==2.3.2.post1`` (plus ``toml`` and ``trimesh``, which ``isaaclab.actuators`` imports) gives a
bootstrapper whose top-level ``isaaclab/__init__.py`` imports ``isaacsim``, with the real package
at ``<site-packages>/isaaclab/source/isaaclab/isaaclab``. For the tests marked ``isaaclab`` only,
and only in that layout, :func:`_isaaclab_setup` puts ``<site-packages>/isaaclab/source/isaaclab``
first on ``sys.path`` and stands in for the two Isaac Sim modules ``isaaclab.utils.assets`` imports
when it loads: ``carb`` (its ``carb.settings.get_settings().get(key)`` answers None) and
``omni.client`` (an empty module; only asset downloads use it). Nothing else of Isaac Sim is
imitated: the actuators, ``configclass`` and ``ArticulationActions`` are Isaac Lab's own code.
Where Isaac Lab is really installed (``isaaclab.actuators`` importable), no shim is used.
"""

from __future__ import annotations

import importlib.util
import sys
import types
from pathlib import Path
from typing import Any

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


def _isaaclab_layout() -> tuple[str, Path | None]:
    """``("installed", None)``, ``("wheel", source folder)`` or ``("absent", None)``, without importing it."""
    spec = importlib.util.find_spec("isaaclab")  # finds the package; does not run its __init__
    if spec is None or not spec.submodule_search_locations:
        return "absent", None
    folder = Path(next(iter(spec.submodule_search_locations)))
    if (folder / "actuators" / "__init__.py").is_file():
        return "installed", None
    source = folder / "source" / "isaaclab"
    if (source / "isaaclab" / "actuators" / "__init__.py").is_file():
        return "wheel", source
    return "absent", None


def _isaaclab_setup() -> None:
    """Make ``isaaclab.actuators`` importable from the PyPI wheel's source tree (see the module docstring)."""
    layout, source = _isaaclab_layout()
    if layout != "wheel" or source is None:
        return
    if str(source) not in sys.path:
        sys.path.insert(0, str(source))
    bootstrap = sys.modules.get("isaaclab")
    if bootstrap is not None and not hasattr(bootstrap, "__path__"):
        del sys.modules["isaaclab"]
    if not _has("carb"):
        carb = types.ModuleType("carb")
        carb.settings = types.SimpleNamespace(  # type: ignore[attr-defined]
            get_settings=lambda: types.SimpleNamespace(get=lambda key: None)
        )
        sys.modules["carb"] = carb
    if not _has("omni"):
        omni = types.ModuleType("omni")
        omni.client = types.ModuleType("omni.client")  # type: ignore[attr-defined]
        sys.modules["omni"] = omni
        sys.modules["omni.client"] = omni.client  # type: ignore[attr-defined]


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip tests whose engine marker names a package that is not installed."""
    isaaclab_absent = _isaaclab_layout()[0] == "absent"
    for item in items:
        for marker, module in _MARKER_MODULES.items():
            if item.get_closest_marker(marker) is not None and not _has(module):
                item.add_marker(pytest.mark.skip(reason=f"needs {module} (extra '{marker}')"))
        if item.get_closest_marker("isaaclab") is not None and isaaclab_absent:
            reason = "needs Isaac Lab (isaaclab.actuators): Isaac Sim, or pip install --no-deps isaaclab"
            item.add_marker(pytest.mark.skip(reason=reason))
        if item.get_closest_marker("gpu") is not None and not _cuda_available():
            item.add_marker(pytest.mark.skip(reason="needs a CUDA device"))


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Before a test marked ``isaaclab``, make Isaac Lab's source tree importable (PyPI wheel layout)."""
    if item.get_closest_marker("isaaclab") is not None:
        _isaaclab_setup()


def _cuda_available() -> bool:
    if _has("torch"):
        import torch

        if torch.cuda.is_available():
            return True
    if _has("warp"):
        import warp as wp

        return bool(wp.is_cuda_available())
    return False


# property tests draw the same examples on every run (a CI failure is reproducible, never a coin
# toss); a local hunt for new counterexamples: pytest --hypothesis-profile=explore. The mjlab
# environment (scripts/test_mjlab.sh) has no hypothesis and no property tests, so none is registered there.
if _has("hypothesis"):
    from hypothesis import settings

    settings.register_profile("default", derandomize=True)
    settings.register_profile("explore", derandomize=False)
    settings.load_profile("default")


@pytest.fixture
def bench_envelope_file(tmp_path: Path) -> Path:
    """An envelope file of 12 N*m, 40 rad/s: the bench logs of the CLI tests lie inside it."""
    from drive_envelope import PerformanceEnvelope, save_envelope

    path = tmp_path / "env.toml"
    save_envelope(PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=40.0, name="demo"), path)
    return path


@pytest.fixture(scope="session")
def bundled_physx_runs() -> dict[str, Any]:
    """Every bundled scenario (examples/scenarios/*.toml) run once on PhysX, by file stem.

    Once per test run: tests/test_teststand_physx.py and tests/test_parity_engines.py both hold
    the reference to these runs (one PhysX instance; run one by one they are the same bit for bit).
    """
    pytest.importorskip("ovphysx")
    import warnings

    from drive_envelope._src.scenario.spec import load_scenario
    from drive_envelope._src.teststand.engines import physx

    paths = sorted((Path(__file__).resolve().parents[1] / "examples" / "scenarios").glob("*.toml"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # authoring and ovphysx notes about the stand's stage
        runs = physx.simulate_many([load_scenario(path) for path in paths])
    return {path.stem: run for path, run in zip(paths, runs, strict=True)}

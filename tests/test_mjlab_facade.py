"""drive_envelope.mjlab without mjlab (the main environment): light, and a clear way to get it.

The actuators themselves are tested with the real mjlab in its own environment (tests/mjlab_env,
scripts/test_mjlab.sh): mjlab pins MuJoCo 3.11, this environment has MuJoCo 4.
"""

from __future__ import annotations

import importlib.util

import pytest


def _mjlab_installed() -> bool:
    # mjlab.actuator, not mjlab: a tests/mjlab folder would be importable as a namespace "mjlab" under pytest
    try:
        return importlib.util.find_spec("mjlab.actuator") is not None
    except ModuleNotFoundError:
        return False


@pytest.mark.skipif(_mjlab_installed(), reason="mjlab is installed here: tests/mjlab_env covers it")
@pytest.mark.parametrize("name", ["PerformanceEnvelopeActuatorCfg", "PerformanceEnvelopeActuator"])
def test_using_an_actuator_without_mjlab_says_how_to_get_it(name: str) -> None:
    """Raise an ImportError that names the install command, not an AttributeError or a traceback."""
    import drive_envelope.mjlab

    with pytest.raises(ImportError, match="pip install mjlab"):
        getattr(drive_envelope.mjlab, name)


def test_unknown_names_are_attribute_errors() -> None:
    """Keep hasattr() working on the facade."""
    import drive_envelope.mjlab

    assert not hasattr(drive_envelope.mjlab, "IdealPdActuator")

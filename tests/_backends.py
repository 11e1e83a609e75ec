"""The batched backends as a test parameter (tests/test_kernels_backends.py, tests/test_clamp_nonfinite.py).

Each parameter carries its engine marker, so it skips cleanly where the extra is absent, and CUDA
ones the ``gpu`` marker (tests/conftest.py). A test takes the fixture it needs, declared in its
file over one of these lists: ``PORTS`` (torch, Warp; host inputs), ``DEVICES`` (the ports on each
device), ``EVERY`` (the NumPy reference too, where a behaviour has numbers of its own).
"""

from __future__ import annotations

import dataclasses
import importlib
from typing import Any

import numpy as np
import pytest

import drive_envelope as de


@dataclasses.dataclass(frozen=True, kw_only=True)
class Backend:
    """One backend on one device: its module and how its arrays go up and come back."""

    name: str
    """``"numpy"``, ``"torch"`` or ``"warp"``."""
    device: str = "cpu"

    @property
    def module(self) -> Any:
        if self.name == "warp":
            import warp as wp

            wp.config.quiet = True
        return importlib.import_module(f"drive_envelope.{self.name}")

    @property
    def dtypes(self) -> tuple[str, ...]:
        """The float dtypes its effort-level ops compute in (Warp: float32 only, like PhysX)."""
        return ("float32",) if self.name == "warp" else ("float32", "float64")

    def upload(self, arrays: list[np.ndarray]) -> list[Any]:
        """The arrays on the backend's device, in its own array type (float32 for Warp)."""
        if self.name == "torch":
            import torch

            return [torch.from_numpy(a).to(self.device) for a in arrays]
        if self.name == "warp":
            import warp as wp

            return [wp.array(a, dtype=wp.float32, device=self.device) for a in arrays]
        return list(arrays)

    def params(self, envelopes: Any, count: int | None = None, dtype: str = "float32") -> Any:
        """The backend's parameter object (for NumPy: the envelope itself)."""
        if self.name == "numpy":
            return envelopes
        if self.name == "torch":
            kind = getattr(np, dtype)
            return self.module.EnvelopeTensors.from_envelopes(
                envelopes, count=count, device=self.device, dtype=kind
            )
        assert dtype == "float32"
        return self.module.EnvelopeArrays.from_envelopes(envelopes, count=count, device=self.device)

    def values(self, **kwargs: Any) -> Any:
        """The parameter object from ``from_values`` on the device."""
        kind = self.module.EnvelopeTensors if self.name == "torch" else self.module.EnvelopeArrays
        return kind.from_values(device=self.device, **kwargs)

    def ops(self) -> Any:
        """``effort_limit``, ``clamp_effort``, ``clamp_effort_implicit`` with the parameters first."""
        if self.name != "numpy":
            return self.module
        return _NumpyOps

    def host(self, result: Any) -> np.ndarray:
        """A result read back into a NumPy array."""
        if self.name == "torch":
            return np.asarray(result.detach().cpu().numpy())
        if self.name == "warp":
            import warp as wp

            return np.asarray(result.numpy() if isinstance(result, wp.array) else result)
        return np.asarray(result)


class _NumpyOps:
    """The reference under the ports' names: ``params`` is a :class:`PerformanceEnvelope`."""

    @staticmethod
    def effort_limit(envelope: de.PerformanceEnvelope, velocity: Any) -> Any:
        return envelope.effort_limit(velocity)

    clamp_effort = staticmethod(de.clamp_effort)
    clamp_effort_implicit = staticmethod(de.clamp_effort_implicit)


PORTS = [pytest.param("torch", marks=pytest.mark.torch), pytest.param("warp", marks=pytest.mark.warp)]
"""The ports, device-independent tests (host inputs)."""
DEVICES = [
    pytest.param(("torch", "cpu"), marks=pytest.mark.torch, id="torch-cpu"),
    pytest.param(("torch", "cuda"), marks=[pytest.mark.torch, pytest.mark.gpu], id="torch-cuda"),
    pytest.param(("warp", "cpu"), marks=pytest.mark.warp, id="warp-cpu"),
    pytest.param(("warp", "cuda:0"), marks=[pytest.mark.warp, pytest.mark.gpu], id="warp-cuda"),
]
"""The ports on each device."""
EVERY = [pytest.param(("numpy", "cpu"), id="numpy"), *DEVICES]
"""The reference and the ports on each device."""

"""The envelope parameters and their names across engines (PhysX, USD, MuJoCo, Isaac Lab, Newton)."""

from __future__ import annotations

from drive_envelope._src.params.table import PARAMETERS, Parameter, parameter, si_unit

__all__ = ["PARAMETERS", "Parameter", "parameter", "si_unit"]

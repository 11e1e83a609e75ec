"""Datasheet-to-sim: the PhysX envelope at the joint from motor, gear and controller datasheets.

Example::

    from drive_envelope.datasheet import derive, load_datasheet

    derivation = derive(load_datasheet("ak80-6.toml"))
    derivation.envelope            # PerformanceEnvelope, SI, joint side
    derivation.max_effort_limits   # every candidate limit, the binding one in max_effort_limited_by

Datasheet files take values as datasheets print them (``"91 mNm/A"``, ``"3000 min^-1"``); see
``docs/datasheet.md``. Catalog actuators (``catalog_entries()``) are datasheet files with sources.
"""

from __future__ import annotations

from drive_envelope._src.datasheet.catalog import (
    CatalogEntry,
    catalog_entries,
    catalog_text,
    load_catalog_datasheet,
)
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.load import datasheet_from_mapping, load_datasheet
from drive_envelope._src.datasheet.report import derivation_report, usd_snippet
from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.datasheet.result import Candidate, Derivation, Duty, LineFit
from drive_envelope._src.datasheet.spec import (
    ControllerSpec,
    Datasheet,
    GearboxSpec,
    GradientMethod,
    LossesSpec,
    MotorDatasheet,
    OutputRating,
    ParamSource,
    ScrewSpec,
    Transmission,
)

__all__ = [
    "Candidate",
    "CatalogEntry",
    "ControllerSpec",
    "Datasheet",
    "Derivation",
    "Duty",
    "GearboxSpec",
    "GradientMethod",
    "LineFit",
    "LossesSpec",
    "MotorDatasheet",
    "OutputRating",
    "ParamSource",
    "ScrewSpec",
    "Transmission",
    "catalog_entries",
    "catalog_text",
    "datasheet_from_mapping",
    "derivation_report",
    "derive",
    "load_catalog_datasheet",
    "load_datasheet",
    "resolve_envelope",
    "usd_snippet",
]

"""Datasheet-to-sim: the PhysX envelope at the joint from motor, gear and controller datasheets.

Example::

    from drive_envelope.datasheet import derive, load_datasheet

    derivation = derive(load_datasheet("ak80-6.toml"))
    derivation.envelope            # PerformanceEnvelope, SI, joint side
    derivation.max_effort_limits   # every candidate limit, the binding one in max_effort_limited_by

Datasheet files take values as datasheets print them (``"91 mNm/A"``, ``"3000 min^-1"``); see
``docs/datasheet.md``. Catalog actuators (``catalog_entries()``) are datasheet files with sources
(``catalog_sources(key)``); ``robot_maps()`` lists the shipped maps of joint patterns -> catalog
actuators for popular robots (Unitree Go2 and G1, SO-101, Franka Panda and FR3).
"""

from __future__ import annotations

from drive_envelope._src.datasheet.catalog import (
    CatalogEntry,
    SourcedValue,
    catalog_entries,
    catalog_sources,
    catalog_text,
    load_catalog_datasheet,
)
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.load import datasheet_from_mapping, load_datasheet
from drive_envelope._src.datasheet.maps import RobotMap, robot_map_path, robot_maps
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
    "RobotMap",
    "ScrewSpec",
    "SourcedValue",
    "Transmission",
    "catalog_entries",
    "catalog_sources",
    "catalog_text",
    "datasheet_from_mapping",
    "derivation_report",
    "derive",
    "load_catalog_datasheet",
    "load_datasheet",
    "resolve_envelope",
    "robot_map_path",
    "robot_maps",
    "usd_snippet",
]

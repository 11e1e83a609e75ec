"""OpenUSD: author PhysX drive performance envelopes into robot assets and read them back.

Needs the ``usd`` extra (``usd-core`` and the codeless ``physx-usd-schemas``); ``pxr`` is imported
only when a function runs. Values in and out are SI, joint side; the conversion to USD's degrees and
to the stage's ``metersPerUnit`` / ``kilogramsPerUnit`` happens here.

Example::

    from pxr import Usd
    from drive_envelope import PerformanceEnvelope
    from drive_envelope.usd import read_envelope, write_envelope

    stage = Usd.Stage.Open("robot.usda")
    env = PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=37.7, speed_effort_gradient=0.57)
    write_envelope(stage, "/Robot/joints/knee", env)       # PhysicsDriveAPI:angular + envelope API
    assert read_envelope(stage, "/Robot/joints/knee").max_effort == 12.0
"""

from __future__ import annotations

from drive_envelope._src.adapters.usd.apply import read_map
from drive_envelope._src.adapters.usd.authoring import (
    DriveRecord,
    EnvelopeAuthoringWarning,
    list_drives,
    read_envelope,
    write_envelope,
)
from drive_envelope._src.adapters.usd.scale import StageUnits
from drive_envelope._src.adapters.usd.stage import open_stage, register_schemas, save_stage, stage_units

__all__ = [
    "DriveRecord",
    "EnvelopeAuthoringWarning",
    "StageUnits",
    "list_drives",
    "open_stage",
    "read_envelope",
    "read_map",
    "register_schemas",
    "save_stage",
    "stage_units",
    "write_envelope",
]

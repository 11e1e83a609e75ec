"""OpenUSD: author PhysX drive performance envelopes into robot assets and read them back.

Needs the ``usd`` extra (``usd-core`` and the codeless ``physx-usd-schemas``); ``pxr`` is imported
only when a function runs. Values in and out are SI, joint side; the conversion to USD's degrees and
to the stage's ``metersPerUnit`` / ``kilogramsPerUnit`` happens here.

Example (non-destructive: the asset is not edited, a small layer over it holds the envelopes)::

    from drive_envelope import PerformanceEnvelope
    from drive_envelope.usd import open_overlay, read_envelope, save_stage, write_envelope

    stage = open_overlay("robot.usda")                     # a new in-memory layer over the asset
    env = PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=37.7, speed_effort_gradient=0.57)
    write_envelope(stage, "/Robot/joints/knee", env)       # PhysicsDriveAPI:angular + envelope API
    assert read_envelope(stage, "/Robot/joints/knee").max_effort == 12.0
    save_stage(stage, "robot_envelope.usda")               # sublayers ./robot.usda, checked, atomic

``open_stage`` + ``save_stage(stage)`` edits the asset's own layers in place instead, and
``save_stage(stage, "robot_flat.usda", flatten=True)`` writes one self-contained file.
"""

from __future__ import annotations

from drive_envelope._src.adapters.usd.authoring import (
    DriveRecord,
    EnvelopeAuthoringWarning,
    list_drives,
    read_envelope,
    write_envelope,
)
from drive_envelope._src.adapters.usd.joint_map import read_map
from drive_envelope._src.adapters.usd.save import save_stage
from drive_envelope._src.adapters.usd.scale import StageUnits
from drive_envelope._src.adapters.usd.stage import (
    UsdStageWarning,
    open_overlay,
    open_stage,
    register_schemas,
    stage_units,
)

__all__ = [
    "DriveRecord",
    "EnvelopeAuthoringWarning",
    "StageUnits",
    "UsdStageWarning",
    "list_drives",
    "open_overlay",
    "open_stage",
    "read_envelope",
    "read_map",
    "register_schemas",
    "save_stage",
    "stage_units",
    "write_envelope",
]

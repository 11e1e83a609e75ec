"""Edge scenarios every engine's test stand is held to, step by step, against the reference.

Each engine's tests take these (``EDGE_CASES``) and add their own; a case both need lives here once.
"""

from __future__ import annotations

from typing import Any

EDGE_CASES: dict[str, dict[str, Any]] = {
    "prismatic_acceleration_drive": {
        "joint": {"type": "prismatic", "inertia": 2.0},
        "drive": {
            "type": "acceleration",
            "stiffness": 400.0,
            "damping": 30.0,
            "target_position": 0.2,
            "max_effort": 50,
        },
        "envelope": {
            "max_actuator_velocity": 0.5,
            "velocity_dependent_resistance": 20.0,
            "speed_effort_gradient": 0.002,
        },
    },
    "applied_and_external_effort": {
        "joint": {"type": "revolute", "inertia": 0.02, "initial_velocity": -2.0},
        "drive": {
            "stiffness": 50.0,
            "damping": 1.0,
            "target_position": -1.0,
            "target_velocity": 0.5,
            "max_effort": 4,
        },
        "envelope": {
            "max_actuator_velocity": 6.0,
            "velocity_dependent_resistance": 0.3,
            "speed_effort_gradient": 0.2,
        },
        "load": {"applied_effort": 1.5, "external_effort": -0.8},
    },
    "stiff_step_plain_drive": {
        "joint": {"type": "revolute", "inertia": 0.01},
        "drive": {"stiffness": 5000.0, "damping": 10.0, "target_position": 1.0, "max_effort": 20},
        "load": {"applied_effort": 5.0},
    },
    "drive_off_applied_only": {
        "joint": {"type": "revolute", "inertia": 0.1},
        "drive": {"stiffness": 10.0, "damping": 1.0, "target_position": 1.0, "max_effort": 0},
        "load": {"applied_effort": 0.7},
    },
    "unlimited_drive": {
        "joint": {"type": "prismatic", "inertia": 1.0},
        "drive": {"stiffness": 100.0, "damping": 5.0, "target_position": -0.3},
    },
    "speed_line_only": {  # PhysX's unauthored maxForce (FLT_MAX) under an envelope: eq. 2 alone
        "joint": {"type": "revolute", "inertia": 0.05},
        "drive": {"damping": 20.0, "target_velocity": 10.0, "max_effort": 3.4028234663852886e38},
        "envelope": {"max_actuator_velocity": 3.0, "speed_effort_gradient": 0.1},
    },
}
"""Scenario mappings by name: an acceleration drive on a prismatic joint, applied and external
effort together, a stiff plain drive, a drive that is off, an unlimited drive, an envelope on an
unlimited drive (the speed line alone)."""

"""The single table of envelope parameters: names, SI units and every engine's name for them.

Adapters take their field names from here; ``docs/glossary.md`` is generated from it
(``python -m drive_envelope._src.params.glossary``) and a test keeps the file fresh.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, kw_only=True, slots=True)
class Parameter:
    """One envelope parameter and its names across engines."""

    name: str
    """Our name (the PhysX name in snake_case)."""
    symbol: str
    """Symbol in the specification."""
    meaning: str
    """One-line meaning."""
    unit_revolute: str
    """SI unit on a revolute joint, as pint reads it."""
    unit_prismatic: str
    """SI unit on a prismatic joint, as pint reads it."""
    physx_cpp: str
    """Field of ``PxPerformanceEnvelope``."""
    usd_attribute: str
    """USD attribute (``{inst}`` is the drive instance: angular, linear, rotX, ...)."""
    usd_unit_angular: str
    """Unit USD stores on angular instances (degrees)."""
    physx_tensor_index: int | None
    """Position in the PhysX tensor API's three-value envelope (None: maxForce, not in that tensor)."""
    mujoco_plugin: str
    """Slot in ``actuator_dynprm`` of the drive's first actuator (plugin ``drive_envelope.envelope``)."""
    isaac_lab: str
    """Isaac Lab 2.3's name (``isaaclab.actuators`` cfg fields), and where this package puts it there."""
    newton: str
    """Newton 1.8's name where Newton has the concept, and this package's clamping stage's."""


PARAMETERS: tuple[Parameter, ...] = (
    Parameter(
        name="max_effort",
        symbol="tau_max",
        meaning="effort cap at zero velocity (eq. 1)",
        unit_revolute="N*m",
        unit_prismatic="N",
        physx_cpp="maxEffort",
        usd_attribute="drive:{inst}:physics:maxForce",
        usd_unit_angular="N*m",
        physx_tensor_index=None,
        mujoco_plugin="actuator_dynprm[0]",
        isaac_lab=(
            "`effort_limit` (an explicit actuator's clip; PerformanceEnvelopeActuatorCfg's max_effort) / "
            "`effort_limit_sim` (PhysX's maxForce, i.e. maxEffort, through write_joint_effort_limit_to_sim)"
        ),
        newton="joint_effort_limit / ClampingMaxEffort.max_effort; ClampingPerformanceEnvelope.max_effort",
    ),
    Parameter(
        name="max_actuator_velocity",
        symbol="v_max",
        meaning="velocity cap at zero effort (eq. 2)",
        unit_revolute="rad/s",
        unit_prismatic="m/s",
        physx_cpp="maxActuatorVelocity",
        usd_attribute="physxDrivePerformanceEnvelope:{inst}:maxActuatorVelocity",
        usd_unit_angular="deg/s",
        physx_tensor_index=1,
        mujoco_plugin="actuator_dynprm[1] (-1: no limit)",
        isaac_lab=(
            "none (`velocity_limit_sim` is PhysX's joint speed cap maxJointVelocity; DCMotorCfg's "
            "`velocity_limit` is its no-load speed); PerformanceEnvelopeActuatorCfg.max_actuator_velocity"
        ),
        newton=(
            "ClampingDCMotor.velocity_limit (no-load speed); "
            "ClampingPerformanceEnvelope.max_actuator_velocity"
        ),
    ),
    Parameter(
        name="velocity_dependent_resistance",
        symbol="k_tau_v",
        meaning="effort lost per unit speed (slope of eq. 1)",
        unit_revolute="N*m*s/rad",
        unit_prismatic="N*s/m",
        physx_cpp="velocityDependentResistance",
        usd_attribute="physxDrivePerformanceEnvelope:{inst}:velocityDependentResistance",
        usd_unit_angular="N*m*s/deg",
        physx_tensor_index=2,
        mujoco_plugin="actuator_dynprm[2]",
        isaac_lab=(
            "none (`viscous_friction` is joint friction, outside the envelope); "
            "PerformanceEnvelopeActuatorCfg.velocity_dependent_resistance"
        ),
        newton="(none); ClampingPerformanceEnvelope.velocity_dependent_resistance",
    ),
    Parameter(
        name="speed_effort_gradient",
        symbol="k_v_tau",
        meaning="speed lost per unit effort (slope of eq. 2)",
        unit_revolute="(rad/s)/(N*m)",
        unit_prismatic="(m/s)/N",
        physx_cpp="speedEffortGradient",
        usd_attribute="physxDrivePerformanceEnvelope:{inst}:speedEffortGradient",
        usd_unit_angular="(deg/s)/(N*m)",
        physx_tensor_index=0,
        mujoco_plugin="actuator_dynprm[3]",
        isaac_lab=(
            "none (DCMotorCfg's line: `velocity_limit` / `saturation_effort`); "
            "PerformanceEnvelopeActuatorCfg.speed_effort_gradient"
        ),
        newton=(
            "implicit in ClampingDCMotor (velocity_limit / saturation_effort); "
            "ClampingPerformanceEnvelope.speed_effort_gradient"
        ),
    ),
)


def parameter(name: str) -> Parameter:
    """Return the table row of ``name`` (one of the four envelope parameters)."""
    for row in PARAMETERS:
        if row.name == name:
            return row
    raise KeyError(name)


def si_unit(name: str, joint: str) -> str:
    """SI unit of parameter ``name`` on a ``joint`` ("revolute" | "prismatic") joint."""
    row = parameter(name)
    return row.unit_revolute if joint == "revolute" else row.unit_prismatic

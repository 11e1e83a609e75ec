"""The test-stand scene as USD: one fixed-base articulation with one driven joint.

Layout (``metersPerUnit`` / ``kilogramsPerUnit`` as given, Z up)::

    /World/physicsScene        PhysicsScene + PhysxSceneAPI (solver type, step rate, gravity)
    /World/stand               ArticulationRootAPI + PhysxArticulationAPI (iteration counts)
    /World/stand/base          rigid body, welded to the world by /World/stand/rootJoint
    /World/stand/link          rigid body: the scenario's inertia about Z (revolute) or its mass (prismatic)
    /World/stand/joint         revolute about Z or prismatic along X, PhysicsDriveAPI + envelope,
                               PhysxJointAxisAPI (armature, friction)

The link has zero linear and angular damping and ``cfmScale`` 0 and the joint no velocity cap; the
joint's armature and friction (``physxJointAxis:<axis>:armature``, ``staticFrictionEffort``,
``dynamicFrictionEffort``, ``viscousFrictionCoefficient``, angular viscous friction per degree) are
the scenario's, 0 unless it has them. Without a ``[pendulum]`` the scene has no gravity and the
link's centre of mass lies on the joint axis (at the joint frame): then PhysX's
``jointProjectedForce``, which the runner logs, is the drive + applied effort. With a pendulum the
link carries the point mass (its mass; its centre of mass ``distance`` from the axis, at
``angle_offset`` from straight down; the scenario's inertia about that centre) and the scene has
gravity along -Y, perpendicular to the Z axis of the joint; the projected force then also holds the
reaction of the link's motion, so the runner reports the drive effort another way (see the runner).
The envelope is authored with :func:`~drive_envelope._src.adapters.usd.authoring.write_envelope`
(the same code path as ``drive-envelope usd apply``).
"""

from __future__ import annotations

import math
import os
import warnings
from typing import TYPE_CHECKING

from drive_envelope._src.adapters.usd.scale import StageUnits, is_angular
from drive_envelope._src.scenario.chain_frames import IDENTITY, Quaternion

if TYPE_CHECKING:
    from pxr import Usd

    from drive_envelope._src.envelope.model import PerformanceEnvelope
    from drive_envelope._src.scenario.loads import FrictionSpec
    from drive_envelope._src.scenario.spec import DriveSpec, Scenario, SimulationSpec

ARTICULATION_PATH = "/World/stand"
"""Prim path of the articulation root (the tensor-binding pattern)."""
LINK_PATH = "/World/stand/link"
"""Prim path of the driven link."""
JOINT_PATH = "/World/stand/joint"
"""Prim path of the driven joint."""
_HUGE = 1.0e30  # "no cap" for PhysX floats that have a finite default


def build_teststand_stage(
    scenario: Scenario, path: str | os.PathLike[str] | None = None, *, units: StageUnits | None = None
) -> Usd.Stage:
    """Author the scenario as a USD stage (and export it to ``path`` when given).

    Args:
        scenario: The test-stand scenario (SI).
        path: Where to write the stage (``.usda``), or None for an in-memory stage only.
        units: Stage units; SI (1 m, 1 kg) by default. Every value is converted to them.

    Returns:
        The stage.
    """
    units = units or StageUnits()
    stage = new_stage(units)
    if scenario.pendulum is None:  # no gravity; a pendulum's is perpendicular to the joint's Z axis
        define_physics_scene(stage, scenario.simulation, (0.0, 0.0, -1.0), 0.0)
    else:
        gravity = float(scenario.simulation.gravity * units.length())
        define_physics_scene(stage, scenario.simulation, (0.0, -1.0, 0.0), gravity)
    define_articulation_root(stage, ARTICULATION_PATH, scenario.simulation)
    revolute = scenario.joint.type == "revolute"
    mass_si = 1.0 if revolute else scenario.joint.inertia
    inertia_si = scenario.joint.inertia if revolute else 1.0
    centre = (0.0, 0.0, 0.0)
    pendulum = scenario.pendulum
    if pendulum is not None:
        # hanging straight down (-Y, along gravity) at position = -angle_offset
        offset, distance = pendulum.angle_offset, pendulum.distance * units.length()
        mass_si, centre = pendulum.mass, (distance * math.sin(offset), -distance * math.cos(offset), 0.0)
    define_body(stage, LINK_PATH, mass=mass_si * units.mass(), inertia=(inertia_si * units.inertia(),) * 3,
                centre=centre)  # fmt: skip
    _define_joint(stage, scenario, units)
    if path is not None:
        stage.GetRootLayer().Export(os.fspath(path))
    return stage


def new_stage(units: StageUnits) -> Usd.Stage:
    """An in-memory stage in ``units``, Z up, with ``/World`` as its default prim."""
    from drive_envelope._src.adapters.usd.stage import register_schemas

    register_schemas()
    from pxr import Usd, UsdGeom, UsdPhysics

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, units.meters_per_unit)
    UsdPhysics.SetStageKilogramsPerUnit(stage, units.kilograms_per_unit)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/World").GetPrim())
    return stage


def _set(prim: Usd.Prim, name: str, type_name: object, value: object) -> None:
    prim.CreateAttribute(name, type_name, False).Set(value)


def define_physics_scene(
    stage: Usd.Stage, sim: SimulationSpec, direction: tuple[float, float, float], gravity: float
) -> None:
    """``/World/physicsScene``: gravity [m/s^2 in stage units] along ``direction``, the solver settings."""
    from pxr import Gf, Sdf, UsdPhysics

    scene = UsdPhysics.Scene.Define(stage, "/World/physicsScene")
    scene.CreateGravityDirectionAttr().Set(Gf.Vec3f(*direction))
    scene.CreateGravityMagnitudeAttr().Set(float(gravity))
    prim = scene.GetPrim()
    prim.ApplyAPI("PhysxSceneAPI")
    _set(prim, "physxScene:solverType", Sdf.ValueTypeNames.Token, sim.solver.upper())
    _set(prim, "physxScene:timeStepsPerSecond", Sdf.ValueTypeNames.UInt, max(1, round(1.0 / sim.dt)))
    # explicit, as the reference engine models it (TGS: forces and envelope clamp per substep).
    # ovphysx 0.3's bundled schema defaulted it to false; ovphysx 0.7 reads physx-usd-schemas
    # (25.11: true) and runs unauthored bit-identically to true. Deprecated: true is TGS's future
    _set(prim, "physxScene:enableExternalForcesEveryIteration", Sdf.ValueTypeNames.Bool, True)
    _set(prim, "physxScene:enableStabilization", Sdf.ValueTypeNames.Bool, False)
    _set(prim, "physxScene:enableGPUDynamics", Sdf.ValueTypeNames.Bool, False)
    _set(prim, "physxScene:broadphaseType", Sdf.ValueTypeNames.Token, "MBP")


def define_articulation_root(stage: Usd.Stage, path: str, sim: SimulationSpec) -> None:
    """An articulation root at ``path``: its iteration counts; no sleep, stabilization or self-collision.

    Its fixed base is ``<path>/base``, a unit rigid body welded to the world by ``<path>/rootJoint``.
    """
    from pxr import Sdf, UsdGeom, UsdPhysics

    root = UsdGeom.Xform.Define(stage, path).GetPrim()
    UsdPhysics.ArticulationRootAPI.Apply(root)
    root.ApplyAPI("PhysxArticulationAPI")
    counts = (("Position", sim.position_iterations), ("Velocity", sim.velocity_iterations))
    for kind, count in counts:
        _set(root, f"physxArticulation:solver{kind}IterationCount", Sdf.ValueTypeNames.Int, count)
    _set(root, "physxArticulation:sleepThreshold", Sdf.ValueTypeNames.Float, 0.0)
    _set(root, "physxArticulation:stabilizationThreshold", Sdf.ValueTypeNames.Float, 0.0)
    _set(root, "physxArticulation:enabledSelfCollisions", Sdf.ValueTypeNames.Bool, False)
    define_body(stage, f"{path}/base", mass=1.0, inertia=(1.0, 1.0, 1.0))
    fixed = UsdPhysics.FixedJoint.Define(stage, f"{path}/rootJoint")
    fixed.CreateBody1Rel().SetTargets([Sdf.Path(f"{path}/base")])


def define_body(
    stage: Usd.Stage,
    path: str,
    *,
    mass: float,
    inertia: tuple[float, ...],
    centre: tuple[float, ...] = (0.0, 0.0, 0.0),
    translate: tuple[float, ...] | None = None,
    orient: Quaternion = IDENTITY,
    principal_axes: Quaternion = IDENTITY,
) -> None:
    """A rigid body at ``path``, posed by ``translate`` and ``orient`` when given (stage units).

    No damping, ``cfmScale`` 0, no velocity caps, no sleep: PhysX adds nothing the reference lacks.
    """
    from pxr import Gf, Sdf, UsdGeom, UsdPhysics

    xform = UsdGeom.Xform.Define(stage, path)
    if translate is not None:
        xform.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*translate))
    if orient != IDENTITY:
        xform.AddOrientOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Quatd(orient[0], *orient[1:]))
    prim = xform.GetPrim()
    UsdPhysics.RigidBodyAPI.Apply(prim)
    mass_api = UsdPhysics.MassAPI.Apply(prim)
    mass_api.CreateMassAttr().Set(float(mass))
    mass_api.CreateDiagonalInertiaAttr().Set(Gf.Vec3f(*inertia))
    mass_api.CreateCenterOfMassAttr().Set(Gf.Vec3f(*centre))
    if principal_axes != IDENTITY:
        mass_api.CreatePrincipalAxesAttr().Set(Gf.Quatf(principal_axes[0], *principal_axes[1:]))
    prim.ApplyAPI("PhysxRigidBodyAPI")
    # PhysX defaults: angular damping 0.05 and cfmScale 0.025 would add effort the drive model lacks
    for name in ("linearDamping", "angularDamping", "cfmScale", "sleepThreshold", "stabilizationThreshold"):
        _set(prim, f"physxRigidBody:{name}", Sdf.ValueTypeNames.Float, 0.0)
    for name in ("maxLinearVelocity", "maxAngularVelocity"):
        _set(prim, f"physxRigidBody:{name}", Sdf.ValueTypeNames.Float, _HUGE)


def _define_joint(stage: Usd.Stage, scenario: Scenario, units: StageUnits) -> None:
    from pxr import Sdf, UsdPhysics

    revolute = scenario.joint.type == "revolute"
    if revolute:
        joint = UsdPhysics.RevoluteJoint.Define(stage, JOINT_PATH)
        joint.CreateAxisAttr().Set(UsdPhysics.Tokens.z)
    else:
        joint = UsdPhysics.PrismaticJoint.Define(stage, JOINT_PATH)
        joint.CreateAxisAttr().Set(UsdPhysics.Tokens.x)
    joint.CreateBody0Rel().SetTargets([Sdf.Path(f"{ARTICULATION_PATH}/base")])
    joint.CreateBody1Rel().SetTargets([Sdf.Path(LINK_PATH)])
    inst = "angular" if revolute else "linear"
    armature = scenario.joint.armature * (units.inertia() if revolute else units.mass())
    author_drive(joint.GetPrim(), inst, scenario.drive, scenario.envelope, units, armature, scenario.friction)


def drive_gains(drive: DriveSpec, inst: str, units: StageUnits) -> tuple[float, float]:
    """``(stiffness, damping)`` of a drive as the stage stores them (per degree on angular drives)."""
    if drive.type == "force":
        return drive.stiffness * units.per_position(inst), drive.damping * units.per_speed(inst)
    # acceleration gains: per time only, but per degree on angular drives like every gain
    angle = 1.0 / units.position(inst) if is_angular(inst) else 1.0
    return drive.stiffness * angle, drive.damping * angle


def author_drive(
    prim: Usd.Prim,
    inst: str,
    spec: DriveSpec,
    envelope: PerformanceEnvelope | None,
    units: StageUnits,
    armature: float,
    friction: FrictionSpec,
) -> None:
    """A stand joint's drive and its envelope (else the drive's maxForce), in stage units.

    Also its PhysxJointAxisAPI: ``armature`` (in stage units), friction and no velocity cap.
    """
    from pxr import Sdf, UsdPhysics

    from drive_envelope._src.adapters.usd.authoring import EnvelopeAuthoringWarning, write_envelope

    # per-axis joint properties (PhysX reads PhysxJointAxisAPI before the older PhysxJointAPI)
    prim.ApplyAPI("PhysxJointAxisAPI", inst)
    axis = {
        "armature": armature,
        "staticFrictionEffort": friction.static_friction * units.effort(inst),
        "dynamicFrictionEffort": friction.dynamic_friction * units.effort(inst),
        "viscousFrictionCoefficient": friction.viscous_friction * units.per_speed(inst),  # per degree
        "maxJointVelocity": _HUGE,
    }
    for name, value in axis.items():
        _set(prim, f"physxJointAxis:{inst}:{name}", Sdf.ValueTypeNames.Float, float(value))
    drive = UsdPhysics.DriveAPI.Apply(prim, inst)
    drive.CreateTypeAttr().Set(spec.type)
    stiffness, damping = drive_gains(spec, inst, units)
    drive.CreateStiffnessAttr().Set(float(stiffness))
    drive.CreateDampingAttr().Set(float(damping))
    drive.CreateTargetPositionAttr().Set(float(spec.target_position * units.position(inst)))
    drive.CreateTargetVelocityAttr().Set(float(spec.target_velocity * units.velocity(inst)))
    if envelope is not None:
        with warnings.catch_warnings():
            # the authoring warnings judge a user's asset (per-radian gains, ...); the stand's gains are
            # the scenario's, converted here, so a stiff velocity drive is meant, not a mistake
            warnings.simplefilter("ignore", EnvelopeAuthoringWarning)
            write_envelope(prim, None, envelope, inst)
    else:
        max_force = spec.max_effort * units.effort(inst)
        drive.CreateMaxForceAttr().Set(math.inf if math.isinf(max_force) else float(max_force))

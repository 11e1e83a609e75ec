"""A chain scenario as USD: one fixed-base articulation with a driven joint per link (SI stage).

Layout (1 m, 1 kg, Z up, gravity along -Z with the scenario's magnitude)::

    /World/physicsScene          PhysicsScene + PhysxSceneAPI (solver type, step rate)
    /World/chain                 ArticulationRootAPI + PhysxArticulationAPI (iteration counts)
    /World/chain/base            rigid body at the world origin, welded by /World/chain/rootJoint
    /World/chain/<name>          one rigid body per joint, at its link frame's zero-position pose,
                                 mass, centre of mass, diagonalInertia and principalAxes
    /World/chain/<name>_joint    revolute (about) or prismatic (along) its axis, body0 the parent,
                                 PhysicsDriveAPI + envelope, PhysxJointAxisAPI (armature, friction)

A joint on a named axis of an unturned frame is authored as before (``physics:axis`` X, Y or Z,
identity local rotations). Otherwise the joint frame carries the rotation: on body1 (the link)
``localRot1`` turns PhysX's joint X axis onto the joint's axis, on body0 ``localRot0`` is the
link frame's fixed rotation times that turn, so at zero position the two frames coincide and the
link sits at its frame's pose.

Every link has zero damping, ``cfmScale`` 0 and no velocity caps, as on the one-joint stand
(:mod:`~drive_envelope._src.adapters.physx.scene`), so PhysX adds nothing the reference engine
lacks. The envelope is authored with the same code as ``drive-envelope usd apply``.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING

from drive_envelope._src.adapters.physx.scene import _set, define_articulation_root, define_physics_scene
from drive_envelope._src.scenario.chain_frames import (
    IDENTITY,
    Quaternion,
    quat_multiply,
    quat_taking_x_to,
    rotate,
)

if TYPE_CHECKING:
    from pxr import Usd

    from drive_envelope._src.scenario.chain import ChainJoint, ChainScenario

CHAIN_PATH = "/World/chain"
"""Prim path of the articulation root."""
_BASE = f"{CHAIN_PATH}/base"
_HUGE = 1.0e30  # "no cap" for PhysX floats that have a finite default


def link_path(joint: ChainJoint) -> str:
    """Prim path of the link a joint carries."""
    return f"{CHAIN_PATH}/{joint.name}"


def joint_path(joint: ChainJoint) -> str:
    """Prim path of a chain joint."""
    return f"{CHAIN_PATH}/{joint.name}_joint"


def zero_pose(scenario: ChainScenario) -> list[tuple[Quaternion, tuple[float, float, float]]]:
    """Each link frame's world rotation ``(w, x, y, z)`` and origin [m] at zero joint position."""
    poses: list[tuple[Quaternion, tuple[float, float, float]]] = []
    for joint in scenario.joints:
        rotation, origin = poses[joint.parent] if joint.parent >= 0 else (IDENTITY, (0.0, 0.0, 0.0))
        shift = rotate(rotation, joint.origin)
        here = (origin[0] + shift[0], origin[1] + shift[1], origin[2] + shift[2])
        poses.append((quat_multiply(rotation, joint.quat), here))
    return poses


def _body(stage: Usd.Stage, path: str, *, mass: float, inertia: tuple[float, ...], com: tuple[float, ...],
          translate: tuple[float, ...], orient: Quaternion = IDENTITY,
          principal_axes: Quaternion = IDENTITY) -> None:  # fmt: skip
    from pxr import Gf, Sdf, UsdGeom, UsdPhysics

    xform = UsdGeom.Xform.Define(stage, path)
    xform.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*translate))
    if orient != IDENTITY:
        xform.AddOrientOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Quatd(orient[0], *orient[1:]))
    prim = xform.GetPrim()
    UsdPhysics.RigidBodyAPI.Apply(prim)
    mass_api = UsdPhysics.MassAPI.Apply(prim)
    mass_api.CreateMassAttr().Set(float(mass))
    mass_api.CreateDiagonalInertiaAttr().Set(Gf.Vec3f(*inertia))
    mass_api.CreateCenterOfMassAttr().Set(Gf.Vec3f(*com))
    if principal_axes != IDENTITY:
        mass_api.CreatePrincipalAxesAttr().Set(Gf.Quatf(principal_axes[0], *principal_axes[1:]))
    prim.ApplyAPI("PhysxRigidBodyAPI")
    for name in ("linearDamping", "angularDamping", "cfmScale", "sleepThreshold", "stabilizationThreshold"):
        _set(prim, f"physxRigidBody:{name}", Sdf.ValueTypeNames.Float, 0.0)
    for name in ("maxLinearVelocity", "maxAngularVelocity"):
        _set(prim, f"physxRigidBody:{name}", Sdf.ValueTypeNames.Float, _HUGE)


def build_chain_stage(scenario: ChainScenario) -> Usd.Stage:
    """Author the chain scenario as an in-memory USD stage (SI units)."""
    from drive_envelope._src.adapters.usd.stage import register_schemas

    register_schemas()
    from pxr import Sdf, Usd, UsdGeom, UsdPhysics

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/World").GetPrim())
    define_physics_scene(stage, scenario.simulation, (0.0, 0.0, -1.0), float(scenario.simulation.gravity))
    define_articulation_root(stage, CHAIN_PATH, scenario.simulation)
    _body(stage, _BASE, mass=1.0, inertia=(1.0, 1.0, 1.0), com=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0))
    fixed = UsdPhysics.FixedJoint.Define(stage, f"{CHAIN_PATH}/rootJoint")
    fixed.CreateBody1Rel().SetTargets([Sdf.Path(_BASE)])
    for joint, (orient, here) in zip(scenario.joints, zero_pose(scenario), strict=True):
        _body(stage, link_path(joint), mass=joint.mass, inertia=joint.inertia, com=joint.com, translate=here,
              orient=orient, principal_axes=joint.inertia_quat)  # fmt: skip
        body0 = _BASE if joint.parent < 0 else link_path(scenario.joints[joint.parent])
        _joint(stage, joint, body0)
    return stage


def _joint(stage: Usd.Stage, spec: ChainJoint, body0: str) -> None:
    from pxr import Gf, Sdf, UsdPhysics

    from drive_envelope._src.adapters.usd.authoring import EnvelopeAuthoringWarning, write_envelope

    revolute = spec.type == "revolute"
    kind = UsdPhysics.RevoluteJoint if revolute else UsdPhysics.PrismaticJoint
    joint = kind.Define(stage, joint_path(spec))
    # a named axis keeps its letter; any other axis is PhysX's X turned onto it by the joint frame
    align = IDENTITY if isinstance(spec.axis, str) else quat_taking_x_to(spec.axis)
    joint.CreateAxisAttr().Set(spec.axis.upper() if isinstance(spec.axis, str) else "X")
    joint.CreateBody0Rel().SetTargets([Sdf.Path(body0)])
    joint.CreateBody1Rel().SetTargets([Sdf.Path(link_path(spec))])
    joint.CreateLocalPos0Attr().Set(Gf.Vec3f(*spec.origin))
    joint.CreateLocalPos1Attr().Set(Gf.Vec3f(0.0, 0.0, 0.0))
    rot0, rot1 = quat_multiply(spec.quat, align), align
    if rot0 != IDENTITY or rot1 != IDENTITY:
        joint.CreateLocalRot0Attr().Set(Gf.Quatf(rot0[0], *rot0[1:]))
        joint.CreateLocalRot1Attr().Set(Gf.Quatf(rot1[0], *rot1[1:]))
    prim = joint.GetPrim()
    inst = "angular" if revolute else "linear"
    per_degree = math.pi / 180.0 if revolute else 1.0  # USD stores angular values per degree
    prim.ApplyAPI("PhysxJointAxisAPI", inst)
    friction = spec.friction
    axis = {
        "armature": spec.armature,
        "staticFrictionEffort": friction.static_friction,
        "dynamicFrictionEffort": friction.dynamic_friction,
        "viscousFrictionCoefficient": friction.viscous_friction * per_degree,
        "maxJointVelocity": _HUGE,
    }
    for name, value in axis.items():
        _set(prim, f"physxJointAxis:{inst}:{name}", Sdf.ValueTypeNames.Float, float(value))
    drive_spec = spec.drive
    drive = UsdPhysics.DriveAPI.Apply(prim, inst)
    drive.CreateTypeAttr().Set(drive_spec.type)
    drive.CreateStiffnessAttr().Set(float(drive_spec.stiffness * per_degree))
    drive.CreateDampingAttr().Set(float(drive_spec.damping * per_degree))
    drive.CreateTargetPositionAttr().Set(float(drive_spec.target_position / per_degree))
    drive.CreateTargetVelocityAttr().Set(float(drive_spec.target_velocity / per_degree))
    if spec.envelope is not None:
        with warnings.catch_warnings():  # the stand's gains are meant, not a per-radian mistake
            warnings.simplefilter("ignore", EnvelopeAuthoringWarning)
            write_envelope(prim, None, spec.envelope, inst)
    else:
        max_force = drive_spec.max_effort
        drive.CreateMaxForceAttr().Set(math.inf if math.isinf(max_force) else float(max_force))

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

from typing import TYPE_CHECKING

from drive_envelope._src.adapters.physx.scene import (
    author_drive,
    define_articulation_root,
    define_body,
    define_physics_scene,
    new_stage,
)
from drive_envelope._src.adapters.usd.scale import StageUnits
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


def build_chain_stage(scenario: ChainScenario) -> Usd.Stage:
    """Author the chain scenario as an in-memory USD stage (SI units)."""
    stage = new_stage(StageUnits())
    define_physics_scene(stage, scenario.simulation, (0.0, 0.0, -1.0), float(scenario.simulation.gravity))
    define_articulation_root(stage, CHAIN_PATH, scenario.simulation)
    for joint, (orient, here) in zip(scenario.joints, zero_pose(scenario), strict=True):
        define_body(stage, link_path(joint), mass=joint.mass, inertia=joint.inertia, centre=joint.com,
                    translate=here, orient=orient, principal_axes=joint.inertia_quat)  # fmt: skip
        body0 = _BASE if joint.parent < 0 else link_path(scenario.joints[joint.parent])
        _joint(stage, joint, body0)
    return stage


def _joint(stage: Usd.Stage, spec: ChainJoint, body0: str) -> None:
    from pxr import Gf, Sdf, UsdPhysics

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
    inst = "angular" if revolute else "linear"
    author_drive(joint.GetPrim(), inst, spec.drive, spec.envelope, StageUnits(), spec.armature, spec.friction)

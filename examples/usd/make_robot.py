"""Build examples/usd/robot.usda: a small arm (two revolute joints, one prismatic) without envelopes.

Centimetre stage (metersPerUnit 0.01) so that `drive-envelope usd apply` has units to convert.
Run: .venv/bin/python examples/usd/make_robot.py
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

Vec3 = tuple[float, float, float]


def body(stage: Any, path: str, mass: float, size: Vec3, at: Vec3) -> None:
    from pxr import Gf, UsdGeom, UsdPhysics

    xform = UsdGeom.Xform.Define(stage, path)
    xform.AddTranslateOp().Set(Gf.Vec3d(*at))
    cube = UsdGeom.Cube.Define(stage, f"{path}/geom")
    cube.CreateSizeAttr(1.0)
    cube.AddScaleOp().Set(Gf.Vec3f(*size))
    UsdPhysics.CollisionAPI.Apply(cube.GetPrim())
    UsdPhysics.RigidBodyAPI.Apply(xform.GetPrim())
    UsdPhysics.MassAPI.Apply(xform.GetPrim()).CreateMassAttr(mass)


def joint(stage: Any, schema: Any, name: str, parent: str, child: str, offset: Vec3) -> Any:
    from pxr import Gf, Sdf, UsdPhysics

    j = schema.Define(stage, f"/Robot/joints/{name}")
    j.CreateBody0Rel().SetTargets([Sdf.Path(parent)])
    j.CreateBody1Rel().SetTargets([Sdf.Path(child)])
    j.CreateLocalPos0Attr(Gf.Vec3f(*offset))
    j.CreateLocalPos1Attr(Gf.Vec3f(0.0, 0.0, 0.0))
    j.CreateAxisAttr("Z" if schema is UsdPhysics.RevoluteJoint else "X")
    return j.GetPrim()


def main() -> None:
    import physx_usd_schemas  # noqa: F401  (registers the PhysX schemas with USD)
    from pxr import Sdf, Usd, UsdGeom, UsdPhysics

    stage = Usd.Stage.CreateNew(str(Path(__file__).with_name("robot.usda")))
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    robot = UsdGeom.Xform.Define(stage, "/Robot")
    stage.SetDefaultPrim(robot.GetPrim())
    UsdPhysics.ArticulationRootAPI.Apply(robot.GetPrim())
    UsdPhysics.Scene.Define(stage, "/physicsScene")
    body(stage, "/Robot/base", 2.0, (10, 10, 4), (0, 0, 2))
    body(stage, "/Robot/upper_arm", 1.0, (30, 4, 4), (15, 0, 6))
    body(stage, "/Robot/forearm", 0.6, (25, 3, 3), (42.5, 0, 6))
    body(stage, "/Robot/slider", 0.2, (6, 2, 2), (58, 0, 6))
    root = UsdPhysics.FixedJoint.Define(stage, "/Robot/joints/root")
    root.CreateBody1Rel().SetTargets([Sdf.Path("/Robot/base")])
    shoulder = joint(
        stage, UsdPhysics.RevoluteJoint, "shoulder", "/Robot/base", "/Robot/upper_arm", (0, 0, 4)
    )
    elbow = joint(stage, UsdPhysics.RevoluteJoint, "elbow", "/Robot/upper_arm", "/Robot/forearm", (15, 0, 0))
    slide = joint(stage, UsdPhysics.PrismaticJoint, "slide", "/Robot/forearm", "/Robot/slider", (15.5, 0, 0))
    # position drives as an importer would write them (angular gains per degree, centimetre units)
    gains = ((shoulder, "angular", 2.0, 0.1), (elbow, "angular", 1.0, 0.05), (slide, "linear", 50.0, 5.0))
    for prim, inst, stiffness, damping in gains:
        drive = UsdPhysics.DriveAPI.Apply(prim, inst)
        drive.CreateTypeAttr("force")
        drive.CreateStiffnessAttr(stiffness)
        drive.CreateDampingAttr(damping)
    stage.GetRootLayer().Save()


if __name__ == "__main__":
    main()

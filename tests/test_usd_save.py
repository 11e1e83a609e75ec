"""The Python API's stage handling: no open edits dropped, every edited layer saved, outputs checked.

Layouts: a robot whose physics lives in a sublayer (as the FR3 conversion's ``Payload/Physics.usda``)
edited with the edit target on that sublayer; a layer another stage of the process (a Kit session)
has open with unsaved edits; an asset in metres and grams written as a layer over it.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from drive_envelope import DriveEnvelopeError, InputError, PerformanceEnvelope

pytestmark = pytest.mark.usd

ENV = PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=20.0)


@pytest.fixture
def asset(tmp_path: Path) -> Path:
    """robot.usda (metres, grams, Y up, 24 time codes/s) sublayering physics/physics.usda (the joint)."""
    import physx_usd_schemas  # noqa: F401
    from pxr import Sdf, Usd, UsdGeom, UsdPhysics

    (tmp_path / "asset" / "physics").mkdir(parents=True)
    physics = Usd.Stage.CreateNew(str(tmp_path / "asset" / "physics" / "physics.usda"))
    UsdPhysics.ArticulationRootAPI.Apply(UsdGeom.Xform.Define(physics, "/Robot").GetPrim())
    for body in ("base", "link"):
        UsdPhysics.RigidBodyAPI.Apply(UsdGeom.Xform.Define(physics, f"/Robot/{body}").GetPrim())
    joint = UsdPhysics.RevoluteJoint.Define(physics, "/Robot/hinge")
    joint.CreateBody0Rel().SetTargets([Sdf.Path("/Robot/base")])
    joint.CreateBody1Rel().SetTargets([Sdf.Path("/Robot/link")])
    physics.Save()
    root = Sdf.Layer.CreateNew(str(tmp_path / "asset" / "robot.usda"))
    root.subLayerPaths.append("./physics/physics.usda")
    root.defaultPrim = "Robot"
    root.pseudoRoot.SetInfo("metersPerUnit", 1.0)
    root.pseudoRoot.SetInfo("kilogramsPerUnit", 0.001)
    root.pseudoRoot.SetInfo("upAxis", "Y")
    root.timeCodesPerSecond = 24.0
    root.Save()
    return tmp_path / "asset" / "robot.usda"


def test_open_stage_keeps_another_stages_unsaved_edits(asset: Path) -> None:
    """Use (and warn about) a layer another stage has edited, never reload it (edits were lost)."""
    from pxr import Usd

    from drive_envelope.usd import UsdStageWarning, open_stage

    session = Usd.Stage.Open(str(asset))  # e.g. the stage open in Isaac Sim
    session.DefinePrim("/Robot/sensor", "Xform")  # an unsaved edit on the root layer
    with pytest.warns(UsdStageWarning, match="already open in this process with unsaved edits"):
        ours = open_stage(asset)
    assert ours.GetPrimAtPath("/Robot/sensor").IsValid()
    assert session.GetPrimAtPath("/Robot/sensor").IsValid() and session.GetRootLayer().dirty


def test_open_stage_refreshes_an_unedited_open_layer(asset: Path) -> None:
    """Re-read a clean open layer whose file changed on disk (nothing unsaved can be lost)."""
    from pxr import Sdf, Usd

    from drive_envelope.usd import open_stage

    first = Usd.Stage.Open(str(asset))
    other = Sdf.Layer.OpenAsAnonymous(str(asset))
    other.comment = "changed on disk"
    other.Export(str(asset))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert open_stage(asset).GetRootLayer().comment == "changed on disk"
    assert first.GetRootLayer().comment == "changed on disk"


def test_save_in_place_saves_the_edited_sublayer(asset: Path) -> None:
    """Save an edit made with the edit target on a sublayer into that sublayer (it was silently lost)."""
    from pxr import Sdf, Usd

    from drive_envelope.usd import open_stage, read_envelope, save_stage, write_envelope

    stage = open_stage(asset)
    physics = Sdf.Layer.Find(str(asset.parent / "physics" / "physics.usda"))
    stage.SetEditTarget(Usd.EditTarget(physics))
    write_envelope(stage, "/Robot/hinge", ENV)
    root_before = asset.read_bytes()
    assert save_stage(stage) == [Path(physics.realPath)]
    assert asset.read_bytes() == root_before  # the root layer had no edit
    assert not physics.dirty  # saved: the layer is clean again
    fresh = Sdf.Layer.OpenAsAnonymous(physics.realPath).ExportToString()
    assert "PhysxDrivePerformanceEnvelopeAPI:angular" in fresh
    assert read_envelope(stage, "/Robot/hinge").max_effort == pytest.approx(12.0)


def test_save_to_output_refuses_to_lose_sublayer_edits(asset: Path, tmp_path: Path) -> None:
    """Refuse to write only the root layer while a sublayer holds the edits; write nothing."""
    from pxr import Sdf, Usd

    from drive_envelope.usd import open_stage, save_stage, write_envelope

    stage = open_stage(asset)
    stage.SetEditTarget(Usd.EditTarget(Sdf.Layer.Find(str(asset.parent / "physics" / "physics.usda"))))
    write_envelope(stage, "/Robot/hinge", ENV)
    out = tmp_path / "copy.usda"
    with pytest.raises(InputError, match=r"copy\.usda: not written: 1 other layer\(s\) .*physics\.usda"):
        save_stage(stage, out)
    assert not out.exists()
    save_stage(stage, tmp_path / "flat.usda", flatten=True)  # flattening keeps every edit
    assert "PhysxDrivePerformanceEnvelopeAPI" in (tmp_path / "flat.usda").read_text(encoding="utf-8")


def test_overlay_repeats_the_stage_metadata(asset: Path, tmp_path: Path) -> None:
    """Keep metres, grams, Y up and the time codes in the layer over the asset (USD reads the root's)."""
    from pxr import Usd, UsdGeom

    from drive_envelope.usd import open_overlay, read_envelope, save_stage, stage_units, write_envelope

    stage = open_overlay(asset)
    assert stage_units(stage).meters_per_unit == 1.0 and stage_units(stage).kilograms_per_unit == 0.001
    write_envelope(stage, "/Robot/hinge", ENV)
    out = tmp_path / "out" / "robot_env.usda"
    out.parent.mkdir()
    assert save_stage(stage, out) == [out]
    written = Usd.Stage.Open(str(out))
    assert UsdGeom.GetStageUpAxis(written) == "Y" and written.GetTimeCodesPerSecond() == 24.0
    assert written.GetDefaultPrim().GetPath() == "/Robot"
    assert stage_units(written).kilograms_per_unit == 0.001
    # 12 N*m in metre-gram units is 12000 g*m^2/s^2: the number USD stores
    attr = written.GetPrimAtPath("/Robot/hinge").GetAttribute("drive:angular:physics:maxForce")
    assert attr.Get() == pytest.approx(12000.0)
    assert read_envelope(written, "/Robot/hinge").max_effort == pytest.approx(12.0)
    assert "@../asset/robot.usda@" in out.read_text(encoding="utf-8")


def test_root_layer_copy_rebases_relative_paths(asset: Path, tmp_path: Path) -> None:
    """Write an edited root layer to another folder with its sublayer path made right for it."""
    from pxr import Usd

    from drive_envelope.usd import list_drives, open_stage, save_stage, write_envelope

    stage = open_stage(asset)
    write_envelope(stage, "/Robot/hinge", ENV)
    out = tmp_path / "elsewhere" / "robot_copy.usda"
    out.parent.mkdir()
    save_stage(stage, out)
    assert "@../asset/physics/physics.usda@" in out.read_text(encoding="utf-8")
    assert len(list_drives(Usd.Stage.Open(str(out)))) == 1


def test_a_result_that_loses_the_robot_is_not_written(
    asset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Check the written file before it replaces anything: verbatim relative paths (the old bug) fail."""
    from pxr import Sdf

    from drive_envelope._src.adapters.usd import save
    from drive_envelope.usd import open_stage, save_stage, write_envelope

    def verbatim(root: Sdf.Layer, target: Path) -> Sdf.Layer:
        copy = Sdf.Layer.CreateAnonymous(target.suffix)
        copy.TransferContent(root)
        return copy

    monkeypatch.setattr(save, "_rebased_root", verbatim)
    stage = open_stage(asset)
    write_envelope(stage, "/Robot/hinge", ENV)
    out = tmp_path / "elsewhere" / "robot_copy.usda"
    out.parent.mkdir()
    with pytest.raises(DriveEnvelopeError, match=r"not written: the result composes to 0 prims instead of 4"):
        save_stage(stage, out)
    assert list(out.parent.iterdir()) == []


def test_output_that_is_one_of_the_stages_layers_is_refused(asset: Path) -> None:
    """Refuse to write the result over the sublayer the stage is made of."""
    from drive_envelope.usd import open_overlay, save_stage, write_envelope

    stage = open_overlay(asset)
    write_envelope(stage, "/Robot/hinge", ENV)
    target = asset.parent / "physics" / "physics.usda"
    before = target.read_bytes()
    with pytest.raises(InputError, match="is one of the layers this stage is made of"):
        save_stage(stage, target)
    assert target.read_bytes() == before


def test_overlay_in_place_needs_an_output(asset: Path) -> None:
    """Say that an in-memory layer needs an output file instead of saving nothing."""
    from drive_envelope.usd import open_overlay, save_stage, write_envelope

    stage = open_overlay(asset)
    write_envelope(stage, "/Robot/hinge", ENV)
    with pytest.raises(InputError, match="give an output file"):
        save_stage(stage)

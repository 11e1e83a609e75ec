"""Opening, saving and describing USD stages, with the PhysX schemas registered.

The one place that turns a file into a ``Usd.Stage`` and back: every command and function of the
USD adapter goes through :func:`open_stage` and :func:`save_stage`.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from drive_envelope._src.adapters.usd.scale import StageUnits
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    from pxr import Usd

__all__ = ["open_stage", "register_schemas", "save_stage", "stage_units"]


def register_schemas() -> None:
    """Make the codeless PhysX schemas known to USD (``import physx_usd_schemas`` registers them).

    Raises:
        InputError: usd-core or physx-usd-schemas is not installed.
    """
    try:
        import physx_usd_schemas  # noqa: F401 - registers the schema plugins on import
        from pxr import Usd  # noqa: F401
    except ImportError as exc:
        raise InputError(
            f"USD support needs the 'usd' extra (pip install 'drive-envelope[usd]'): missing {exc.name!r}"
        ) from None


def open_stage(path: str | os.PathLike[str]) -> Usd.Stage:
    """Open a USD file with the PhysX schemas registered.

    Raises:
        InputError: missing file, or a file USD cannot read.
    """
    file = Path(path)
    if not file.is_file():
        raise InputError(f"{file}: no such file")
    register_schemas()
    from pxr import Sdf, Tf, Usd

    try:
        cached = Sdf.Layer.Find(str(file))
        if cached is not None:
            cached.Reload(force=True)  # the file on disk, not edits an earlier failed run left in memory
        stage = Usd.Stage.Open(str(file))
    except Tf.ErrorException as exc:
        raise InputError(f"{file}: USD cannot open it: {' '.join(str(exc).split())[:300]}") from None
    if stage is None:
        raise InputError(f"{file}: USD cannot open it")
    return stage


def save_stage(stage: Usd.Stage, output: str | os.PathLike[str]) -> None:
    """Write the stage's root layer to ``output`` atomically (a temporary file renamed over it)."""
    from drive_envelope._src.io.atomic import atomic_path

    target = Path(output)
    if target.suffix.lower() not in (".usd", ".usda", ".usdc"):
        raise InputError(f"--output {str(output)!r}: expected a .usd, .usda or .usdc file name")
    with atomic_path(target) as tmp:
        if not stage.GetRootLayer().Export(str(tmp)):
            raise InputError(f"{target}: USD could not write the file")
        if target.exists():
            shutil.copymode(target, tmp)  # the temporary file is 0600; keep the asset's permissions


def stage_units(stage: Usd.Stage) -> StageUnits:
    """The stage's ``metersPerUnit`` and ``kilogramsPerUnit`` (USD fallbacks 0.01 and 1)."""
    from pxr import UsdGeom, UsdPhysics

    return StageUnits(
        meters_per_unit=float(UsdGeom.GetStageMetersPerUnit(stage)),
        kilograms_per_unit=float(UsdPhysics.GetStageKilogramsPerUnit(stage)),
    )

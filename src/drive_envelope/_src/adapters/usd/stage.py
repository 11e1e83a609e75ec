"""Opening USD stages with the PhysX schemas registered, and USD's messages as one clean line.

With :mod:`~drive_envelope._src.adapters.usd.save` the one place that turns files into a
``Usd.Stage`` and back: every command and function of the USD adapter opens through
:func:`open_stage` (the asset itself) or :func:`open_overlay` (a new in-memory layer over it, the
non-destructive way: edits go to the new layer only).

USD reports problems through its own diagnostics (``Tf``), printed straight to stderr with C++
names (``pxrInternal_v0_26_11__pxrReserved__::...``). Here they are collected while a stage opens
and turned into one-line messages: a file USD cannot read is an :class:`InputError`, a sublayer or
reference it cannot load is a :class:`UsdStageWarning`.
"""

from __future__ import annotations

import contextlib
import os
import re
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.usd.newton_actuator import SCHEMA_DIR
from drive_envelope._src.adapters.usd.scale import StageUnits
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.files import read_text
from drive_envelope._src.io.paths import input_file

if TYPE_CHECKING:
    from pxr import Usd

_READABLE = (".usd", ".usda", ".usdc", ".usdz")
# stage metadata a layer over an asset must repeat: USD reads stage metadata from the root layer only
# (a sublayer's metersPerUnit is ignored), so without these a metre asset would compose as centimetres
_NOT_COPIED = {"subLayers", "subLayerOffsets", "documentation", "comment", "customLayerData"}
_INTERNAL = re.compile(r"\bpxrInternal_v\w+?__pxrReserved__::")
_STAGE_SUFFIX = re.compile(r"\s*\(instantiating stage on stage @[^@]*@ <0x[0-9a-f]+>\)")
_MAX_MESSAGE = 300


class UsdStageWarning(UserWarning):
    """A problem USD found while composing an asset (a sublayer or reference it cannot load)."""


def register_schemas(*, strict: bool = True) -> None:
    """Make the codeless PhysX schemas known to USD (``import physx_usd_schemas`` registers them).

    USD builds its schema registry once per process, on first use: if something read schemas
    before ``physx_usd_schemas`` was imported (Newton's ``add_usd``, another library), the envelope
    API stays unknown and every joint would silently read as having no envelope. That is refused.

    Args:
        strict: Refuse a registry built before the PhysX schemas were registered. A reader that
            finds the envelope API in the layers' ``apiSchemas`` (``list_drives``) passes False.

    Raises:
        InputError: usd-core or physx-usd-schemas is not installed, or (``strict``) USD's schema
            registry was built before the PhysX schemas were registered.
    """
    try:
        import physx_usd_schemas  # noqa: F401 - registers the schema plugins on import
        from pxr import Plug, Usd
    except ImportError as exc:
        raise InputError(
            f"USD support needs the 'usd' extra (pip install 'drive-envelope[usd]'): missing {exc.name!r}"
        ) from None
    # our own codeless schema (the Newton-actuator clamping stage) joins before the registry is built
    Plug.Registry().RegisterPlugins([str(SCHEMA_DIR)])
    if strict and Usd.SchemaRegistry().FindAppliedAPIPrimDefinition(_ENVELOPE_API) is None:
        raise InputError(
            f"USD does not know {_ENVELOPE_API}: its schema registry was built before the PhysX schemas "
            "were registered; call drive_envelope.usd.register_schemas() (or import physx_usd_schemas) "
            "before anything opens a USD stage in this process"
        )


_ENVELOPE_API = "PhysxDrivePerformanceEnvelopeAPI"


def clean_usd_message(text: str) -> str:
    """One line of a USD diagnostic: no C++ namespaces, no stage addresses, no line breaks."""
    text = _STAGE_SUFFIX.sub("", _INTERNAL.sub("", str(text)))
    text = " ".join(text.split())
    return text if len(text) <= _MAX_MESSAGE else text[: _MAX_MESSAGE - 3] + "..."


def _error_text(exc: BaseException) -> str:
    """The commentary of every ``Tf.Error`` a ``Tf.ErrorException`` carries, cleaned."""
    parts = [_commentary(error) for error in exc.args] or [_commentary(exc)]
    return clean_usd_message("; ".join(dict.fromkeys(parts)))  # USD often repeats itself


def _commentary(error: object) -> str:
    """One ``Tf.Error``'s text; USD quotes the file's bytes in it, which need not be UTF-8."""
    try:
        return str(getattr(error, "commentary", error)).strip()
    except UnicodeDecodeError:
        return "USD's message quotes bytes that are not UTF-8 text (the file is damaged or not USD)"


@contextlib.contextmanager
def usd_diagnostics() -> Iterator[list[str]]:
    """Collect USD's warnings and status messages instead of letting USD print them.

    Yields a list that holds, after the block, each diagnostic as one clean line.
    """
    from pxr import UsdUtils

    messages: list[str] = []
    delegate = UsdUtils.CoalescingDiagnosticDelegate()  # while it lives USD prints nothing
    try:
        yield messages
    finally:
        messages.extend(clean_usd_message(d.commentary) for d in delegate.TakeUncoalescedDiagnostics())
        del delegate


@contextlib.contextmanager
def usd_errors(where: str) -> Iterator[None]:
    """Turn a ``Tf.ErrorException`` raised in the block into an :class:`InputError` naming ``where``."""
    from pxr import Tf

    try:
        yield
    except Tf.ErrorException as exc:
        raise InputError(f"{where}: {_error_text(exc)}") from None


def _check_readable(file: Path) -> None:
    if file.suffix.lower() != ".usda":  # crate files (.usd, .usdc) and packages: USD maps them
        input_file(file, max_bytes=None)
    else:  # USD's own message on a byte that is not UTF-8 cannot be decoded: say where it is here
        read_text(file)
    if file.suffix.lower() not in _READABLE:
        raise InputError(f"{file}: expected a USD file (.usd, .usda, .usdc or .usdz), got {file.suffix!r}")


def _reuse_open_layer(file: Path) -> None:
    """Leave a layer this process already has open as it is, or refresh it if it is unedited.

    A dirty layer holds edits that another stage of this process (a Kit or Isaac Sim session)
    has not saved: reloading it would throw them away, so it is used as it is, with a warning.
    """
    from pxr import Sdf

    layer = Sdf.Layer.Find(str(file))
    if layer is None:
        return
    if layer.dirty:
        warnings.warn(
            f"{file}: already open in this process with unsaved edits; using the open layer, not the file",
            UsdStageWarning,
            stacklevel=3,
        )
        return
    with usd_errors(str(file)):
        layer.Reload()  # only when the file changed on disk; the layer has nothing unsaved


def _warn_composition(file: Path, messages: list[str], stage: Any) -> None:
    problems = [clean_usd_message(str(error)) for error in _composition_errors(stage)] or messages
    for message in problems[:5]:
        warnings.warn(f"{file}: {message}", UsdStageWarning, stacklevel=3)
    if len(problems) > 5:
        warnings.warn(f"{file}: {len(problems) - 5} more composition problems", UsdStageWarning, stacklevel=3)


def _composition_errors(stage: Any) -> list[Any]:
    errors = getattr(stage, "GetCompositionErrors", None)  # usd-core >= 24.11
    return list(errors()) if errors is not None else []


def open_stage(path: str | os.PathLike[str], *, strict: bool = True) -> Usd.Stage:
    """Open a USD file (payloads loaded) with the PhysX schemas registered.

    A layer of that file that this process already has open is shared (as USD always does); if it
    has unsaved edits they are kept and a :class:`UsdStageWarning` says so; an unedited one is
    refreshed from the file. Sublayers or references USD cannot load are reported as
    :class:`UsdStageWarning` (USD itself skips them).

    Raises:
        InputError: a missing file, a folder, a suffix USD does not read, or a file USD cannot parse.
    """
    file = Path(path)
    _check_readable(file)
    register_schemas(strict=strict)  # strict=False: a reader of authored attributes only
    from pxr import Usd

    _reuse_open_layer(file)
    with usd_diagnostics() as messages, usd_errors(f"{file}: USD cannot open it"):
        stage = Usd.Stage.Open(str(file), load=Usd.Stage.LoadAll)
    if stage is None:
        raise InputError(f"{file}: USD cannot open it")
    _warn_composition(file, messages, stage)
    return stage


def open_overlay(path: str | os.PathLike[str]) -> Usd.Stage:
    """A stage whose root is a new in-memory layer over the asset at ``path``: edits go there only.

    The new layer sublayers the asset (by absolute path until it is saved:
    :func:`~drive_envelope._src.adapters.usd.save.save_stage` writes it relative to the output's
    folder) and repeats the asset's stage metadata (``metersPerUnit``, ``kilogramsPerUnit``,
    ``upAxis``, ``defaultPrim``, time codes), which USD reads from the root layer only. The asset's
    own layers are never edited.

    Raises:
        InputError: as :func:`open_stage`.
    """
    source = open_stage(path)  # validates, reports composition problems once, loads the asset's layers
    from pxr import Sdf, Usd

    base = source.GetRootLayer()
    overlay = Sdf.Layer.CreateAnonymous(".usda")
    for key in base.pseudoRoot.ListInfoKeys():
        if key not in _NOT_COPIED:
            overlay.pseudoRoot.SetInfo(key, base.pseudoRoot.GetInfo(key))
    overlay.documentation = f"drive-envelope: PhysX drive envelopes over {Path(path).name}"
    overlay.subLayerPaths.append(base.realPath or base.identifier)
    with usd_diagnostics(), usd_errors(f"{path}: USD cannot open it"):
        stage = Usd.Stage.Open(overlay, load=Usd.Stage.LoadAll)
    stage.SetEditTarget(Usd.EditTarget(overlay))
    return stage


def stage_units(stage: Usd.Stage) -> StageUnits:
    """The stage's ``metersPerUnit`` and ``kilogramsPerUnit`` (USD fallbacks 0.01 and 1).

    Raises:
        InputError: ``stage`` is not a valid ``Usd.Stage``, or a unit that is not a finite number > 0.
    """
    from pxr import Usd, UsdGeom, UsdPhysics

    if not isinstance(stage, Usd.Stage):  # None or a path: USD's multi-line Tf.ErrorException
        raise InputError(
            f"argument 'stage': expected a Usd.Stage (drive_envelope.usd.open_stage(path)), "
            f"got {type(stage).__name__} {stage!r}"
        )
    meters, kilograms = UsdGeom.GetStageMetersPerUnit(stage), UsdPhysics.GetStageKilogramsPerUnit(stage)
    try:
        return StageUnits(meters_per_unit=float(meters), kilograms_per_unit=float(kilograms))
    except ValueError as exc:
        raise InputError(f"{stage.GetRootLayer().identifier}: stage metadata: {exc}") from None

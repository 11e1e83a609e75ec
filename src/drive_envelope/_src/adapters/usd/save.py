"""Writing USD stages: atomically, every edited layer, nothing lost, checked before it replaces a file.

Three ways to write a stage (:func:`save_stage`):

* in place (no output): every layer of the stage that has unsaved edits is written back to its
  own file: the root layer and any sublayer the edit target pointed at;
* to an output file: the root layer, with its relative asset paths (sublayers, references,
  payloads, asset attributes) rewritten for the output's folder, so the written file still finds
  the robot; a layer from :func:`~drive_envelope._src.adapters.usd.stage.open_overlay` becomes a
  small file that sublayers the asset by a relative path and holds only the new opinions;
* flattened: the whole composed stage as one self-contained file.

Every file goes to a temporary file beside its target first
(:func:`~drive_envelope._src.io.atomic.atomic_path`: symlinks written through, read-only targets
refused unless ``force``, no temporary file left on errors or signals). The temporary file is read
back: it must parse to the same layer, and a new output must compose to the same prims and the
same joint drives as the stage in memory, before it replaces the target. Otherwise nothing is
replaced.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.usd.stage import usd_diagnostics, usd_errors
from drive_envelope._src.errors import DriveEnvelopeError, InputError

if TYPE_CHECKING:
    from pxr import Sdf, Usd

WRITABLE_SUFFIXES = (".usd", ".usda", ".usdc")
"""File names USD writes (a ``.usdz`` package is read-only to USD)."""
_SHOWN = 3


def check_output_name(output: str | os.PathLike[str], flag: str = "output") -> Path:
    """``output`` as a path, refused early when USD cannot write a file of that name.

    Raises:
        InputError: an empty name, a folder, or a suffix other than ``.usd``, ``.usda``, ``.usdc``.
    """
    name = os.fspath(output)
    if not name.strip():
        raise InputError(f"{flag} '': expected a .usd, .usda or .usdc file name")
    path = Path(name)
    if path.is_dir():
        raise InputError(f"{flag} {name!r}: is a folder; expected a .usd, .usda or .usdc file name")
    if path.suffix.lower() not in WRITABLE_SUFFIXES:
        hint = " (USD cannot write .usdz packages)" if path.suffix.lower() == ".usdz" else ""
        raise InputError(f"{flag} {name!r}: expected a .usd, .usda or .usdc file name{hint}")
    return path


def _file_of(layer: Sdf.Layer) -> str:
    return str(layer.realPath or layer.identifier)


def _edited_layers(stage: Usd.Stage) -> list[Sdf.Layer]:
    """Layers with unsaved edits, the session layers excluded (USD never saves those)."""
    session = {layer.identifier for layer in stage.GetLayerStack(includeSessionLayers=True)} - {
        layer.identifier for layer in stage.GetLayerStack(includeSessionLayers=False)
    }
    return [layer for layer in stage.GetUsedLayers() if layer.dirty and layer.identifier not in session]


def save_stage(
    stage: Usd.Stage,
    output: str | os.PathLike[str] | None = None,
    *,
    flatten: bool = False,
    force: bool = False,
) -> list[Path]:
    """Write a stage so that no edit is lost (see the module docstring for the three ways).

    Args:
        stage: The stage.
        output: None to save every edited layer in place; else the file to write (``.usd``,
            ``.usda`` or ``.usdc``).
        flatten: Write the whole composed stage to ``output`` as one self-contained file.
        force: Replace read-only target files.

    Returns:
        The files written.

    Raises:
        InputError: an output USD cannot write, a read-only target (without ``force``), an output
            that is one of the stage's own layers, edits on sublayers that writing only the root
            layer would lose, a ``.usdz`` package to edit in place, or a failed write.
        DriveEnvelopeError: the written file would not compose back to the same prims and drives.
    """
    if output is None:
        if flatten:
            raise InputError("save_stage: flatten=True needs an output file")
        return _save_in_place(stage, force)
    target = check_output_name(output)
    own = {_real(_file_of(layer)): layer for layer in stage.GetUsedLayers() if not layer.anonymous}
    hit = own.get(_real(target))
    if hit is not None and not flatten and hit == stage.GetRootLayer():
        return _save_in_place(stage, force)  # the root layer's own file: the same as saving in place
    if hit is not None:
        raise InputError(f"{target}: is one of the layers this stage is made of; write to another file")
    if flatten:
        with usd_diagnostics(), usd_errors(f"{target}: USD cannot flatten the stage"):
            layer = stage.Flatten()
        if stage.GetRootLayer().anonymous:  # USD's note would name an in-memory layer
            layer.documentation = f"{stage.GetRootLayer().documentation} (flattened)"
    else:
        _refuse_lost_edits(stage, target)
        layer = _rebased_root(stage.GetRootLayer(), target)
    _write(layer, target, force, stage)
    return [target]


def _real(path: str | Path) -> str:
    return os.path.realpath(os.path.abspath(path))


def _refuse_lost_edits(stage: Usd.Stage, target: Path) -> None:
    lost = [layer for layer in _edited_layers(stage) if layer != stage.GetRootLayer()]
    if lost:
        names = ", ".join(_file_of(layer) for layer in lost[:_SHOWN])
        raise InputError(
            f"{target}: not written: {len(lost)} other layer(s) of the stage have unsaved edits that "
            f"writing the root layer would lose ({names}); save them in place (no output) or flatten"
        )


def _save_in_place(stage: Usd.Stage, force: bool) -> list[Path]:
    layers = _edited_layers(stage)
    for layer in layers:
        if layer.anonymous:
            raise InputError(
                "save_stage: the stage's edits are in an in-memory layer (a layer over the asset); "
                "give an output file to write it to"
            )
        if layer.GetFileFormat().IsPackage():
            raise InputError(
                f"{_file_of(layer)}: USD cannot write into a .usdz package; write the edits to a new "
                "layer over it instead (an output file)"
            )
    written = []
    with contextlib.ExitStack() as renames:  # every temporary file is ready before any file is replaced
        for layer in layers:
            target = Path(_file_of(layer))
            tmp = renames.enter_context(_atomic(target, force))
            _export(layer, tmp, target)
            written.append(target)
    for layer in layers:  # the files now hold exactly the layers' content: reloading loses nothing
        with usd_diagnostics(), usd_errors(f"{_file_of(layer)}: USD cannot reload it"):
            layer.Reload(force=True)
    return written


def _atomic(target: Path, force: bool) -> Any:
    from drive_envelope._src.io.atomic import atomic_path

    return atomic_path(target, force=force)


def _export(layer: Sdf.Layer, tmp: Path, shown: Path) -> None:
    """Export ``layer`` to ``tmp`` and check the file parses back to the same layer."""
    from pxr import Sdf

    try:
        with usd_diagnostics() as messages, usd_errors(f"{shown}: USD could not write it"):
            ok = layer.Export(str(tmp))
    except InputError as exc:
        raise _write_failure(shown, tmp, str(exc)) from None
    if not ok:
        raise _write_failure(shown, tmp, f"{shown}: USD could not write it: {'; '.join(messages)}")
    with usd_diagnostics(), usd_errors(f"{shown}: the written file does not read back"):
        back = Sdf.Layer.OpenAsAnonymous(str(tmp))
    if back is None or back.ExportToString() != layer.ExportToString():
        raise DriveEnvelopeError(
            f"{shown}: not written: the file USD wrote does not read back to the same layer"
        )


def _write_failure(shown: Path, tmp: Path, message: str) -> InputError:
    if "No space left" in message:
        return InputError(f"{shown}: cannot write: no space left on the device")
    return InputError(message.replace(str(tmp), str(shown)).rstrip(": "))


def _write(layer: Sdf.Layer, target: Path, force: bool, stage: Usd.Stage) -> None:
    with _atomic(target, force) as tmp:
        _export(layer, tmp, target)
        _check_composes(tmp, target, stage)


def _prim_paths(stage: Usd.Stage) -> list[str]:
    from pxr import Usd

    return [str(prim.GetPath()) for prim in stage.Traverse(Usd.TraverseInstanceProxies())]


def _check_composes(tmp: Path, target: Path, stage: Usd.Stage) -> None:
    """Open the written file as a stage: the same prims and drives as ``stage``, or nothing is written."""
    from pxr import Usd

    from drive_envelope._src.adapters.usd.authoring import list_drives

    with usd_diagnostics(), usd_errors(f"{target}: not written: USD cannot open the result"):
        written = Usd.Stage.Open(str(tmp), load=Usd.Stage.LoadAll)
    expected, got = _prim_paths(stage), _prim_paths(written)
    if got != expected:
        missing = [path for path in expected if path not in set(got)]
        raise DriveEnvelopeError(
            f"{target}: not written: the result composes to {len(got)} prims instead of {len(expected)} "
            f"(missing: {', '.join(missing[:_SHOWN]) or 'none'}); a sublayer or reference did not resolve"
        )
    before, after = list_drives(stage), list_drives(written)
    if before != after:
        changed = [a.joint_path for a, b in zip(before, after, strict=False) if a != b] or ["(count)"]
        raise DriveEnvelopeError(
            f"{target}: not written: the result reads different joint drives ({', '.join(changed[:_SHOWN])})"
        )


def _rebased_root(root: Sdf.Layer, target: Path) -> Sdf.Layer:
    """A copy of ``root`` whose relative asset paths are right for a file written at ``target``."""
    from pxr import Sdf, UsdUtils

    copy = Sdf.Layer.CreateAnonymous(target.suffix)
    copy.TransferContent(root)
    # absolute paths where no folder anchors the file: a symlinked output lives in another folder than
    # the name the user opens it by, and a device or FIFO gets a stream (built, and checked, in the
    # system's temporary folder, then read wherever its reader puts it)
    streamed = target.exists() and not target.is_file()
    folder = None if target.is_symlink() or streamed else Path(os.path.abspath(target)).parent
    sublayers = set(root.subLayerPaths)

    def rebase(path: str) -> str:
        if not path or "://" in path or "[" in path:
            return path  # internal, a URL, or a path inside a package: as written
        if os.path.isabs(path):
            # an in-memory layer (open_overlay) can only hold absolute paths; the file gets relative ones
            return _relative(path, folder) if root.anonymous and path in sublayers else path
        if root.anonymous:
            return path
        absolute = root.ComputeAbsolutePath(path)
        return _relative(absolute, folder) if os.path.exists(absolute) else path  # else a search path

    UsdUtils.ModifyAssetPaths(copy, rebase)
    return copy


def _relative(path: str, folder: Path | None) -> str:
    if folder is None:
        return path
    try:
        common = Path(os.path.commonpath([path, folder]))
        if common.parent == common:
            return path  # nothing in common but the root: a relative path would only break on a move
        relative = os.path.relpath(path, folder)
    except ValueError:  # another drive (Windows)
        return path
    relative = relative.replace(os.sep, "/")
    return relative if relative.startswith("..") else f"./{relative}"

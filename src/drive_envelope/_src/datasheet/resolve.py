"""The one resolver: an envelope, an envelope file, a datasheet file or a catalog name -> an envelope.

Every command and function that accepts "an envelope" in any of these forms calls
:func:`resolve_envelope` (check, fit, plot, simulate's ``envelope.datasheet``, ``usd apply``,
``drive_envelope.mujoco.add_drive``, joint maps), so each form means the same thing everywhere.
"""

from __future__ import annotations

import os
from pathlib import Path

from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import check_path_name

EnvelopeLike = PerformanceEnvelope | str | os.PathLike[str]
"""A :class:`PerformanceEnvelope`, or the name of an envelope file, a datasheet file or a catalog actuator."""

_FILE_SUFFIXES = (".toml", ".json", ".yaml", ".yml")


def resolve_envelope(
    spec: EnvelopeLike,
    *,
    base: str | os.PathLike[str] | None = None,
    duty: str = "peak",
    where: str = "",
) -> PerformanceEnvelope:
    """Return the envelope named by ``spec``.

    Args:
        spec: An envelope (returned as is); an envelope file (TOML/JSON/YAML); a datasheet file (one
            with any of the sections motor, gear, controller, losses, output, screw); or the key or
            name of a catalog actuator (``drive-envelope catalog`` lists them).
        base: Folder a relative file name is looked up in first (the folder of the file that
            names it: a map, a scenario); then the current folder.
        duty: ``"peak"`` (motor ``max_torque``) or ``"continuous"`` (``continuous_torque``); used
            only when ``spec`` is a datasheet or a catalog name.
        where: Prefix of every error message (the file and key that named ``spec``), if any.

    Raises:
        InputError: the file or name cannot be read, or the datasheet gives no envelope.
    """
    return resolve_with_warnings(spec, base=base, duty=duty, where=where)[0]


def resolve_with_warnings(
    spec: EnvelopeLike,
    *,
    base: str | os.PathLike[str] | None = None,
    duty: str = "peak",
    where: str = "",
) -> tuple[PerformanceEnvelope, tuple[str, ...]]:
    """:func:`resolve_envelope`, with the warnings ``derive`` prints when ``spec`` is a datasheet.

    Returns:
        The envelope and the derivation's unit-slip warnings (one line each; none for an envelope
        or an envelope file, which are not derived).

    Raises:
        InputError: as :func:`resolve_envelope`.
    """
    if isinstance(spec, PerformanceEnvelope):
        return spec, ()
    try:
        return _resolve(spec, base, duty)
    except InputError as exc:
        if not where:
            raise
        raise InputError(f"{where}: {exc}") from None


def _resolve(
    spec: object, base: str | os.PathLike[str] | None, duty: str
) -> tuple[PerformanceEnvelope, tuple[str, ...]]:
    from drive_envelope._src.datasheet.catalog import load_catalog_datasheet
    from drive_envelope._src.datasheet.derive import derive
    from drive_envelope._src.datasheet.load import datasheet_from_mapping, is_datasheet_mapping
    from drive_envelope._src.envelope.model import envelope_from_mapping
    from drive_envelope._src.io.files import read_mapping

    if not isinstance(spec, (str, os.PathLike)) or not os.fspath(spec).strip():
        raise InputError(
            f"expected an envelope, an envelope or datasheet file, or a catalog name, got {spec!r}"
        )
    if duty not in ("peak", "continuous"):
        raise InputError(f"duty: expected 'peak' or 'continuous', got {duty!r}")
    check_path_name(os.fspath(spec))
    path = _find_file(os.fspath(spec), base)
    if path is not None:
        data = read_mapping(path)
        if not is_datasheet_mapping(data):
            return envelope_from_mapping(data, source=str(path)), ()
        sheet = datasheet_from_mapping(data, source=str(path))
    else:
        refuse_missing_file(os.fspath(spec))
        sheet = load_catalog_datasheet(os.fspath(spec))
    derivation = derive(sheet, duty="peak" if duty == "peak" else "continuous")
    return derivation.envelope, derivation.warnings


def refuse_missing_file(spec: str) -> None:
    """Refuse a missing ``spec`` that names a file (a file's suffix, a folder), not a catalog actuator.

    Raises:
        InputError: ``spec``: no such file (or its name is too long).
    """
    if Path(spec).suffix.lower() in _FILE_SUFFIXES or "/" in spec:
        check_path_name(spec)
        raise InputError(f"{spec}: no such file")


def _find_file(spec: str, base: str | os.PathLike[str] | None) -> Path | None:
    """The file ``spec`` names: relative to ``base`` first, then as given; None if neither exists."""
    candidates = [Path(spec)]
    if base is not None and not Path(spec).is_absolute():
        candidates.insert(0, Path(base) / spec)
    # exists(), not is_file(): a FIFO or a device is found here and refused by type when it is read
    return next((path for path in candidates if os.path.exists(path)), None)

"""One entry point for commands that need an envelope: an envelope file, a datasheet or a catalog name."""

from __future__ import annotations

from pathlib import Path

from drive_envelope._src.envelope.model import PerformanceEnvelope

__all__ = ["resolve_envelope"]


def resolve_envelope(spec: str, *, duty: str = "peak") -> PerformanceEnvelope:
    """Return the envelope named by ``spec``.

    Args:
        spec: An envelope file (TOML/JSON), a datasheet file (one with any of the sections motor,
            gear, controller, losses, output, screw) or the name of a catalog actuator
            (``drive-envelope catalog`` lists them).
        duty: ``"peak"`` (motor ``max_torque``) or ``"continuous"`` (``continuous_torque``); used
            only when ``spec`` is a datasheet or a catalog name.

    Raises:
        InputError: the file or name cannot be read, or the datasheet gives no envelope.
    """
    from drive_envelope._src.datasheet.catalog import load_catalog_datasheet
    from drive_envelope._src.datasheet.derive import derive
    from drive_envelope._src.datasheet.load import datasheet_from_mapping, is_datasheet_mapping
    from drive_envelope._src.envelope.model import envelope_from_mapping
    from drive_envelope._src.errors import InputError
    from drive_envelope._src.io.files import read_mapping

    if duty != "peak" and duty != "continuous":
        raise InputError(f"duty: expected 'peak' or 'continuous', got {duty!r}")
    if Path(spec).is_file():
        data = read_mapping(spec)
        if not is_datasheet_mapping(data):
            return envelope_from_mapping(data, source=str(spec))
        sheet = datasheet_from_mapping(data, source=str(spec))
    elif Path(spec).suffix.lower() in (".toml", ".json", ".yaml", ".yml") or "/" in spec:
        raise InputError(f"{spec}: no such file")
    else:
        sheet = load_catalog_datasheet(spec)
    return derive(sheet, duty="peak" if duty == "peak" else "continuous").envelope

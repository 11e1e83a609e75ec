"""The envelope a ``plot`` command argument names: envelope/datasheet file, catalog name or scenario."""

from __future__ import annotations

from pathlib import Path

from drive_envelope._src.datasheet.resolve import resolve_with_warnings
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError


def _is_scenario(path: Path) -> bool:
    """A readable mapping file with a ``joint`` table is a test-stand scenario."""
    from drive_envelope._src.io.files import read_mapping

    if not path.is_file():
        return False
    try:
        return isinstance(read_mapping(path).get("joint"), dict)
    except InputError:
        return False  # let the envelope reader report the problem


def envelope_from_argument(spec: str) -> tuple[PerformanceEnvelope, tuple[str, ...]]:
    """Resolve ``spec`` to an envelope, with the warnings ``derive`` gives a datasheet.

    Args:
        spec: An envelope file, a datasheet file, a catalog actuator name, or a scenario file (its
            envelope, or the plain ``+-max_effort`` envelope of a drive without one).

    Returns:
        The envelope and derive's unit-slip warnings (none unless ``spec`` is a datasheet).

    Raises:
        InputError: the file or name cannot be read, or a scenario has no finite ``max_effort``.
    """
    path = Path(spec)
    if _is_scenario(path):
        from drive_envelope._src.scenario.spec import load_scenario

        envelope = load_scenario(path).effective_envelope()
        if envelope is None:
            raise InputError(
                f"{spec}: the scenario's drive has no max_effort, so there is no envelope to plot"
            )
        return envelope, ()
    return resolve_with_warnings(spec)

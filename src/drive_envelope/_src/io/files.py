"""Reading TOML/JSON/YAML input files into mappings, with one-line errors naming the file."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from drive_envelope._src.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["format_toml_value", "read_mapping", "read_text"]


def read_text(path: str | os.PathLike[str]) -> str:
    """Read a UTF-8 text file; a missing or unreadable file is a one-line :class:`InputError`."""
    file = Path(path)
    try:
        return file.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{file}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{file}: cannot read: {exc}") from None


def read_mapping(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML (``.toml``), JSON (``.json``) or YAML (``.yaml``/``.yml``) file into a dict.

    Raises:
        InputError: the file is missing, unreadable, malformed, or not a table at the top level.
    """
    file = Path(path)
    text = read_text(file)
    suffix = file.suffix.lower()
    try:
        if suffix == ".json":
            data = json.loads(text)
        elif suffix in (".yaml", ".yml"):
            try:
                import yaml
            except ImportError:
                raise InputError(
                    f"{file}: YAML needs the 'yaml' extra (pip install 'drive-envelope[yaml]')"
                ) from None
            data = yaml.safe_load(text)
        else:
            data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{file}: malformed TOML: {exc}") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{file}: malformed JSON: {exc}") from None
    except InputError:
        raise
    except Exception as exc:  # yaml.YAMLError and friends
        raise InputError(f"{file}: malformed file: {' '.join(str(exc).split())}") from None
    if not isinstance(data, dict):
        raise InputError(f"{file}: expected a table of keys at the top level, got {type(data).__name__}")
    return data


def format_toml_value(value: object) -> str:
    """Format a scalar as a TOML value (floats round-trip exactly; inf as ``inf``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if value != value:
            raise ValueError("NaN cannot be written")
        if value in (float("inf"), float("-inf")):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    raise TypeError(f"cannot write {type(value).__name__} as a TOML scalar")

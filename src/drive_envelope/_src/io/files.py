"""Reading TOML/JSON/YAML input files into mappings, with one-line errors naming the file.

The three formats are read so that a file means what its author wrote, whatever the format:

* a key written twice is an error naming the key (JSON and YAML would silently keep the last one;
  TOML already refuses it);
* a number beyond the float range (``1e400``, a 400-digit integer) is an error naming the key,
  never a silent ``inf``; ``inf`` itself is written as a word (``inf``, ``.inf`` in YAML);
* YAML is read with the YAML 1.2 core schema: ``6:1`` and ``1:50`` stay strings (YAML 1.1 reads
  them as base-60 integers, 361 and 110), ``010`` is ten (not octal eight), ``yes``/``on`` and
  dates stay strings, and ``1e3`` is a number.
"""

from __future__ import annotations

import functools
import json
import os
import re
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import read_input_bytes
from drive_envelope._src.io.toml_names import named_duplicate

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

_FLOAT_MAX = sys.float_info.max
_INF_WORDS = re.compile(r"^[-+]?(?:inf|infinity|\.inf|nan|\.nan)$", re.IGNORECASE)


class _OutOfRange(str):
    """A number literal beyond the float range, kept as written until the key that holds it is known."""


class _DuplicateKey(Exception):
    """A mapping key written twice (JSON and YAML readers raise it; the caller names the file)."""

    def __init__(self, key: object, line: int | None = None) -> None:
        super().__init__(key)
        self.key = key
        self.line = line


_MAPPING_SUFFIXES = (".toml", ".json", ".yaml", ".yml")


def read_text(path: str | os.PathLike[str], *, what: str = "file") -> str:
    """Read a UTF-8 text file of at most :data:`~.paths.MAX_TEXT_BYTES` [bytes].

    Raises:
        InputError: one line naming the file: missing, a folder, not a regular file (a FIFO, a
            device such as ``/dev/zero``), too large, a name too long, or not UTF-8.
    """
    data = read_input_bytes(path, what=what)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise InputError(
            f"{Path(path)}: cannot read: byte 0x{data[exc.start]:02x} on line {line} is not UTF-8 text"
        ) from None


def read_mapping(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML (``.toml``), JSON (``.json``) or YAML (``.yaml``/``.yml``) file into a dict.

    Raises:
        InputError: the suffix is none of those (a ``.txt`` is not read as TOML by guess), the file
            is missing, unreadable or malformed, a key is written twice, a number is beyond the float
            range, or the top level is not a table.
    """
    file = Path(path)
    suffix = file.suffix.lower()
    if suffix not in _MAPPING_SUFFIXES:
        raise InputError(
            f"{file}: expected a .toml, .json, .yaml or .yml file (the suffix tells how to read it), "
            f"got {repr(suffix) if suffix else 'a name without one'}"
        )
    text = read_text(file)
    try:
        if suffix == ".json":
            data = json.loads(text, parse_float=_parse_float, object_pairs_hook=_json_object)
        elif suffix in (".yaml", ".yml"):
            data = _load_yaml(text, file)
        else:
            data = tomllib.loads(text, parse_float=_parse_float)
    except _DuplicateKey as exc:
        where = f" (line {exc.line})" if exc.line is not None else ""
        raise InputError(f"{file}: duplicate key {exc.key!r}{where}: each key may be written once") from None
    except tomllib.TOMLDecodeError as exc:
        named = named_duplicate(Path(file), text, str(exc))
        raise InputError(named or f"{file}: malformed TOML: {exc}") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{file}: malformed JSON: {exc}") from None
    except InputError:
        raise
    except Exception as exc:  # yaml.YAMLError and friends
        raise InputError(f"{file}: malformed file: {' '.join(str(exc).split())}") from None
    if not isinstance(data, dict):
        raise InputError(f"{file}: expected a table of keys at the top level, got {type(data).__name__}")
    _check_numbers(data, file, "")
    return data


def _parse_float(text: str) -> float:
    """``float(text)``, except that a finite literal that overflows is kept (and refused later)."""
    value = float(text)
    if value in (float("inf"), float("-inf")) and not _INF_WORDS.match(text.strip()):
        return _OutOfRange(text)  # type: ignore[return-value]  # refused by _check_numbers
    return value


def _json_object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    result: dict[str, Any] = {}
    for key, value in pairs:
        if key in result:
            raise _DuplicateKey(key)
        result[key] = value
    return result


def _check_numbers(value: object, file: Path, where: str) -> None:
    """Refuse numbers beyond the float range anywhere in the data, naming the dotted key."""
    if isinstance(value, _OutOfRange) or (
        isinstance(value, int) and not isinstance(value, bool) and abs(value) > _FLOAT_MAX
    ):
        shown = str(value) if len(str(value)) <= 24 else f"{str(value)[:12]}...({len(str(value))} digits)"
        raise InputError(
            f"{file}: key {where or '(top level)'!r}: {shown} is beyond the float range "
            f"(about 1.8e308); write a smaller number, or inf for no limit"
        )
    if isinstance(value, Mapping):
        for key, item in value.items():
            _check_numbers(item, file, f"{where}.{key}" if where else str(key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            _check_numbers(item, file, f"{where}[{index}]")


def _load_yaml(text: str, file: Path) -> Any:
    try:
        import yaml
    except ImportError:
        raise InputError(
            f"{file}: YAML needs the 'yaml' extra (pip install 'drive-envelope[yaml]')"
        ) from None
    return yaml.load(text, Loader=_yaml_loader())  # a SafeLoader subclass: no arbitrary objects


@functools.lru_cache(maxsize=1)
def _yaml_loader() -> type:
    """A ``yaml.SafeLoader`` with the YAML 1.2 core schema's scalars and duplicate-key checks."""
    import yaml

    class Loader(yaml.SafeLoader):
        # its own resolver table (the class attribute of SafeLoader is shared and must stay YAML 1.1)
        yaml_implicit_resolvers: ClassVar[dict[str, list[tuple[str, re.Pattern[str]]]]] = {}

        def construct_mapping(self, node: Any, deep: bool = False) -> Any:
            seen: set[object] = set()
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=deep)
                if key in seen:
                    raise _DuplicateKey(key, key_node.start_mark.line + 1)
                seen.add(key)
            return super().construct_mapping(node, deep=deep)

    def int_10(loader: Any, node: Any) -> int:
        return int(loader.construct_scalar(node), 10)  # "010" is ten, as written

    def float_checked(loader: Any, node: Any) -> float:
        text = loader.construct_scalar(node)
        lowered = text.lower().lstrip("+-")
        if lowered == ".inf":
            return float("-inf") if text.startswith("-") else float("inf")
        if lowered == ".nan":
            return float("nan")
        return _parse_float(text)

    core = {
        "tag:yaml.org,2002:bool": (r"^(?:true|True|TRUE|false|False|FALSE)$", list("tTfF")),
        "tag:yaml.org,2002:int": (r"^[-+]?[0-9]+$", list("-+0123456789")),
        "tag:yaml.org,2002:float": (
            r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
            r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$",
            list("-+.0123456789"),
        ),
        "tag:yaml.org,2002:null": (r"^(?:~|null|Null|NULL|)$", [*"~nN", ""]),
        "tag:yaml.org,2002:merge": (r"^(?:<<)$", ["<"]),
    }
    for tag, (pattern, first) in core.items():
        Loader.add_implicit_resolver(tag, re.compile(pattern), first)
    Loader.add_constructor("tag:yaml.org,2002:int", int_10)
    Loader.add_constructor("tag:yaml.org,2002:float", float_checked)
    return Loader


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

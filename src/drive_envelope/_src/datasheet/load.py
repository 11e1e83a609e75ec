"""Reading datasheet files (TOML, JSON or YAML) into a :class:`Datasheet`, with strict validation.

Every quantity is a bare number in the SI unit of its key (quoted or not) or a string with units as
datasheets print them (``"91 mNm/A"``, ``"3000 min^-1"``). Every mistake raises ``InputError`` with
one line naming the file, the key, the value and what was expected; a value of the wrong dimension
also names the key that takes that dimension (``'100 rpm/V' ... did you mean motor.speed_constant?``).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from drive_envelope._src.datasheet.marks import bare_numbers, current_conventions
from drive_envelope._src.datasheet.pairs import check_pairs
from drive_envelope._src.datasheet.spec import (
    GRADIENT_METHODS,
    ControllerSpec,
    Datasheet,
    GearboxSpec,
    LossesSpec,
    MotorDatasheet,
    OutputRating,
    ParamSource,
    ScrewSpec,
)
from drive_envelope._src.errors import InputError, UnitsError
from drive_envelope._src.io.files import read_mapping
from drive_envelope._src.units import converts_to, describe_unit, to_si
from drive_envelope._src.validation import check_keys, nearest_key

SECTION_CLASSES: dict[str, type] = {
    "motor": MotorDatasheet,
    "gear": GearboxSpec,
    "controller": ControllerSpec,
    "losses": LossesSpec,
    "output": OutputRating,
    "screw": ScrewSpec,
}
"""Each datasheet section and the class it is read into, in file order."""
DATASHEET_SECTIONS = tuple(SECTION_CLASSES)
_TOP_KEYS = ("name", "joint", "description", "sources", *DATASHEET_SECTIONS)

# SI unit of each kind of quantity, for rotary motor data, linear motor data and the joint side.
_ROTARY = {
    "torque": "N*m",
    "speed": "rad/s",
    "torque_constant": "N*m/A",
    "speed_constant": "rad/s/V",
    "back_emf_constant": "V*s/rad",
    "gradient": "rad/s/(N*m)",
    "resistance_joint": "N*m*s/rad",
}
_LINEAR = {
    "torque": "N",
    "speed": "m/s",
    "torque_constant": "N/A",
    "speed_constant": "m/s/V",
    "back_emf_constant": "V*s/m",
    "gradient": "m/s/N",
    "resistance_joint": "N*s/m",
}
_FIXED = {"current": "A", "voltage": "V", "ohm": "ohm", "fraction": "dimensionless", "ratio": "dimensionless"}

# section -> key -> (kind, rule, side), derived from the rules on the section classes' fields (see
# spec._rule): one table, so a field and its file key cannot drift apart. rule: ">0", ">=0" or "(0,1]".
# side: "motor" (motor units, linear for a linear motor) or "joint" (joint units).
_Rule = tuple[str, str, str]


def _file_keys(section_class: type) -> dict[str, _Rule]:
    """The file keys of one section class: each field with a rule, under its own name."""
    return {
        item.name: (item.metadata["kind"], item.metadata["bound"], item.metadata["side"])
        for item in fields(section_class)
        if "kind" in item.metadata
    }


SECTION_KEYS: dict[str, dict[str, _Rule]] = {
    section: _file_keys(section_class) for section, section_class in SECTION_CLASSES.items()
}
_REQUIRED = {"gear": "ratio", "screw": "lead"}
KEY_ALIASES: dict[str, dict[str, str]] = {
    "output": {
        "stall_torque": "stall_effort",
        "stall_force": "stall_effort",
        "no_load_speed": "no_load_velocity",
    },
}
"""Other names vendors use for a key: section -> alias -> key. Each means exactly the key."""
_ALIAS_JOINT = {"stall_torque": "revolute", "stall_force": "prismatic"}


def load_datasheet(
    path: str | os.PathLike[str], *, overrides: Mapping[str, object] | None = None, source: str | None = None
) -> Datasheet:
    """Read and validate a datasheet file.

    Args:
        path: TOML (``.toml``), JSON (``.json``) or YAML (``.yaml``/``.yml``) file.
        overrides: ``"section.key"`` (or ``"name"``/``"joint"``) -> value, applied on top of the
            file and recorded with provenance ``"user"``; same rules as values in the file.
        source: Label for error messages instead of the path (catalog entries use their name).

    Raises:
        InputError: malformed file, unknown key or section (with the nearest valid one), missing
            ``name``, a value of the wrong unit or out of range, or contradicting keys.
    """
    return datasheet_from_mapping(read_mapping(path), source=source or str(path), overrides=overrides)


def is_datasheet_mapping(data: Mapping[str, object]) -> bool:
    """Whether a file's mapping is a datasheet (it has any datasheet section) rather than an envelope."""
    return any(section in data for section in DATASHEET_SECTIONS)


def datasheet_from_mapping(
    data: Mapping[str, Any], *, source: str, overrides: Mapping[str, object] | None = None
) -> Datasheet:
    """Validate a datasheet mapping (see :func:`load_datasheet`) and convert it to SI."""
    merged, provenance = _apply_overrides(data, overrides or {}, source)
    _check_top_level(merged, source)
    overridden = frozenset(overrides or {})
    name = merged.get("name")
    if name is None:
        raise InputError(f"{source}: missing required key 'name' (the actuator's name)")
    if not isinstance(name, str) or not name.strip():
        where = _where(source, "name", overridden)
        raise InputError(f"{where}: expected a non-empty string, got {name!r}")
    joint = merged.get("joint", "revolute")
    if joint not in ("revolute", "prismatic"):
        where = _where(source, "joint", overridden)
        raise InputError(f"{where}: expected 'revolute' or 'prismatic', got {joint!r}")
    if "screw" in merged and joint != "prismatic":
        raise InputError(
            f'{source}: section [screw]: a screw needs joint = "prismatic", got joint = {joint!r}'
        )
    units = _LINEAR if joint == "prismatic" and "screw" not in merged else _ROTARY
    joint_units = _LINEAR if joint == "prismatic" else _ROTARY
    notes: list[str] = []
    context = _Reading(
        units=units, joint_units=joint_units, joint=joint, source=source, notes=notes, overridden=overridden
    )
    sections = {
        section: _read_motor_side(merged[section], section, context)
        for section in DATASHEET_SECTIONS
        if section in merged
    }
    check_pairs(sections, source)
    for section, values in sections.items():
        for key in values:
            provenance.setdefault(f"{section}.{key}", "datasheet")
    return Datasheet(
        name=name.strip(),
        joint=joint,
        motor=MotorDatasheet(**sections["motor"]) if "motor" in sections else None,
        gear=GearboxSpec(**sections["gear"]) if "gear" in sections else None,
        controller=ControllerSpec(**sections["controller"]) if "controller" in sections else None,
        losses=LossesSpec(**sections["losses"]) if "losses" in sections else None,
        output=OutputRating(**sections["output"]) if "output" in sections else None,
        screw=ScrewSpec(**sections["screw"]) if "screw" in sections else None,
        description=read_text(merged, "description", source),
        sources=_sources(merged, source),
        source=source,
        provenance=provenance,
        notes=tuple(notes),
        current_conventions=current_conventions(merged),
        bare_numbers=bare_numbers(merged, DATASHEET_SECTIONS, KEY_ALIASES),
    )


@dataclass(frozen=True, kw_only=True, slots=True)
class _Reading:
    """What reading one file needs besides the values: units, joint type, source and a note sink."""

    units: dict[str, str]
    """SI units of motor-side kinds (linear for a linear motor)."""
    joint_units: dict[str, str]
    """SI units of joint-side kinds."""
    joint: str
    """``"revolute"`` or ``"prismatic"``."""
    source: str
    """File or catalog name, for messages."""
    notes: list[str]
    """Collects how ambiguous spellings were read."""
    overridden: frozenset[str] = frozenset()
    """``"section.key"`` (as written) of each value set with an override (``derive --set``)."""


def _where(source: str, dotted: str, overridden: frozenset[str]) -> str:
    """The start of a message about key ``dotted``: the override that set it, else the file's key."""
    # a bad --set value is the command line's mistake, not the file's: say so as an unknown key does
    return f"override {dotted!r}" if dotted in overridden else f"{source}: key {dotted!r}"


def _read_motor_side(table: Any, section: str, context: _Reading) -> dict[str, Any]:
    """``_read_section``; a rotary value on a linear motor (prismatic, no ``[screw]``) says why."""
    try:
        return _read_section(table, section, context)
    except InputError as exc:
        if context.units is not _LINEAR or context.joint_units is not _LINEAR:
            raise
        rotary = _Reading(
            units=_ROTARY,
            joint_units=_LINEAR,
            joint=context.joint,
            source=context.source,
            notes=[],
            overridden=context.overridden,
        )
        try:
            _read_section(table, section, rotary)
        except InputError:
            raise exc from None
        raise InputError(
            f'{exc}; joint = "prismatic" without [screw] reads [{section}] as a linear motor\'s '
            "(forces in N, speeds in m/s): a rotary motor on a prismatic joint needs [screw] "
            "lead = '5 mm/rev' (with its efficiency)"
        ) from None


def _apply_overrides(
    data: Mapping[str, Any], overrides: Mapping[str, object], source: str
) -> tuple[dict[str, Any], dict[str, ParamSource]]:
    """Copy ``data`` with the ``section.key`` overrides set; return it and the ``user`` provenance."""
    merged: dict[str, Any] = {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in data.items()}
    provenance: dict[str, ParamSource] = {}
    for dotted, value in overrides.items():
        section, _, key = dotted.partition(".")
        if not key:
            if section not in ("name", "joint"):
                raise InputError(f"override {dotted!r}: expected SECTION.KEY (e.g. controller.max_voltage)")
            merged[section] = value
            continue
        if section not in SECTION_KEYS:
            hint = nearest_key(section, list(SECTION_KEYS))
            raise InputError(f"override {dotted!r}: unknown section {section!r}{hint}")
        aliases = KEY_ALIASES.get(section, {})
        if key not in SECTION_KEYS[section] and key not in aliases:
            hint = nearest_key(key, [*SECTION_KEYS[section], *aliases])
            raise InputError(
                f"override {dotted!r}: unknown key {key!r} in [{section}]{hint}; "
                f"valid keys in [{section}]: {', '.join(SECTION_KEYS[section])}"
            )
        table = merged.setdefault(section, {})
        if not isinstance(table, dict):
            raise InputError(f"{source}: key {section!r}: expected a table [{section}], got {table!r}")
        canonical = aliases.get(key, key)
        for alias, target in aliases.items():  # the override replaces the key under any of its names
            if target == canonical and alias != key:
                table.pop(alias, None)
        if canonical != key:
            table.pop(canonical, None)
        table[key] = value
        provenance[f"{section}.{canonical}"] = "user"
    return merged, provenance


def _check_top_level(data: Mapping[str, Any], source: str) -> None:
    for key in data:
        if key in _TOP_KEYS:
            continue
        owner = [s for s, keys in SECTION_KEYS.items() if key in keys]
        hint = (
            f" (it belongs in section [{owner[0]}])"
            if owner
            else nearest_key(str(key), _TOP_KEYS, cutoff=0.75)
        )
        raise InputError(f"{source}: unknown key or section {key!r}{hint}; valid: {', '.join(_TOP_KEYS)}")


def read_text(data: Mapping[str, Any], key: str, source: str) -> str:
    """A string value (empty when absent), for datasheets and scenarios alike."""
    value = data.get(key, "")
    if not isinstance(value, str):
        raise InputError(f"{source}: key {key!r}: expected a string, got {value!r}")
    return value


def _sources(data: Mapping[str, Any], source: str) -> tuple[str, ...]:
    value = data.get("sources", ())
    if isinstance(value, str):
        return (value,)
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
        raise InputError(f"{source}: key 'sources': expected a list of strings (URLs), got {value!r}")
    return tuple(value)


def _read_section(table: object, section: str, reading: _Reading) -> dict[str, Any]:
    source = reading.source
    if not isinstance(table, Mapping):
        raise InputError(f"{source}: key {section!r}: expected a table [{section}], got {table!r}")
    spec = SECTION_KEYS[section]
    aliases = KEY_ALIASES.get(section, {})
    written: dict[str, str] = {}  # key -> the name it was written under
    check_keys(table, spec, source, section, aliases=aliases)
    for key in table:
        canonical = aliases.get(str(key), str(key))
        if canonical in written:
            raise InputError(
                f"{source}: keys {f'{section}.{written[canonical]}'!r} and {f'{section}.{key}'!r} "
                f"both given; they are the same key ({section}.{canonical}): keep one"
            )
        if key in _ALIAS_JOINT and _ALIAS_JOINT[key] != reading.joint:
            other = "stall_force" if reading.joint == "prismatic" else "stall_torque"
            where = _where(source, f"{section}.{key}", reading.overridden)
            raise InputError(
                f"{where}: a {reading.joint} joint has a {other} (or write {section}.{canonical})"
            )
        written[canonical] = str(key)
    required = _REQUIRED.get(section)
    if required is not None and required not in written:
        raise InputError(f"{source}: section [{section}] needs key {required!r}")
    values: dict[str, Any] = {}
    for key, name in written.items():
        raw = table[name]
        kind, rule, side = spec[key]
        where = _where(source, f"{section}.{name}", reading.overridden)
        if kind == "enum":
            values[key] = _read_enum(raw, where)
        elif kind == "points":
            values[key] = _read_points(raw, reading.units, where)
        else:
            units = reading.units if side == "motor" else reading.joint_units
            values[key] = _read_value(raw, kind, rule, units, where, reading, (section, key))
    return values


def _unit_of(kind: str, units: dict[str, str]) -> str:
    return _FIXED.get(kind) or units[kind]


def _read_value(
    raw: object,
    kind: str,
    rule: str,
    units: dict[str, str],
    where: str,
    reading: _Reading,
    key: tuple[str, str],
) -> float:
    dotted = repr(f"{key[0]}.{key[1]}")
    try:
        if kind == "ratio" and isinstance(raw, str) and ":" in raw:
            value = _read_ratio(raw, where, dotted, reading.notes)
        elif kind == "lead":
            value = _read_lead(raw, where)
        else:
            value = to_si(raw, _unit_of(kind, units), where)
    except UnitsError as exc:
        raise UnitsError(f"{exc}{_neighbour_hint(raw, key, reading)}") from None
    _check_rule(value, raw, rule, where)
    if kind == "ratio" and value < 1.0 and not (isinstance(raw, str) and ":" in raw):
        # accepted (a speed-up gear is valid), but on a robot joint it is far more often a reduction
        # typed inverted (joint speed / motor speed); "1:6" gets its note in _read_ratio
        shown = repr(raw) if isinstance(raw, str) else f"{value:g}"
        reduction = 1.0 / value
        reading.notes.append(
            f"{dotted} = {shown} is below 1: read as a speed-up gear, the joint turning {reduction:g} times "
            f"as fast as the motor (i_G = motor speed / output speed); write a reduction above 1, e.g. "
            f'{reduction:g} or "{reduction:g}:1"'
        )
    return value


def _neighbour_hint(raw: object, key: tuple[str, str], reading: _Reading) -> str:
    """``": it reads as a speed constant ...: did you mean motor.speed_constant?"`` or ``""``."""
    if not isinstance(raw, str):
        return ""
    section = key[0]
    ordered = [section] + [s for s in SECTION_KEYS if s != section]
    for candidate_section in ordered:
        for candidate, (kind, _, side) in SECTION_KEYS[candidate_section].items():
            if (candidate_section, candidate) == key or kind in ("enum", "points", "lead"):
                continue
            units = reading.units if side == "motor" else reading.joint_units
            unit = _unit_of(kind, units)
            if converts_to(raw, unit):
                words = describe_unit(unit).split(" in ")[0]
                return f"; {raw!r} reads as {words}: did you mean {candidate_section}.{candidate}?"
    return ""


def _read_ratio(raw: str, where: str, dotted: str, notes: list[str]) -> float:
    """Read a ratio printed as ``"6:1"`` (motor turns : output turns); ``"1:50"`` is a reduction of 50."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*:\s*([0-9]*\.?[0-9]+)\s*", raw)
    try:
        if match is None:
            raise ValueError(raw)
        first, second = float(match.group(1)), float(match.group(2))
        value = first / second
    except (ValueError, ZeroDivisionError):
        raise InputError(
            f'{where}: cannot read {raw!r} as a gear ratio (write 6, "6:1" or "6 : 1")'
        ) from None
    if 0.0 < first < second:
        # vendors print reductions both ways ("1:50" and "50:1"); a speed-up gear is rare and must
        # be written as a plain number, so the smaller-first spelling is read as a reduction
        notes.append(
            f"{dotted} = {raw!r} read as a reduction of {second / first:g} "
            f"(i_G = motor speed / output speed); write a speed-up gear as a number, e.g. {first / second:g}"
        )
        return second / first
    return value


def _read_lead(raw: object, where: str) -> float:
    """Read a screw lead [m]; ``"5 mm/rev"`` (travel per revolution) and ``"5 mm"`` both work."""
    if isinstance(raw, str) and re.search(r"/\s*(rev|revolution|turn)s?\s*$", raw):
        return to_si(raw, "m/turn", where)
    return to_si(raw, "m", where)


def _check_rule(value: float, raw: object, rule: str, where: str) -> None:
    shown = repr(raw) if isinstance(raw, str) else f"{value:g}"
    if rule == ">0" and not value > 0.0:
        raise InputError(f"{where}: expected a value > 0, got {shown}")
    if rule == ">=0" and not value >= 0.0:
        raise InputError(f"{where}: expected a value >= 0, got {shown}")
    if rule == "(0,1]" and not 0.0 < value <= 1.0:
        raise InputError(f'{where}: expected a fraction in (0, 1] (e.g. 0.9 or "90 %"), got {shown}')
    if value == float("inf"):
        raise InputError(f"{where}: expected a finite value, got {shown}")


def _read_enum(raw: object, where: str) -> str:
    if raw not in GRADIENT_METHODS:
        hint = nearest_key(str(raw), GRADIENT_METHODS)
        raise InputError(f"{where}: expected one of {', '.join(GRADIENT_METHODS)}, got {raw!r}{hint}")
    return str(raw)


MAX_OPERATING_POINTS = 10_000
"""Most ``operating_points`` read: a digitized curve has tens to hundreds; each costs a unit conversion."""


def _read_points(raw: object, units: dict[str, str], where: str) -> tuple[tuple[float, float], ...]:
    if not isinstance(raw, (list, tuple)):
        raise InputError(f"{where}: expected a list of [speed, torque] pairs, got {raw!r}")
    if len(raw) > MAX_OPERATING_POINTS:
        raise InputError(
            f"{where}: {len(raw)} points; expected at most {MAX_OPERATING_POINTS} (a digitized curve "
            "needs tens; thin the points out, or fit a measured sweep with `drive-envelope fit`)"
        )
    points = []
    for index, pair in enumerate(raw):
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise InputError(f"{where}: point {index}: expected a [speed, torque] pair, got {pair!r}")
        speed = to_si(pair[0], units["speed"], f"{where}: point {index} speed")
        torque = to_si(pair[1], units["torque"], f"{where}: point {index} torque")
        _check_rule(speed, pair[0], ">=0", f"{where}: point {index} speed")
        _check_rule(torque, pair[1], ">=0", f"{where}: point {index} torque")
        points.append((speed, torque))
    return tuple(points)

"""The one role-to-column plan of every log reader: which header cell holds which role.

``check`` and ``fit`` (:mod:`.log_model`), ``fit --from-curve`` (:mod:`.curve`: a curve's
``speed``/``torque`` aliases), ``identify`` and ``replay`` (their bench logs) each say which roles
they read as :class:`Role` values (the column the user named or the default, aliases, required or
not, the flag that names it, what its unit converts to), and :func:`plan_columns` matches them
against a header once, with one rule and one set of messages:

- a cell is a role's column when its name (without the unit) or its whole text equals the role's
  name or an alias, up to case and outer spaces (:func:`~.log_units.find_columns`);
- a name found twice (``velocity,Velocity``), two cells that could each be the role (``velocity``
  and its alias ``speed``), or one cell named for two roles is an error, never a silent first pick;
  a default-named optional role (``time``) whose cell an explicit role took is not read;
- every required role that is missing is named in one line, with the columns the header has, the
  nearest name in it and the flag (or the file kind's list of columns) that fixes it;
- a unit in a header converts the column to SI (:func:`~.log_units.column_scale`), and units of two
  joint types in one header are refused.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from drive_envelope._src.analysis.log_units import ROLE_UNITS, column_scale, find_columns, split_header
from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError
from drive_envelope._src.validation import nearest_key


@dataclass(frozen=True, kw_only=True, slots=True)
class Role:
    """One thing a reader takes from a log, and how its column is found."""

    role: str
    """The role's key in the plan (``"velocity"``, ``"target_position"``)."""
    column: str | None
    """The column name looked for: the user's choice or the default; None: the role is not read."""
    required: bool = False
    """Whether a log without the column is refused (an optional role is read when present)."""
    aliases: tuple[str, ...] = ()
    """Other names that may hold the role (a curve's ``speed``); looked for beside ``column``."""
    flag: str = ""
    """The option that names the column (``--velocity-column``), for messages; ``""``: none."""
    quantity: str | None = None
    """What a unit in the header converts to (a key of :data:`~.log_units.ROLE_UNITS`); None: no unit."""
    text: bool = False
    """A column of names (the joint): found by its whole header text, never converted."""
    meaning: str = ""
    """What a number column without a quantity holds (``"0 or 1 per sample"``), for its unit error."""


@dataclass(frozen=True, kw_only=True, slots=True)
class ColumnPlan:
    """Where each role's column sits in a header, with the scale of its unit to SI."""

    label: str
    """The source, which starts every message."""
    header: tuple[str, ...]
    """The header cells, outer spaces removed (names with their units)."""
    position: dict[str, int]
    """Role -> index in ``header`` of each role found, in the order of the roles."""
    numeric: tuple[str, ...]
    """The roles found that are read as numbers (every one but a text role), in the order of the roles."""
    scale: dict[str, float]
    """Numeric role -> factor to SI of its values (1.0 without a unit in the header)."""
    unit: dict[str, str]
    """Numeric role -> the unit written in its header (``""`` for none)."""
    joint_type: JointType | None
    """The joint type asked for, else the one the units imply; None when nothing tells."""

    def name(self, role: str) -> str:
        """The header text of ``role``'s column (with its unit, as written)."""
        return self.header[self.position[role]]

    def __contains__(self, role: object) -> bool:
        return role in self.position


def plan_columns(
    header: Sequence[object],
    roles: Sequence[Role],
    label: str,
    *,
    joint_type: JointType | None = None,
    needs: str = "",
) -> ColumnPlan:
    """Match ``roles`` against ``header`` (see the module docstring for the rules).

    Args:
        header: The header cells (CSV header, Parquet schema, table keys).
        roles: What the reader takes, in the order they are resolved and reported.
        label: The file (or ``<table>``) the header comes from; it starts every message.
        joint_type: The joint type the log is read for (fixes what units convert to); None: either,
            as the units say.
        needs: The kind of file (``"a bench log"``): a missing column's message then lists the
            columns it needs and those it may have.

    Raises:
        InputError: one line naming ``label``: a name found twice, two cells for one role, one
            cell for two roles, the missing required columns (with the columns there, the nearest
            name and the fix), a bad unit, or units of two joint types.
    """
    cells = tuple(str(cell).strip() for cell in header)
    position: dict[str, int] = {}
    missing: list[Role] = []
    for role in roles:
        if role.column is None:
            continue
        index = _find(cells, role, role.column, label)
        if index is None:
            if role.required:
                missing.append(role)
            continue
        taken = next((other for other, at in position.items() if at == index), None)
        if taken is not None:
            if not role.required:  # a default name (time, joint) taken by an explicit role: not read
                continue
            first = next(item for item in roles if item.role == taken)
            raise InputError(
                f"{label}: column {cells[index]!r} is named by both {first.flag or repr(taken)} and "
                f"{role.flag or repr(role.role)}; expected a different column for each"
            )
        position[role.role] = index
    if missing:
        raise InputError(_missing(cells, roles, missing, position, label, needs))
    return _units(cells, roles, position, label, joint_type)


def _find(cells: tuple[str, ...], role: Role, column: str, label: str) -> int | None:
    """The one cell that holds ``role`` (its ``column`` or an alias), or None."""
    hits: dict[int, None] = {}
    for name in dict.fromkeys([column.strip(), *role.aliases]):
        found = find_columns(cells, name, whole=role.text)
        if len(found) > 1:
            listed = ", ".join(f"{cells[i]!r} (column {i + 1})" for i in found)
            raise InputError(
                f"{label}: column {name!r} is ambiguous: the header has {listed}; "
                "expected each column name once"
            )
        hits.update(dict.fromkeys(found))
    if len(hits) > 1:
        listed = ", ".join(repr(cells[i]) for i in sorted(hits))
        fix = f"name the one to use with {role.flag}" if role.flag else "expected one"
        raise InputError(f"{label}: columns {listed} could each be the {role.role}; {fix}")
    return next(iter(hits), None)


def _missing(
    cells: tuple[str, ...],
    roles: Sequence[Role],
    missing: list[Role],
    position: dict[str, int],
    label: str,
    needs: str,
) -> str:
    """The one line for the required columns a header lacks."""
    names = [repr(str(role.column).strip()) for role in missing]
    wanted = names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"
    free = [split_header(cell)[0] for index, cell in enumerate(cells) if index not in position.values()]
    nearest = nearest_key(str(missing[0].column).strip(), free) if free else ""
    fixes = []
    flags = [role.flag for role in missing if role.flag]
    joints = _per_joint(free, [str(role.column).strip() for role in missing])
    if joints and len(flags) == len(missing):  # simulate's chain format: JOINT.velocity, JOINT.effort
        nearest = ""
        example = " ".join(f"{role.flag} {joints[0]}.{str(role.column).strip()}" for role in missing)
        fixes.append(f"the columns are per joint ({', '.join(joints)}): name one with {example}")
    elif flags:
        fixes.append(f"name {'it' if len(flags) == 1 else 'them'} with {' and '.join(flags)}")
    if needs:
        required = [str(role.column) for role in roles if role.required and role.column is not None]
        optional = [str(role.column) for role in roles if not role.required and role.column is not None]
        tail = f" (optional: {', '.join(optional)})" if optional else ""
        fixes.append(f"{needs} needs {', '.join(required)}{tail}")
    return f"{label}: no column {wanted} (columns: {', '.join(cells) or 'none'}){nearest}" + "".join(
        f"; {fix}" for fix in fixes
    )


def _per_joint(names: Sequence[str], wanted: Sequence[str]) -> list[str]:
    """The prefixes ``JOINT`` for which every wanted name stands as ``JOINT.name``, in header order."""
    prefixes = [name[: -len(f".{wanted[0]}")] for name in names if name.endswith(f".{wanted[0]}")]
    return [joint for joint in prefixes if joint and all(f"{joint}.{other}" in names for other in wanted)]


def _units(
    cells: tuple[str, ...],
    roles: Sequence[Role],
    position: dict[str, int],
    label: str,
    joint_type: JointType | None,
) -> ColumnPlan:
    """The plan with each numeric column's unit read (a unit of the wrong kind raises)."""
    numeric = tuple(role.role for role in roles if role.role in position and not role.text)
    scale: dict[str, float] = {}
    unit: dict[str, str] = {}
    implied: dict[str, JointType] = {}
    quantities = []
    for role in (item for item in roles if item.role in numeric):
        cell = cells[position[role.role]]
        unit[role.role] = split_header(cell)[1]
        where = f"{label}: column {cell!r}"
        if role.quantity is None:
            if unit[role.role]:
                raise InputError(f"{where}: expected no unit ({role.meaning}), got {unit[role.role]!r}")
            scale[role.role] = 1.0
            continue
        quantities.append(role.quantity)
        scale[role.role], kind = column_scale(role.quantity, unit[role.role], joint_type, where)
        if kind is not None:
            implied[cell] = kind
    if len(set(implied.values())) > 1:
        (first, kind), *rest = implied.items()
        other, other_kind = next((cell, k) for cell, k in rest if k != kind)
        kinds = [q for q in dict.fromkeys(quantities) if q != "time"]
        units = [" and ".join(ROLE_UNITS[q][joint] for q in kinds) for joint in ("revolute", "prismatic")]
        raise InputError(
            f"{label}: the header units are of two joint types: column {first!r} has the unit of a "
            f"{kind} joint but column {other!r} that of a {other_kind} joint; expected one joint type "
            f"({units[0]} for a revolute joint, or {units[1]} for a prismatic one)"
        )
    return ColumnPlan(
        label=label,
        header=cells,
        position=position,
        numeric=numeric,
        scale=scale,
        unit=unit,
        joint_type=joint_type or next(iter(implied.values()), None),
    )

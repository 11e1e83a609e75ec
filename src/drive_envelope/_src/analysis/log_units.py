"""Units in column headers: ``speed [rpm]``, ``torque (mNm)``, read the same way by every reader.

A header cell is a name and, optionally, a unit in square brackets or parentheses after it. The
unit gives the scale to SI of every value in that column; a column without a unit is SI. A column
is found by its name or its whole text up to case (:func:`find_columns`: ``Velocity [RPM]`` is the
``velocity`` column); units keep their case, as the unit parser reads them (``RPM``, ``Rpm`` and
``rpm`` are rpm there, while ``Ms`` and ``ms`` are different units). The one column plan
(:mod:`.columns`) uses :func:`find_columns`, :func:`split_header` and :func:`column_scale` for the
log readers (:mod:`.log_model`), the curve reader (:mod:`.curve`) and identify's bench logs, so
``check``, ``fit``, ``fit --from-curve``, ``identify`` and ``replay`` accept the same headers.

SI units per role, by joint type: time [s]; position [rad or m]; velocity [rad/s or m/s]; effort
[N*m or N]. Angles are explicit (``deg``, ``deg/s``, ``rpm``, ``rev/s``): ``1/s`` and ``Hz`` are
refused for an angular speed, as :func:`~drive_envelope._src.units.to_si` refuses them everywhere.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from drive_envelope._src.envelope.model import JointType
from drive_envelope._src.errors import InputError, UnitsError
from drive_envelope._src.units import describe_unit, to_si

JOINT_TYPES: tuple[JointType, ...] = ("revolute", "prismatic")
"""Joint types, in the order a unit is tried when the joint type is not known."""
ROLE_UNITS: dict[str, dict[JointType, str]] = {
    "time": {"revolute": "s", "prismatic": "s"},
    "position": {"revolute": "rad", "prismatic": "m"},
    "velocity": {"revolute": "rad/s", "prismatic": "m/s"},
    "effort": {"revolute": "N*m", "prismatic": "N"},
}
"""SI unit of each numeric column role by joint type: what a unit in its header converts to."""

_WORDS = {"rad": "an angle in rad (e.g. 'deg')", "m": "a length in m (e.g. 'mm')"}
# name, then one bracketed unit to the end of the cell; the unit may itself hold parentheses
_HEADER = re.compile(r"^(?P<name>[^\[\(]*?)\s*(?:\[(?P<square>.*)\]|\((?P<round>.*)\))$")


def split_header(cell: str) -> tuple[str, str]:
    """``"velocity [rpm]"`` -> ``("velocity", "rpm")``; a cell without a unit -> ``(cell, "")``.

    Spaces around the name and the unit are removed. A cell whose brackets do not close at its end
    (``velocity [rpm] raw``) has no unit: its whole text is its name.
    """
    text = str(cell).strip()
    match = _HEADER.match(text)
    if match is None or not match.group("name").strip():
        return text, ""
    unit = match.group("square") if match.group("square") is not None else match.group("round")
    return match.group("name").strip(), (unit or "").strip()


def find_columns(header: Sequence[str], name: str, *, whole: bool = False) -> list[int]:
    """Indices of the header cells that are ``name`` up to case (the one rule of every log reader).

    A cell is ``name`` when its whole text or (unless ``whole``) its name without the unit equals
    ``name`` ignoring case and surrounding spaces: ``velocity`` finds ``Velocity [RPM]`` and
    ``VELOCITY``. More than one index means the column is ambiguous (``Velocity,velocity``); the
    caller refuses that rather than pick one.
    """
    wanted = name.strip().casefold()
    found = []
    for index, cell in enumerate(header):
        texts = [str(cell).strip()] if whole else [str(cell).strip(), split_header(cell)[0]]
        if any(text.casefold() == wanted for text in texts):
            found.append(index)
    return found


def _describe(unit: str) -> str:
    return _WORDS.get(unit, describe_unit(unit))


def _scale(unit: str, target: str, where: str) -> tuple[float | None, bool]:
    """``(scale to target, unit known)``: scale None when ``unit`` is not a ``target`` quantity."""
    try:
        return to_si(f"1 {unit}", target, where), True
    except UnitsError as exc:
        return None, not str(exc).removeprefix(f"{where}: ").startswith("unknown unit")


def column_scale(role: str, unit: str, joint: JointType | None, where: str) -> tuple[float, JointType | None]:
    """The factor that turns a column's values in ``unit`` into SI, and the joint type it implies.

    Args:
        role: ``"time"``, ``"position"``, ``"velocity"`` or ``"effort"`` (see :data:`ROLE_UNITS`).
        unit: The unit from the header (``"rpm"``); empty: the values are SI already.
        joint: The joint type the log is read for; None: either, as the unit says.
        where: The file and column, which start every error message.

    Returns:
        ``(scale, joint type)``: ``scale`` [SI per unit]; the joint type the unit implies (None for
        a time, an empty unit, or a unit that fits both).

    Raises:
        InputError: an unknown unit, or one of the wrong dimension for the role (one line naming
            ``where`` and the unit).
    """
    units = ROLE_UNITS[role]
    if not unit:
        return 1.0, None
    kinds = JOINT_TYPES if joint is None else (joint,)
    known = False
    for kind in kinds:
        scale, recognised = _scale(unit, units[kind], where)
        known = known or recognised
        if scale is not None:
            return scale, (None if units["revolute"] == units["prismatic"] else kind)
    expected = " or ".join(dict.fromkeys(_describe(units[kind]) for kind in kinds))
    if not known:
        raise InputError(f"{where}: unknown unit {unit!r}; expected {expected}")
    other = [
        kind for kind in JOINT_TYPES if kind not in kinds and _scale(unit, units[kind], where)[0] is not None
    ]
    hint = f"; it is the unit of a {other[0]} joint" if other else ""
    raise InputError(f"{where}: unit {unit!r} is not {expected}{hint}")

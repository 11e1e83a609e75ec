"""A URDF robot as chain-scenario joints: the ``[[joints]]`` entries of its revolute and prismatic joints.

A URDF child link's frame is its joint's frame (``origin xyz rpy`` in the parent link's frame) and
the joint axis is in it, which is the chain format's convention, so each moving joint becomes
one ``[[joints]]`` entry with ``origin``, ``quat`` (from ``rpy``), ``axis`` and its child link's
``mass``, ``com`` and full inertia tensor (the inertial ``origin rpy`` turned into the link frame,
six numbers ``[ixx, iyy, izz, ixy, ixz, iyz]``). A link hung on a ``fixed`` joint is welded to
its parent: the links fixed to the root are the fixed base (dropped), any other is merged into
the moving link it hangs on (mass, centre of mass and inertia by the parallel-axis theorem) and
its children's joints are carried through its fixed transform.

Not read: joint limits, ``dynamics`` (damping, friction), ``mimic``, visuals and collisions (the
stands have none); the caller adds each joint's drive and envelope tables.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drive_envelope._src.errors import InputError
from drive_envelope._src.scenario.chain_frames import (
    IDENTITY,
    Matrix3,
    Quaternion,
    quat_from_rpy,
    quat_multiply,
    rotate,
    turn_tensor,
)

_MOVING = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}


@dataclass(kw_only=True, slots=True)
class _Body:
    """A link's inertia in its own frame (mass [kg], centre of mass [m], tensor about it [kg*m^2])."""

    mass: float
    com: tuple[float, float, float]
    tensor: Matrix3


def _numbers(element: ET.Element | None, key: str, count: int, where: str) -> tuple[float, ...]:
    text = "0 " * count if element is None else element.get(key, "0 " * count)
    try:
        values = tuple(float(item) for item in text.split())
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputError(f"{where}: key '{key}': expected {count} numbers, got {text!r}")
    return values


def _pose(element: ET.Element | None, where: str) -> tuple[tuple[float, float, float], Quaternion]:
    origin = None if element is None else element.find("origin")
    x, y, z = _numbers(origin, "xyz", 3, where)
    roll, pitch, yaw = _numbers(origin, "rpy", 3, where)
    return (x, y, z), quat_from_rpy(roll, pitch, yaw)


def _inertial(link: ET.Element, where: str) -> _Body:
    inertial = link.find("inertial")
    if inertial is None:
        return _Body(mass=0.0, com=(0.0, 0.0, 0.0), tensor=((0.0,) * 3,) * 3)  # type: ignore[arg-type]
    com, turn = _pose(inertial, f"{where} inertial origin")
    (mass,) = _numbers(inertial.find("mass"), "value", 1, f"{where} inertial mass")
    element = inertial.find("inertia")
    if element is None:
        raise InputError(f"{where}: an <inertial> needs an <inertia>")
    keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    ixx, iyy, izz, ixy, ixz, iyz = (_numbers(element, key, 1, f"{where} inertia")[0] for key in keys)
    tensor = ((ixx, ixy, ixz), (ixy, iyy, iyz), (ixz, iyz, izz))
    return _Body(mass=mass, com=com, tensor=turn_tensor(turn, tensor))


def _merge(body: _Body, part: _Body, shift: tuple[float, float, float], turn: Quaternion) -> _Body:
    """``part`` (in its frame, at ``shift``/``turn`` in ``body``'s) welded onto ``body``."""
    if part.mass == 0.0:
        return body
    moved = rotate(turn, part.com)
    com_part = (shift[0] + moved[0], shift[1] + moved[1], shift[2] + moved[2])
    mass = body.mass + part.mass
    com = tuple((body.mass * a + part.mass * b) / mass for a, b in zip(body.com, com_part, strict=True))
    part_tensor = turn_tensor(turn, part.tensor)
    total = [[0.0] * 3 for _ in range(3)]
    for m, c, t in ((body.mass, body.com, body.tensor), (part.mass, com_part, part_tensor)):
        d = [c[i] - com[i] for i in range(3)]
        square = sum(v * v for v in d)
        for i in range(3):
            for j in range(3):
                total[i][j] += t[i][j] + m * ((square if i == j else 0.0) - d[i] * d[j])
    return _Body(mass=mass, com=com, tensor=tuple(tuple(row) for row in total))  # type: ignore[arg-type]


def urdf_joints(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The ``[[joints]]`` entries of a fixed-base URDF robot, parents first (the file's tree order).

    Raises:
        InputError: the file is not a URDF tree (no single root, a cycle, a floating or planar
            joint), or a number or an inertia is missing or not finite; the message names the file
            and the element.
    """
    file = Path(path)
    try:
        robot = ET.parse(file).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"{file}: cannot read the URDF: {exc}") from None
    links = {link.get("name", ""): link for link in robot.findall("link")}
    joints = robot.findall("joint")
    children: dict[str, list[ET.Element]] = {}
    parents = set()
    for joint in joints:
        where = f"{file}: joint {joint.get('name')!r}"
        kind = joint.get("type", "")
        if kind not in (*_MOVING, "fixed"):
            raise InputError(f"{where}: type {kind!r}: expected revolute, continuous, prismatic or fixed")
        parent, child = joint.find("parent"), joint.find("child")
        if (
            parent is None
            or child is None
            or parent.get("link") not in links
            or child.get("link") not in links
        ):
            raise InputError(f"{where}: expected <parent link=...> and <child link=...> naming links")
        children.setdefault(str(parent.get("link")), []).append(joint)
        parents.add(str(child.get("link")))
    roots = [name for name in links if name not in parents]
    if len(roots) != 1:
        raise InputError(f"{file}: expected one root link (the fixed base), got {roots}")
    entries: list[dict[str, Any]] = []
    bodies: list[_Body] = []
    # each link's moving link (index into entries, -1 the base) and its pose in that link's frame
    carrier: dict[str, tuple[int, tuple[float, float, float], Quaternion]] = {
        roots[0]: (-1, (0.0, 0.0, 0.0), IDENTITY)
    }
    stack = [roots[0]]
    while stack:
        name = stack.pop(0)
        index, shift, turn = carrier[name]
        for joint in children.get(name, []):
            where = f"{file}: joint {joint.get('name')!r}"
            link_name = str(joint.find("child").get("link"))  # type: ignore[union-attr]
            if link_name in carrier:
                raise InputError(f"{where}: link {link_name!r} is reached twice (a URDF is a tree)")
            xyz, rpy = _pose(joint, where)
            moved = rotate(turn, xyz)
            origin = (shift[0] + moved[0], shift[1] + moved[1], shift[2] + moved[2])
            quat = quat_multiply(turn, rpy)
            body = _inertial(links[link_name], f"{file}: link {link_name!r}")
            if joint.get("type") == "fixed":
                carrier[link_name] = (index, origin, quat)
                if index >= 0:
                    bodies[index] = _merge(bodies[index], body, origin, quat)
            else:
                found = joint.find("axis")
                axis = (1.0, 0.0, 0.0) if found is None else _numbers(found, "xyz", 3, f"{where} axis")
                entries.append({
                    "name": joint.get("name"), "type": _MOVING[str(joint.get("type"))],
                    "parent": "base" if index < 0 else entries[index]["name"],
                    "origin": list(origin), "quat": list(quat), "axis": list(axis),
                })  # fmt: skip
                bodies.append(body)
                carrier[link_name] = (len(entries) - 1, (0.0, 0.0, 0.0), IDENTITY)
            stack.append(link_name)
    for entry, body in zip(entries, bodies, strict=True):
        if not body.mass > 0.0:
            raise InputError(
                f"{file}: joint {entry['name']!r}: its link (with the links fixed to it) has no mass; "
                "expected an <inertial> with <mass value> > 0"
            )
        t = body.tensor
        entry.update(mass=body.mass, com=list(body.com),
                     inertia=[t[0][0], t[1][1], t[2][2], t[0][1], t[0][2], t[1][2]])  # fmt: skip
    return entries

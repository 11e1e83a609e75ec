"""Which joints PhysX simulates as articulation joints: the only ones that keep the envelope.

Two steps of omni.physx's USD loading are followed (NVIDIA-Omniverse/PhysX, under
``omni/extensions/runtime/source/``):

1. finding articulations, ``omni.usdphysics/plugins/Articulation.cpp`` ``finalizeArticulations``
   (the same algorithm as OpenUSD's ``pxr/usd/usdPhysics/parseUtils.cpp``), with the body rules of
   ``omni.usdphysics/plugins/UsdLoad.cpp``:

   * a ``PhysicsArticulationRootAPI`` prim starts an articulation (a root nested under another
     root is ignored, one with ``physxArticulation:articulationEnabled = false`` too). On a rigid
     body it is the floating base (refused when the body is disabled or kinematic); on a joint
     with one empty body (a world-anchoring joint such as Isaac Sim's ``rootJoint``) the base is
     the joint's other body; on any other prim (an Xform above the robot) every rigid body below
     it starts a search, and each connected group gets as its root its world-anchoring joint (the
     heaviest by PhysX's weights) or, with none, its most central body;
   * links are the enabled, non-kinematic rigid bodies reached through enabled joints (a joint's
     ``body0``/``body1`` stands for its nearest ``RigidBodyAPI`` ancestor); the search does not
     cross a joint with ``excludeFromArticulation``; a dynamic body inside an instance is no body
     at all ("RigidBodyAPI on an instance proxy not supported");

2. building the tree, ``omni.physx/plugins/usdLoad/Articulation.cpp`` ``createArticulationLinks``
   and ``createLinkHierarchy``: from the root link, in the stage's joint order, each joint to a
   dynamic body that is not yet a link makes that body a child link: those joints are the
   articulation joints. Not articulation joints: the world-anchoring root joint (it fixes the base
   and carries no DOF, whatever its type), a joint to the world from any other link, a second
   joint that closes a loop ("closed articulation ... will be now excluded"), excluded joints and
   distance joints. PhysX drops the envelope of all of those.

The tests check :func:`articulated_joints` against the joints real PhysX (ovphysx) loads as
articulation DOFs on each layout, and against OpenUSD's parser on Newton's assets.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pxr import Usd

_WORLD_WEIGHT, _EXCLUDED_WEIGHT, _LINK_WEIGHT = 100000, 1000, 100  # finalizeArticulations' weights


@dataclass(frozen=True, slots=True)
class _Joint:
    body0: str
    """Body (or "" for the world) of ``physics:body0``."""
    body1: str
    """Body of ``physics:body1``."""
    excluded: bool
    """``physics:excludeFromArticulation``."""
    distance: bool
    """A distance joint (never an articulation joint)."""


@dataclass(slots=True)
class _Scene:
    """The physics prims of a stage as omni.physx's parser sees them."""

    dynamic: set[str] = field(default_factory=set)
    """Enabled, non-kinematic rigid bodies outside instances: the possible links."""
    bodies: set[str] = field(default_factory=set)
    """Every rigid body PhysX knows (dynamic, kinematic, disabled)."""
    joints: dict[str, _Joint] = field(default_factory=dict)
    """Enabled joints in stage order."""
    roots: list[str] = field(default_factory=list)
    """Enabled articulation roots, outermost only, in stage order."""
    links: dict[str, list[str]] = field(default_factory=dict)
    """Dynamic body -> its joints, sorted by path (the parser's order)."""


def _traverse(prim: Usd.Prim) -> Any:
    from pxr import Usd

    return iter(Usd.PrimRange(prim, Usd.TraverseInstanceProxies()))


def _body_of(stage: Usd.Stage, target: Any) -> str:
    """The body a joint relationship stands for: the nearest ``RigidBodyAPI`` ancestor, else a collider."""
    from pxr import UsdPhysics

    prim = stage.GetPrimAtPath(target)
    collision = ""
    while prim and not prim.IsPseudoRoot():
        if prim.HasAPI(UsdPhysics.RigidBodyAPI):
            return str(prim.GetPath())
        if prim.HasAPI(UsdPhysics.CollisionAPI):
            collision = str(prim.GetPath())  # a static collider: a body, never a link
        prim = prim.GetParent()
    return collision


def _articulation_enabled(prim: Usd.Prim) -> bool:
    attr = prim.GetAttribute("physxArticulation:articulationEnabled")
    return not (prim.HasAPI("PhysxArticulationAPI") and attr.Get() is False)


def _scan(stage: Usd.Stage) -> _Scene:
    from pxr import UsdPhysics

    scene = _Scene()
    for prim in _traverse(stage.GetPseudoRoot()):
        path = str(prim.GetPath())
        if prim.HasAPI(UsdPhysics.RigidBodyAPI):
            api = UsdPhysics.RigidBodyAPI(prim)
            dynamic = bool(api.GetRigidBodyEnabledAttr().Get()) and not api.GetKinematicEnabledAttr().Get()
            if not (dynamic and prim.IsInstanceProxy()):
                scene.bodies.add(path)
                if dynamic:
                    scene.dynamic.add(path)
        if prim.IsA(UsdPhysics.Joint) and UsdPhysics.Joint(prim).GetJointEnabledAttr().Get():
            joint = UsdPhysics.Joint(prim)
            targets = [rel.GetTargets() for rel in (joint.GetBody0Rel(), joint.GetBody1Rel())]
            body0, body1 = (_body_of(stage, t[0]) if t else "" for t in targets)
            excluded = bool(joint.GetExcludeFromArticulationAttr().Get())
            scene.joints[path] = _Joint(body0, body1, excluded, prim.IsA(UsdPhysics.DistanceJoint))
        nested = any(path.startswith(root + "/") for root in scene.roots)
        if prim.HasAPI(UsdPhysics.ArticulationRootAPI) and not nested and _articulation_enabled(prim):
            scene.roots.append(path)
    for path in sorted(scene.joints):
        joint = scene.joints[path]
        for body in dict.fromkeys((joint.body0, joint.body1)):
            if body in scene.dynamic:
                scene.links.setdefault(body, []).append(path)
    return scene


def articulated_joints(stage: Usd.Stage) -> frozenset[str]:
    """Paths of the joints PhysX makes articulation joints (see the module docstring)."""
    scene = _scan(stage)
    consumed: set[str] = set()  # shared by all articulations, as in createArticulationLinks
    found: set[str] = set()
    for root in scene.roots:
        candidates, root_prims = _find_articulation(stage, scene, root)
        order = [path for path in scene.joints if path in candidates]
        for root_prim in root_prims:
            base = _root_link(scene, root_prim, consumed)
            if base is not None:
                _build_tree(scene, base, order, consumed, found)
    return frozenset(found)


# -- step 1: finalizeArticulations -------------------------------------------------------------------


def _find_articulation(stage: Usd.Stage, scene: _Scene, root: str) -> tuple[set[str], list[str]]:
    """The articulation's candidate joints and its root prims (bodies or world joints)."""
    start, root_prims = root, []
    if root in scene.bodies:
        if root not in scene.dynamic:
            return set(), []  # "ArticulationRootAPI definition on a static/kinematic rigid body"
        root_prims = [root]
    elif root in scene.joints:
        joint = scene.joints[root]
        if not joint.body0 or not joint.body1:
            root_prims, start = [root], joint.body1 or joint.body0
    prim = stage.GetPrimAtPath(start) if start else None
    candidates: set[str] = set()
    if not prim:
        return candidates, []
    choose = not root_prims  # a root API on an Xform: each connected group gets its own root
    collected: set[str] = set()
    prims = _traverse(prim)
    for candidate in prims:
        path = str(candidate.GetPath())
        if path in collected:
            prims.PruneChildren()  # a link's subtree was searched with it
        elif path in scene.bodies:
            order = _collect(path, scene, collected)
            if order:
                candidates.update(joint for body in order for joint in scene.links[body])
                chosen = _choose_root(scene, order) if choose else ""
                if chosen:
                    root_prims.append(chosen)
    return candidates, root_prims


def _is_world(scene: _Scene, joint: _Joint) -> bool:
    return not (joint.body0 in scene.links and joint.body1 in scene.links)


def _neighbours(scene: _Scene, body: str) -> list[str]:
    """The links one enabled, not excluded joint away from ``body``, in its joints' order."""
    others = []
    for path in scene.links[body]:
        joint = scene.joints[path]
        if not _is_world(scene, joint) and not joint.excluded:
            others.append(joint.body1 if joint.body0 == body else joint.body0)
    return others


def _collect(start: str, scene: _Scene, collected: set[str]) -> list[str]:
    """The links reachable from ``start`` in the parser's depth-first order (traverseHierarchy)."""
    order: list[str] = []
    stack = [start]
    while stack:
        body = stack.pop()
        if body in collected or body not in scene.links:
            continue
        collected.add(body)
        order.append(body)
        stack.extend(reversed(_neighbours(scene, body)))  # visit in joint order, as the recursion does
    return order


def _weight(scene: _Scene, body: str) -> tuple[int, str]:
    """A link's weight and its world-anchoring joint ("" if none), as finalizeArticulations counts."""
    weight, anchor = 0, ""
    for path in scene.links[body]:
        joint = scene.joints[path]
        if _is_world(scene, joint):
            weight += _EXCLUDED_WEIGHT if joint.excluded else _WORLD_WEIGHT
            anchor = anchor if joint.excluded else path
        else:
            weight += _EXCLUDED_WEIGHT if joint.excluded else _LINK_WEIGHT
    return weight, anchor


def _choose_root(scene: _Scene, order: list[str]) -> str:
    """The root prim of one connected group: its heaviest world joint, else its most central body."""
    best, largest = "", 0
    for body in sorted(order):
        weight, anchor = _weight(scene, body)
        if anchor and weight > largest:
            best, largest = anchor, weight
    return best or _center(scene, order)


def _center(scene: _Scene, order: list[str]) -> str:
    """The body with the smallest eccentricity; ties: more joints, then the earlier one (getCenterOfGraph)."""
    neighbours = {body: _neighbours(scene, body) for body in order}
    best, best_key = "", (0, 0, 0)
    for index, body in enumerate(order):
        key = (-_eccentricity(neighbours, body), len(scene.links[body]), -index)
        if not best or key > best_key:
            best, best_key = body, key
    return best


def _eccentricity(neighbours: dict[str, list[str]], start: str) -> int:
    """The longest of the shortest link distances from ``start``."""
    seen, frontier, depth = {start}, [start], 0
    while True:
        frontier = [n for b in frontier for n in neighbours.get(b, ()) if n not in seen]
        if not frontier:
            return depth
        seen.update(frontier)
        depth += 1


# -- step 2: createArticulationLinks / createLinkHierarchy -------------------------------------------


def _root_link(scene: _Scene, root_prim: str, consumed: set[str]) -> str | None:
    """The root link of a root prim; a world joint fixes the base and is consumed (no DOF)."""
    if root_prim not in scene.joints:
        return root_prim if root_prim in scene.dynamic else None
    joint = scene.joints[root_prim]
    if not joint.body0 or not joint.body1:
        base = joint.body1 or joint.body0
    else:  # a joint to a static or kinematic body: the base is the dynamic side
        base = joint.body1 if joint.body0 not in scene.dynamic else joint.body0
    consumed.add(root_prim)
    return base if base in scene.dynamic else None


def _build_tree(scene: _Scene, base: str, order: list[str], consumed: set[str], found: set[str]) -> None:
    """Make child links depth first from ``base``, adding the joint of each to ``found``."""
    linked = {base}
    stack: list[tuple[str, Iterator[str], set[str]]] = [(base, iter(order), set())]
    while stack:
        parent, joints, children = stack[-1]
        child, path = _next_child(scene, parent, joints, consumed)
        if not child:
            stack.pop()
            continue
        if child in children:
            continue  # "was skipped, since body1 is already defined as a child of body0"
        children.add(child)
        consumed.add(path)
        if child in linked:
            continue  # closes a loop: "will be now excluded from the articulation"
        linked.add(child)
        found.add(path)
        stack.append((child, iter(order), set()))


def _next_child(scene: _Scene, parent: str, joints: Iterator[str], consumed: set[str]) -> tuple[str, str]:
    """The next joint of ``parent`` (in stage order) that leads to a dynamic body, and that body."""
    for path in joints:
        joint = scene.joints[path]
        if path in consumed or joint.excluded or joint.distance:
            continue
        other = joint.body1 if parent == joint.body0 else joint.body0 if parent == joint.body1 else ""
        if other and other in scene.dynamic:
            return other, path
    return "", ""

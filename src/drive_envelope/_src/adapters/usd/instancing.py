"""Joints inside instanced prims: where an edit can go so that PhysX sees it.

Below an instanceable prim every prim is an *instance proxy*: USD composes it from a shared
prototype and ignores opinions authored on it (``ApplyAPI`` refuses them). An envelope for such a
joint has to go on the prototype's *source*, the prim the instance references:

* when the reference (or payload) points into the stage's own layer stack (an internal reference,
  ``references = </RobotPrototype>``, the usual way to clone one robot many times), the edit is an
  override on that source prim, a normal, non-instanced path of this stage; every instance that
  shares the prototype gets the envelope;
* when it points into another file (``references = @./ant.usda@</ant>``), no opinion in this
  stage's layers can reach inside the instance: the message names the file and the prim to apply
  the envelope to instead (or the instance to make non-instanceable).

PhysX itself does not simulate dynamic rigid bodies inside instances (omni.physx ``UsdLoad.cpp``:
"RigidBodyAPI on an instance proxy not supported"; ovphysx loads no DOF there): the envelope on the
source takes effect where the source is simulated without instancing (the referenced file on its
own, or the instances made non-instanceable, which real PhysX then reads on every clone).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    from pxr import Usd

_MAX_DEPTH = 16  # nested instancing levels followed before giving up


@dataclass(frozen=True, slots=True)
class EditSite:
    """Where to author an edit meant for a joint."""

    prim: Any
    """The prim to author on (``Usd.Prim``): the joint itself, or its prototype's source."""
    note: str | None = None
    """One line saying where the edit went when it is not the joint's own path."""


def _instance_of(prim: Usd.Prim) -> Usd.Prim:
    node = prim.GetParent()
    while not node.IsInstance():
        node = node.GetParent()
    return node


def _source_arcs(instance: Usd.Prim) -> tuple[Any | None, Any | None]:
    """The strongest reference/payload arc into the stage's own layer stack, and the strongest of any."""
    from pxr import Pcp, Usd

    arcs = Usd.PrimCompositionQuery(instance).GetCompositionArcs()
    own = arcs[0].GetTargetNode().layerStack.identifier  # the root arc: this stage's layer stack
    kinds = (Pcp.ArcTypeReference, Pcp.ArcTypePayload)
    candidates = [arc for arc in arcs[1:] if arc.GetArcType() in kinds]
    internal = next((arc for arc in candidates if arc.GetTargetNode().layerStack.identifier == own), None)
    return internal, candidates[0] if candidates else None


def edit_site(prim: Usd.Prim) -> EditSite:
    """The prim an edit for the joint ``prim`` must be authored on (see the module docstring).

    Raises:
        InputError: the joint is inside an instance of a prototype that comes from another file,
            naming that file and the prim there to edit.
    """
    if not prim.IsInstanceProxy():
        return EditSite(prim)
    stage, joint = prim.GetStage(), str(prim.GetPath())
    current = prim
    for _ in range(_MAX_DEPTH):
        if not current.IsInstanceProxy():
            return EditSite(
                current,
                f"joint {joint!r} is inside an instance: the envelope is authored on its prototype's "
                f"source {str(current.GetPath())!r} (every instance gets it); PhysX does not simulate "
                "bodies inside instances, so it uses it once the instances are made non-instanceable",
            )
        instance = _instance_of(current)
        relative = current.GetPath().MakeRelativePath(instance.GetPath())
        internal, strongest = _source_arcs(instance)
        if internal is None:
            raise _external(joint, instance, strongest, relative)
        current = stage.GetPrimAtPath(internal.GetTargetNode().path.AppendPath(relative))
        if not current.IsValid():
            break
    raise InputError(
        f"joint {joint!r}: inside an instance whose prototype source cannot be found on this stage"
    )


def _external(joint: str, instance: Usd.Prim, arc: Any, relative: Any) -> InputError:
    where = f"joint {joint!r} is inside instanceable prim {str(instance.GetPath())!r}"
    if arc is None:
        return InputError(
            f"{where}, whose prototype has no reference to edit; author instanceable = false on it"
        )
    source = str(arc.GetTargetNode().path.AppendPath(relative))
    layer = arc.GetTargetLayer()
    file = (layer.realPath or layer.identifier) if layer is not None else "the referenced file"
    return InputError(
        f"{where}, whose joints come from {source!r} in {file}: no opinion in this stage reaches inside "
        f"the instance; apply the envelope there (usd apply {file} --joint {source} ...) or author "
        f"instanceable = false on {str(instance.GetPath())!r}"
    )

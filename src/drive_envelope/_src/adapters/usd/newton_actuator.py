"""``DriveEnvelopeClampingAPI``: the envelope on Newton's ``NewtonActuator`` prims (pxr side).

Newton's actuator parser (``newton.actuators.parse_actuator_prim``) turns each applied API schema of
a ``NewtonActuator`` prim into a component and reads, for a schema USD knows, only that schema's
``newton:`` attributes; USD lists an applied API schema only once it is registered. So the envelope
is a codeless API schema shipped here (``newton_schema/``: ``plugInfo.json`` and
``generatedSchema.usda``, attributes ``newton:envelopeMaxEffort`` ...; the ``envelope`` prefix keeps
them apart from ``NewtonMaxEffortClampingAPI``'s ``newton:maxEffort`` on the same prim).

USD reads plugins into its schema registry once, at the first schema query: :func:`register_schema`
must run before that (``newton_usd_schemas`` registers itself on import for the same reason).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS
from drive_envelope._src.errors import InputError

ENVELOPE_CLAMPING_SCHEMA = "DriveEnvelopeClampingAPI"
SCHEMA_DIR = Path(__file__).resolve().parent / "newton_schema"
# USD attribute per spec field, in the newton: namespace (the one Newton's parser reads)
USD_ATTRIBUTES = {
    field: "newton:envelope" + "".join(word.capitalize() for word in field.split("_"))
    for field in ENVELOPE_FIELDS
}


def register_schema() -> None:
    """Register the codeless schema plugin with USD (idempotent).

    Raises:
        InputError: USD's schema registry was built before (register earlier).
    """
    from pxr import Plug, Usd

    # Newton's and PhysX's schemas must be in before the query below builds the registry (once per
    # process): a registry built here without PhysX's would make every envelope read as absent
    for module in ("newton_usd_schemas", "physx_usd_schemas"):
        try:
            __import__(module)
        except ImportError:
            pass
    Plug.Registry().RegisterPlugins([str(SCHEMA_DIR)])
    if Usd.SchemaRegistry().FindAppliedAPIPrimDefinition(ENVELOPE_CLAMPING_SCHEMA) is None:
        raise InputError(
            f"register_envelope_clamping: USD's schema registry was built before the "
            f"{ENVELOPE_CLAMPING_SCHEMA} plugin ({SCHEMA_DIR}) was registered; call "
            f"drive_envelope.isaaclab.register_envelope_clamping() before the first USD schema query "
            f"(before creating the simulation), or set PXR_PLUGINPATH_NAME={SCHEMA_DIR}"
        )


def apply_envelope_clamping(
    stage: Any,
    articulation_prim_path: str,
    values: Mapping[str, float],
    joint_names_expr: str | Sequence[str],
) -> list[str]:
    """Apply ``DriveEnvelopeClampingAPI`` with ``values`` to the matching ``NewtonActuator`` prims.

    Args:
        stage: The ``pxr.Usd.Stage``.
        articulation_prim_path: Root prim searched (inactive prims are skipped, as Newton skips them).
        values: The four spec fields as SI floats: ``max_effort`` [N*m or N],
            ``max_actuator_velocity`` [rad/s or m/s], ``velocity_dependent_resistance``
            [N*m*s/rad or N*s/m], ``speed_effort_gradient`` [(rad/s)/(N*m) or (m/s)/N].
        joint_names_expr: Regular expression(s) matched in full against the target joint's name.

    Returns:
        The paths of the prims authored, in stage order.

    Raises:
        InputError: bad expression, root not found, or no prim matched.
    """
    from pxr import Sdf, Usd

    patterns = [joint_names_expr] if isinstance(joint_names_expr, str) else list(joint_names_expr)
    try:
        compiled = [re.compile(p) for p in patterns]
    except (re.error, TypeError) as exc:
        raise InputError(f"author_envelope_clamping: joint_names_expr {joint_names_expr!r}: {exc}") from None
    root = stage.GetPrimAtPath(articulation_prim_path)
    if not root.IsValid():
        raise InputError(
            f"author_envelope_clamping: articulation_prim_path {articulation_prim_path!r}: no such prim"
        )
    authored: list[str] = []
    for prim in Usd.PrimRange(root):
        if prim.GetTypeName() != "NewtonActuator":
            continue
        targets = prim.GetRelationship("newton:targets")
        names = [str(t).rsplit("/", 1)[-1] for t in (targets.GetTargets() if targets else [])]
        # Newton uses the first target only
        if not names or not any(c.fullmatch(names[0]) for c in compiled):
            continue
        prim.AddAppliedSchema(ENVELOPE_CLAMPING_SCHEMA)
        for field, attribute in USD_ATTRIBUTES.items():
            prim.CreateAttribute(attribute, Sdf.ValueTypeNames.Float).Set(float(values[field]))
        authored.append(str(prim.GetPath()))
    if not authored:
        raise InputError(
            f"author_envelope_clamping: no active NewtonActuator prim under {articulation_prim_path!r} "
            f"targets a joint matching {patterns}; Isaac Lab authors them only with "
            f"SimulationCfg(use_newton_actuators=True) and one of its explicit cfgs (IdealPDActuatorCfg, "
            f"DCMotorCfg, ...) for those joints"
        )
    return authored

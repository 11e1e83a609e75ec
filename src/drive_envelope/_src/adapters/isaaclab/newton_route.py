"""Isaac Lab 3.0's Newton-actuator route: the envelope as a clamping stage of ``NewtonActuator`` prims.

With ``SimulationCfg(use_newton_actuators=True)`` (3.0's default) Isaac Lab does not run explicit
actuator models itself: ``define_actuator_properties`` authors a ``NewtonActuator`` prim per joint
from its own cfg types only (``IdealPDActuatorCfg`` -> ``NewtonPDControlAPI`` +
``NewtonMaxEffortClampingAPI``, ...; any other cfg, ours included, is refused by
``validate_newton_native_actuator_cfgs``), and Newton builds ``newton.actuators.Actuator`` objects
from those prims: ``ModelBuilder.add_usd`` on the Newton backend, Isaac Lab's
``NewtonActuatorAdapter.from_usd`` on PhysX/OVPhysX. Both parse a prim with
``newton.actuators.parse_actuator_prim``, which turns every applied API schema found in
``register_actuator_component``'s table into a component.

So the envelope rides on those prims: :func:`register_envelope_clamping` registers a codeless USD
API schema, ``DriveEnvelopeClampingAPI`` (``adapters/usd/newton_actuator.py`` and its
``newton_schema/``, attributes ``newton:envelopeMaxEffort`` ...), with USD and with Newton
(``adapters/newton/usd_clamping.py``) as a ``ComponentKind.CLAMPING`` whose class is
``ClampingPerformanceEnvelope``; :func:`author_envelope_clamping` applies it to the prims
Isaac Lab authored, after spawning and before the stage is read. Newton reads only a registered
schema's own attributes, and USD lists an applied API schema only once it is registered; hence the
codeless schema rather than bare attributes (the other schemas' ``newton:kp`` ... would reach the
clamp otherwise, and an unregistered schema name is dropped by ``GetAppliedSchemas``).

USD builds its schema registry once, on first use: the plugin must be registered before that, as
``newton_usd_schemas`` does on import. Importing ``drive_envelope.isaaclab`` does not import pxr,
so call :func:`register_envelope_clamping` early (before a stage is created); when USD's registry
was built first, it raises a one-line ``InputError`` saying so.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from typing import Any

from drive_envelope._src.adapters.newton.clamp import resolve_envelope_arguments
from drive_envelope._src.adapters.newton.usd_clamping import register_clamping_component
from drive_envelope._src.adapters.usd.newton_actuator import (
    ENVELOPE_CLAMPING_SCHEMA,
    apply_envelope_clamping,
    register_schema,
)
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError


@functools.cache
def register_envelope_clamping() -> type:
    """Register ``DriveEnvelopeClampingAPI`` with USD and with Newton's actuator parser (once).

    Returns:
        The clamping class Newton builds for the schema: a ``ClampingPerformanceEnvelope`` that
        also takes the parsed USD keys (``envelope_max_effort`` ...).

    Raises:
        InputError: USD's schema registry was built before this call (register earlier).
    """
    component = register_clamping_component(ENVELOPE_CLAMPING_SCHEMA)  # imports newton and its schemas
    register_schema()
    return component


def _envelope_values(envelope: PerformanceEnvelope | Mapping[str, Any]) -> dict[str, float]:
    """The four SI floats of ``envelope`` (a ``PerformanceEnvelope`` or a dict of spec names)."""
    if isinstance(envelope, PerformanceEnvelope):
        return {field: float(getattr(envelope, field)) for field in ENVELOPE_FIELDS}
    if not isinstance(envelope, Mapping):
        raise InputError(
            f"author_envelope_clamping: envelope: expected a PerformanceEnvelope or a dict of "
            f"{', '.join(ENVELOPE_FIELDS)}, got {type(envelope).__name__}"
        )
    try:
        return resolve_envelope_arguments(dict(envelope))
    except InputError as exc:
        raise InputError(f"author_envelope_clamping: envelope: {exc}") from None


def author_envelope_clamping(
    stage: Any,
    articulation_prim_path: str,
    envelope: PerformanceEnvelope | Mapping[str, Any],
    *,
    joint_names_expr: str | Sequence[str] = ".*",
) -> list[str]:
    """Apply the envelope as a clamping stage to the ``NewtonActuator`` prims of some joints.

    Call it after Isaac Lab spawned the articulation (``Articulation(cfg)`` or the scene's spawn,
    which authors the prims from an ``IdealPDActuatorCfg`` / ``DCMotorCfg`` ...) and before the
    stage is cloned and read (``replicate``, ``sim.reset``). The stage applies after the prim's
    other clamping stages (innermost first).

    Args:
        stage: The USD stage (``pxr.Usd.Stage``).
        articulation_prim_path: Root prim of the articulation whose actuators get the stage
            (e.g. ``"/World/Env_0/Robot"``); prims are found under it.
        envelope: A ``PerformanceEnvelope`` or a dict of ``max_effort`` [N*m or N],
            ``max_actuator_velocity`` [rad/s or m/s], ``velocity_dependent_resistance``
            [N*m*s/rad or N*s/m], ``speed_effort_gradient`` [(rad/s)/(N*m) or (m/s)/N] (SI
            numbers or strings with units).
        joint_names_expr: Regular expression(s), matched in full against the target joint's name.

    Returns:
        The paths of the prims authored, in stage order.

    Raises:
        InputError: bad envelope, root not found, or no active ``NewtonActuator`` prim under it
            targets a matching joint (Isaac Lab authors them only with
            ``use_newton_actuators=True`` and one of its own explicit cfgs for those joints).
    """
    values = _envelope_values(envelope)
    register_envelope_clamping()
    return apply_envelope_clamping(stage, articulation_prim_path, values, joint_names_expr)


@functools.cache
def build_articulation_cfg() -> type:
    """Import Isaac Lab, register the schema and define ``PerformanceEnvelopeArticulationCfg`` (once)."""
    from isaaclab.assets import ArticulationCfg
    from isaaclab.utils import configclass

    register_envelope_clamping()  # now: the cfg is made before the scene's stage, the schema must be too

    @configclass
    class PerformanceEnvelopeArticulationCfg(ArticulationCfg):  # type: ignore[misc,valid-type]
        """``ArticulationCfg`` whose Newton actuators get the envelope as a clamping stage.

        For ``SimulationCfg(use_newton_actuators=True)``: give the groups Isaac Lab's own explicit
        cfgs (``IdealPDActuatorCfg`` ...) in ``actuators`` and their envelopes in
        ``envelope_clamping``; after Isaac Lab authored the group's ``NewtonActuator`` prims at
        spawn (``_post_spawn``, Isaac Lab's hook for assets that author more USD schemas),
        :func:`author_envelope_clamping` adds ``DriveEnvelopeClampingAPI`` to them, so clones and
        every backend's Newton actuators carry it.
        """

        envelope_clamping: dict[str, Any] = {}  # noqa: RUF012  (configclass copies mutable defaults per instance)
        """Envelope per actuator group name (a key of ``actuators``): a ``PerformanceEnvelope`` or a
        dict of ``max_effort`` [N*m or N], ``max_actuator_velocity`` [rad/s or m/s],
        ``velocity_dependent_resistance`` [N*m*s/rad or N*s/m], ``speed_effort_gradient``
        [(rad/s)/(N*m) or (m/s)/N]."""

        def _post_spawn(self, stage: Any) -> None:
            """Author Isaac Lab's ``NewtonActuator`` prims, then the envelope on the groups named."""
            # explicit base call: configclass may rebuild the class, which breaks zero-argument super()
            ArticulationCfg._post_spawn(self, stage)
            if not self.envelope_clamping:
                return
            _author_groups(self, stage)

    PerformanceEnvelopeArticulationCfg.__module__ = "drive_envelope.isaaclab"
    return PerformanceEnvelopeArticulationCfg


def _author_groups(cfg: Any, stage: Any) -> None:
    """Apply ``cfg.envelope_clamping`` to the spawned articulation(s), with one-line errors."""
    from isaaclab.sim import SimulationContext
    from isaaclab.sim.utils.queries import find_matching_prims

    where = "PerformanceEnvelopeArticulationCfg.envelope_clamping"
    actuators = cfg.actuators if isinstance(cfg.actuators, Mapping) else {}
    for group in cfg.envelope_clamping:
        if group not in actuators:
            raise InputError(
                f"{where}: group {group!r} is not a key of actuators (expected one of {sorted(actuators)})"
            )
    context = SimulationContext.instance()
    if context is None or not context.cfg.use_newton_actuators:
        raise InputError(
            f"{where}: needs SimulationCfg(use_newton_actuators=True) (Newton's actuators run the "
            f"clamping stage); with use_newton_actuators=False use PerformanceEnvelopeActuatorCfg"
        )
    path = (
        cfg.spawn.spawn_path if cfg.spawn is not None and cfg.spawn.spawn_path is not None else cfg.prim_path
    )
    for prim in find_matching_prims(path, stage):
        for group, envelope in cfg.envelope_clamping.items():
            try:
                author_envelope_clamping(
                    stage, str(prim.GetPath()), envelope, joint_names_expr=actuators[group].joint_names_expr
                )
            except InputError as exc:
                raise InputError(f"{where}[{group!r}]: {exc}") from None

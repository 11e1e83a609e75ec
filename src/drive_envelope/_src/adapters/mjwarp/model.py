"""``put_model`` for MJWarp: a model with ``drive_envelope.envelope`` actuators, on the device.

MJWarp 4.0's ``put_model`` refuses actuator plugins (``NotImplementedError: Actuator plugins not
supported``), and a model that still has any non-geom plugin instance fails even after its
``actuator_plugin`` is cleared: ``Model.plugin`` keeps only geom plugins but its array is sized by
``MjModel.nplugin`` (``RuntimeError: Failed to reshape the input data to the given shape (1,)``).
A compiled ``MjModel`` cannot lose a plugin instance, so the model is rebuilt from its spec: a copy
whose drive actuators are the same actuators without the plugin (same names, order, controls,
groups, delays and ``dynprm``: MJWarp computes them as ``general`` actuators) and whose
``drive_envelope.envelope`` instances are deleted. Its compiled twin goes to ``mujoco_warp.put_model``
and :class:`.drives.EnvelopeDrives`, installed as ``Model.callback.act_bias``, overwrites those
actuators' forces with the plugin's law every step.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.mjwarp.structure import DriveSpec, DriveTable, plugin_drive_specs
from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco_warp

    from drive_envelope._src.adapters.mjwarp.drives import EnvelopeDrives

_WHERE = "drive_envelope.mjwarp.put_model"


def _is_spec(value: object) -> bool:
    return hasattr(value, "compile") and hasattr(value, "actuators") and hasattr(value, "plugins")


def _is_model(value: object) -> bool:
    return hasattr(value, "actuator_plugin") and hasattr(value, "nu")


def spec_without_plugin(spec: Any) -> Any:
    """A copy of ``spec`` whose ``drive_envelope.envelope`` actuators are plain actuators.

    Each drive actuator keeps its name, place, joint, control, group, delay and ``dynprm``; the
    plugin's instances (explicit ``<instance>`` and per-actuator) are deleted. Other plugins stay.
    """
    from drive_envelope._src.adapters.mujoco.existing import is_drive

    copy = spec.copy()
    names, ids = set(), set()
    for actuator in copy.actuators:
        if not is_drive(copy, actuator):
            continue
        if actuator.plugin.name:
            names.add(actuator.plugin.name)
        else:
            ids.add(int(actuator.plugin.id))
        actuator.plugin.active = False
    for plugin in list(copy.plugins):
        if (plugin.name and plugin.name in names) or (not plugin.name and int(plugin.id) in ids):
            copy.delete(plugin)
    return copy


def _source_spec(model: Any) -> Any:
    """The MjSpec to rebuild from: ``model`` itself (an MjSpec) or an MJCF file parsed."""
    from drive_envelope._src.adapters.mujoco.mjcf import load_spec

    if _is_spec(model):
        return model
    if isinstance(model, (str, os.PathLike)):
        return load_spec(model)
    raise InputError(
        f"{_WHERE}: argument 'model': expected a mujoco.MjSpec, an MJCF path or a mujoco.MjModel, "
        f"got {type(model).__name__}"
    )


def _compile(spec: Any, what: str) -> Any:
    from drive_envelope._src.adapters.mujoco.mjcf import mujoco_warnings

    try:
        with mujoco_warnings():
            return spec.compile()
    except ValueError as exc:
        raise InputError(f"{_WHERE}: {what} does not compile: {' '.join(str(exc).split())}") from None


def put_model(model: Any, *, batch_sizes: dict[str, int] | None = None) -> mujoco_warp.Model:
    """``mujoco_warp.put_model`` for models with ``drive_envelope.envelope`` actuators.

    Args:
        model: A ``mujoco.MjSpec`` (not modified) or an MJCF file with the plugin's drives (the
            same MJCF that runs in C MuJoCo), or a compiled ``mujoco.MjModel`` without them (passed
            on unchanged). A compiled model with plugin drives cannot be rebuilt: pass its spec.
        batch_sizes: MJWarp's per-world batch sizes of model fields, e.g.
            ``{"actuator_dynprm": nworld}`` for a different envelope in each world.

    Returns:
        The MJWarp model; its ``callback.act_bias`` is the drives' :class:`EnvelopeDrives`, whose
        ``mj_model`` is the compiled plugin-free twin (same sizes as the original model, so
        ``mujoco_warp.make_data``/``put_data`` take either).

    Raises:
        InputError: an unreadable file, a model that does not compile, a bad drive, or an
            ``MjModel`` with plugin drives.
        PluginError: the plugin is not built (it is needed to read the drives).
    """
    import mujoco_warp

    if _is_model(model):
        if (model.actuator_plugin >= 0).any():
            raise InputError(
                f"{_WHERE}: argument 'model': a compiled MjModel with plugin actuators cannot go to MJWarp "
                "(its put_model rejects any plugin instance; docs/mjwarp.md): pass the mujoco.MjSpec or "
                "the MJCF file it was compiled from"
            )
        return mujoco_warp.put_model(model, batch_sizes=batch_sizes)
    from drive_envelope._src.adapters.mujoco.loader import load_plugin

    spec = _source_spec(model)
    load_plugin()
    original = _compile(spec, "the model")
    specs = plugin_drive_specs(original)
    DriveTable.build(original, specs)  # a bad drive fails here, before the copy is compiled
    twin = _compile(spec_without_plugin(spec), "the model without its plugin actuators")
    try:
        device_model = mujoco_warp.put_model(twin, batch_sizes=batch_sizes)
    except (NotImplementedError, ValueError) as exc:
        raise InputError(f"{_WHERE}: MJWarp cannot take the model: {' '.join(str(exc).split())}") from None
    _install(device_model, twin, specs)
    return device_model


def attach(
    model: mujoco_warp.Model,
    mj_model: Any,
    actuators: Sequence[int | str],
    *,
    acceleration: bool = False,
) -> EnvelopeDrives:
    """Drive joints of a plugin-free model with the envelope: a ``pos`` input per drive.

    For models built without the plugin (e.g. by mjlab, whose MuJoCo cannot load it): each named
    actuator (one control, joint transmission, gear 1, no forcerange) becomes a drive whose
    control is its position target and whose ``actuator_dynprm`` holds the six numbers (the
    plugin's layout). Its native force is overwritten, so give it no velocity-dependent gain or
    bias (a ``motor``), or an implicit integrator would integrate that too.

    Args:
        model: The MJWarp model of ``mj_model`` (its ``callback.act_bias`` is set).
        mj_model: The compiled ``mujoco.MjModel`` it was put from.
        actuators: Names or ids of the drives' actuators.
        acceleration: Gains per unit inertia (``acceleration`` drives) instead of ``force``.

    Returns:
        The installed callback; a model that has one already gets one for its drives and these.

    Raises:
        InputError: an unknown actuator, one that cannot feed a drive, or two on one joint.
    """
    ids = []
    for actuator in actuators:
        if isinstance(actuator, str):
            try:
                ids.append(int(mj_model.actuator(actuator).id))
            except KeyError:
                raise InputError(
                    f"attach: argument 'actuators': the model has no actuator {actuator!r}"
                ) from None
        else:
            ids.append(int(actuator))
    specs = [DriveSpec(actuator=i, inputs=(i, -1, -1), acceleration=acceleration) for i in ids]
    current = getattr(model.callback, "act_bias", None)
    if current is not None and hasattr(current, "specs"):
        model.callback.act_bias = None  # one solve couples every drive: extend the installed set
        specs = [*current.specs, *specs]
    return _install(model, mj_model, specs)


def _install(model: mujoco_warp.Model, mj_model: Any, specs: Sequence[DriveSpec]) -> EnvelopeDrives:
    from drive_envelope._src.adapters.mjwarp.drives import EnvelopeDrives

    if model.callback.act_bias is not None:
        raise InputError(f"{_WHERE}: the MJWarp model already has an act_bias callback; wrap it in yours")
    drives = EnvelopeDrives(DriveTable.build(mj_model, specs), mj_model, model, specs=tuple(specs))
    model.callback.act_bias = drives
    return drives


def envelope_drives(model: Any, where: str = "drive_envelope.mjwarp") -> EnvelopeDrives:
    """The :class:`EnvelopeDrives` installed on an MJWarp model (by :func:`put_model` or :func:`attach`)."""
    from drive_envelope._src.adapters.mjwarp.drives import EnvelopeDrives

    callback = getattr(getattr(model, "callback", None), "act_bias", None)
    if not isinstance(callback, EnvelopeDrives):
        raise InputError(
            f"{where}: argument 'm': the MJWarp model has no envelope drives "
            "(build it with drive_envelope.mjwarp.put_model or attach)"
        )
    return callback

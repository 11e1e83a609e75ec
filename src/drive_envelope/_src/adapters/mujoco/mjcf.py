"""Equip an MJCF robot with envelope drives, and list a model's drives (``drive-envelope mujoco``).

``apply`` reads the robot with ``mujoco.MjSpec``, gives each chosen joint a drive through
:func:`~drive_envelope._src.adapters.mujoco.spec.add_drive` with ``replace=True`` (the joint's
actuator becomes the drive in place: same name, same ``data.ctrl`` slot, keyframes kept), and
writes a new MJCF that loads in stock MuJoCo once the plugin library is loaded. The gains come
from the replaced actuator unless given: ``position`` and ``general`` PD actuators give kp and kv
(their control stays a target position), ``velocity`` actuators kv (a target velocity); a
``motor`` has none, so its joint needs ``stiffness`` and ``damping``.

MuJoCo's MJCF writer keeps 6 significant digits unless told otherwise and drops comments and
``<include>`` structure; here it writes every digit (:func:`write_mjcf`), and asset folders are
re-pointed relative to the output file. The file is compiled from its final folder before it replaces
anything.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from drive_envelope._src.adapters.mujoco.existing import (
    PLUGIN_NAME,
    describe_kind,
    feed_forward_motor,
    joint_actuators,
    primary_actuator,
)
from drive_envelope._src.adapters.mujoco.ratings import Rating, joint_ratings
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.io.paths import input_file

if TYPE_CHECKING:
    import mujoco


@dataclass(frozen=True, kw_only=True, slots=True)
class Assignment:
    """One joint to drive, with its envelope and where that came from (for messages)."""

    joint: str
    """Joint name (hinge or slide)."""
    envelope: PerformanceEnvelope
    """Its envelope (SI)."""
    where: str = ""
    """The map key or flag the envelope came from."""


@dataclass(frozen=True, kw_only=True, slots=True)
class EquippedJoint:
    """What :func:`apply_drives` did to one joint."""

    joint: str
    """The joint."""
    drive: str
    """Name of the drive's effort actuator."""
    inputs: tuple[str, ...]
    """The drive's control inputs."""
    envelope: PerformanceEnvelope
    """The envelope written (SI)."""
    stiffness: float
    """Drive stiffness [N*m/rad or N/m]."""
    damping: float
    """Drive damping [N*m*s/rad or N*s/m]."""
    replaced: str
    """What it replaced, e.g. ``"position 'actuator1'"``, or ``""``."""
    gains_from: str
    """Where the gains came from: the replaced actuator, or the arguments."""
    kept_gain: str | None = None
    """``"stiffness"`` or ``"damping"``: the gain kept from the replaced actuator beside one given."""
    where: str = ""
    """The map key or flag the envelope came from (reports group joints by it)."""
    rating: Rating | None = None
    """The model's own effort rating of the joint before the edit
    (:mod:`~drive_envelope._src.adapters.mujoco.ratings`); None if the model did not compile."""


def load_spec(path: str | os.PathLike[str]) -> mujoco.MjSpec:
    """Parse an MJCF file into an ``MjSpec``.

    Raises:
        InputError: no such file, or MuJoCo cannot parse it (its message, on one line).
    """
    import mujoco

    name = os.fspath(path)
    input_file(name, what="MJCF file")  # a FIFO or /dev/zero would block or fill the memory
    try:
        return mujoco.MjSpec.from_file(name)
    except ValueError as exc:
        raise InputError(f"{name}: MuJoCo cannot read it: {' '.join(str(exc).split())}") from None


@contextlib.contextmanager
def mujoco_warnings(handler: Callable[[str], None] | None = None) -> Iterator[None]:
    """Turn MuJoCo's warnings (``mju_warning``, e.g. the plugin's) into Python warnings meanwhile.

    MuJoCo prints them on stdout; the command line prints Python warnings as one stderr line each.
    A ``handler`` takes each message instead (``lambda message: None`` drops them).
    """
    import mujoco

    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(
        handler or (lambda message: warnings.warn(" ".join(str(message).split()), stacklevel=2))
    )
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)


def model_poses(model: Any) -> Iterator[tuple[int, Any]]:
    """``(key, data)`` at ``qpos0`` (key -1) and at each keyframe, after ``mj_fwdPosition``.

    The checks that read what the model does in its own poses (transmissions, contacts) share it;
    MuJoCo's warnings are dropped meanwhile (the plugin's were given when the model compiled).
    """
    import mujoco

    with warnings.catch_warnings(), mujoco_warnings():
        warnings.simplefilter("ignore")
        data = mujoco.MjData(model)
        for key in range(-1, model.nkey):
            if key >= 0:
                mujoco.mj_resetDataKeyframe(model, data, key)
            mujoco.mj_fwdPosition(model, data)
            yield key, data


def _load_plugin_if_used(text: str) -> None:
    """Load the plugin; a model that does not use it compiles without it."""
    from drive_envelope._src.adapters.mujoco.build import PluginError
    from drive_envelope._src.adapters.mujoco.loader import load_plugin

    try:
        load_plugin()
    except PluginError:
        if PLUGIN_NAME in text:
            raise


def read_model(path: str | os.PathLike[str]) -> mujoco.MjModel:
    """Compile an MJCF file (loading the plugin if it uses it).

    Raises:
        InputError: the file cannot be read or compiled (MuJoCo's or the plugin's message).
        PluginError: the model uses the plugin and it is not built.
    """
    import mujoco

    name = os.fspath(path)
    input_file(name, what="MJCF file")  # a FIFO or /dev/zero would block or fill the memory
    _load_plugin_if_used(Path(name).read_text(encoding="utf-8", errors="replace"))
    try:
        with mujoco_warnings():
            return mujoco.MjModel.from_xml_path(name)
    except ValueError as exc:
        raise InputError(f"{name}: MuJoCo cannot compile it: {' '.join(str(exc).split())}") from None


def uses_plugin(model: mujoco.MjModel) -> bool:
    """Whether a compiled model has instances of the plugin (False if it was never loaded)."""
    from drive_envelope._src.adapters.mujoco.build import PluginError
    from drive_envelope._src.adapters.mujoco.loader import plugin_slot

    if not model.nplugin:
        return False
    try:
        slot = plugin_slot()
    except PluginError:
        return False  # a model using it would not have compiled
    return any(int(p) == slot for p in model.plugin)


def driven_joints(spec: mujoco.MjSpec) -> list[str]:
    """Names of the spec's hinge and slide joints (the joints a drive can take), in model order."""
    import mujoco

    kinds = (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
    return [joint.name for joint in spec.joints if joint.type in kinds and joint.name]


def _inputs_of_instance(spec: mujoco.MjSpec, instance: str) -> tuple[str, ...]:
    for plugin in spec.plugins:
        if plugin.name == instance:
            words = str(dict(plugin.config).get("input", "pos")).replace(",", " ").split()
            return tuple(name for name in ("pos", "vel", "ff") if name in words) or ("pos",)
    return ("pos",)


def apply_drives(
    spec: mujoco.MjSpec,
    assignments: Sequence[Assignment],
    *,
    stiffness: float | str | None = None,
    damping: float | str | None = None,
) -> list[EquippedJoint]:
    """Give each assigned joint a drive, replacing its actuators (see the module docstring).

    Args:
        spec: The robot, edited in place (callers write nothing on an error).
        assignments: Joints and envelopes.
        stiffness: Drive stiffness for every joint [N*m/rad or N/m]; None keeps each replaced
            actuator's kp.
        damping: Drive damping for every joint [N*m*s/rad or N*s/m]; None keeps each kv.

    Raises:
        InputError: an unknown joint, a joint whose actuator has no gains when none are given, or
            anything :func:`add_drive` refuses, naming the joint.
    """
    from drive_envelope._src.adapters.mujoco.spec import add_drive, compile_copy

    joints = driven_joints(spec)
    for item in assignments:
        if item.joint not in joints:
            raise InputError(
                f"{item.where or item.joint}: the model has no hinge or slide joint named "
                f"{item.joint!r}{_nearest_joints(item.joint, joints)}"
            )
    # the flags' gains are checked once, naming the flag: a map key would send the user to the map
    gains = {
        kind: _flag_gains(stiffness, damping, kind) for kind in {item.envelope.joint for item in assignments}
    }
    # the gains, control ranges and ratings MuJoCo compiles (dampratio, inheritrange, classes)
    with warnings.catch_warnings(), mujoco_warnings():
        warnings.simplefilter("ignore")  # the result's compile gives the warnings that matter
        before = compile_copy(spec)  # None: the spec's own numbers are read
    ratings = joint_ratings(before, [item.joint for item in assignments]) if before is not None else {}
    done = []
    for item in assignments:
        existing = joint_actuators(spec, item.joint, before)
        first = primary_actuator(existing) if existing else None
        inputs: tuple[str, ...] = ("pos",)
        if first is not None and first.kind == "velocity":
            inputs = ("vel",)
        elif first is not None and first.kind == "drive":
            actuator: Any = spec.actuators[first.index]
            inputs = _inputs_of_instance(spec, actuator.plugin.name)
        if first is not None and feed_forward_motor(existing, first) is not None:
            inputs += ("ff",)  # the motor beside it keeps its slot as the drive's feed-forward
        given_k, given_c = gains[item.envelope.joint]
        k = given_k if given_k is not None else (first.stiffness if first else None)
        c = given_c if given_c is not None else (first.damping if first else None)
        if k is None or c is None:
            what = (
                f"its actuator {first.name!r} is {describe_kind(first.kind)}"
                if first
                else "it has no actuator"
            )
            missing = [flag for flag, value in (("--stiffness", k), ("--damping", c)) if value is None]
            flags = [f for f, v in (("--stiffness", stiffness), ("--damping", damping)) if v is not None]
            ask = " and ".join(missing) + (f" too ({flags[0]} is given)" if flags else "")
            raise InputError(
                f"{item.where or item.joint}: joint {item.joint!r}: {what} (no position gains to keep); "
                f"give {ask}"
            )
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                drive = add_drive(
                    spec,
                    item.joint,
                    envelope=item.envelope,
                    stiffness=k,
                    damping=c,
                    inputs=inputs,
                    effort_sensor=False,
                    replace=True,
                )
        except InputError as exc:
            raise _at(item, exc) from None
        for warning in caught:  # add_drive's own said with the map key (or flag) in front, as errors are
            message = str(warning.message)
            if message.startswith("add_drive("):
                message = str(_at(item, InputError(message)))
            warnings.warn(message, stacklevel=2)
        source = f"{first.kind} {first.name!r}" if first else "given"
        kept_gain = None
        if stiffness is not None and damping is not None:
            source = "given"
        elif first is not None and (stiffness is not None or damping is not None):  # one kept: say which
            kept_gain = "damping" if stiffness is not None else "stiffness"
            source = f"{'stiffness' if stiffness is not None else 'damping'} given, the other from {source}"
        done.append(
            EquippedJoint(
                joint=item.joint,
                drive=drive.name,
                inputs=drive.inputs,
                envelope=item.envelope,
                stiffness=drive.stiffness,
                damping=drive.damping,
                replaced=f"{first.kind} {first.name!r}" if first else "",
                gains_from=source,
                kept_gain=kept_gain,
                where=item.where or item.joint,
                rating=ratings.get(item.joint),
            )
        )
    return done


def _flag_gains(
    stiffness: float | str | None, damping: float | str | None, joint: str
) -> tuple[float | None, float | None]:
    """``--stiffness`` and ``--damping`` in SI for a ``joint`` joint (None where not given).

    Raises:
        InputError: a value that is not a number with a gain's unit, or outside [0, 1e12], naming
            the flag and the value as given.
    """
    from drive_envelope._src.adapters.mujoco.params import gain_units
    from drive_envelope._src.values import read_quantity

    gains: list[float | None] = []
    for flag, value, unit in zip(
        ("--stiffness", "--damping"), (stiffness, damping), gain_units(joint, "force"), strict=True
    ):
        if value is None:
            gains.append(None)
            continue
        number = read_quantity(value, unit, f"{flag} {value!r}")
        if not (math.isfinite(number) and 0.0 <= number <= 1e12):
            why = " (a drive gain is never negative)" if number < 0 else ""
            raise InputError(
                f"{flag} {value!r}: expected a number in [0, 1e12] [{unit}]{why}, got {number!r}"
            )
        gains.append(number)
    return gains[0], gains[1]


def _nearest_joints(name: str, joints: Sequence[str]) -> str:
    """`` (did you mean 'a', 'b'?)``: joints containing ``name`` (any case), else difflib's closest."""
    import difflib

    lowered = name.lower()
    close = [j for j in joints if lowered and lowered in j.lower()][:3]
    close = close or difflib.get_close_matches(name, list(joints), n=3, cutoff=0.5)
    return f" (did you mean {', '.join(repr(j) for j in close)}?)" if close else ""


def _at(item: Assignment, exc: InputError) -> InputError:
    """``exc`` with the map key (or flag) of ``item`` in front, instead of the ``add_drive(...)`` call."""
    from drive_envelope._src.validation import keyed_error

    message = str(exc).removeprefix(f"add_drive(joint={item.joint!r}): ")
    if message != str(exc):
        message = f"joint {item.joint!r}: {message}"
    return keyed_error(item.where, InputError(message))


def _exact_dynprm(xml: str, spec: mujoco.MjSpec) -> str:
    """MuJoCo writes numbers with 6 digits: put every digit back into the drives' ``dynprm``."""
    from drive_envelope._src.adapters.mujoco.existing import is_drive

    exact = {}
    for actuator in spec.actuators:
        if actuator.name and is_drive(spec, actuator):
            values = [float(v) for v in actuator.dynprm]
            while len(values) > 1 and values[-1] == 0.0:
                values.pop()
            exact[actuator.name] = " ".join(repr(v) if v != int(v) else str(int(v)) for v in values)

    def fix(match: re.Match[str]) -> str:
        tag = match.group(0)
        name = re.search(r'\bname="([^"]*)"', tag)
        if not name or name.group(1) not in exact:
            return tag
        text = f'dynprm="{exact[name.group(1)]}"'
        if re.search(r'\bdynprm="[^"]*"', tag):
            return re.sub(r'\bdynprm="[^"]*"', text, tag)
        return tag.replace("<plugin ", f"<plugin {text} ", 1)

    # only inside <actuator>: sensors may be named like actuators
    def section(match: re.Match[str]) -> str:
        return re.sub(r"<plugin\b[^>]*>", fix, match.group(0))

    return re.sub(r"<actuator>.*?</actuator>", section, xml, flags=re.DOTALL)


def _repoint_assets(xml: str, spec: mujoco.MjSpec, source: Path, output: Path) -> str:
    """Point relative asset folders (meshdir, texturedir) at the same files from ``output``'s folder."""
    here, there = source.resolve().parent, output.resolve().parent
    files = [
        a.file for group in (spec.meshes, spec.textures, spec.hfields, spec.skins) for a in group if a.file
    ]
    if here == there or not files:
        return xml
    for attribute in ("meshdir", "texturedir"):
        folder = str(getattr(spec, attribute) or "")
        if os.path.isabs(folder):
            continue
        value = os.path.relpath(here / folder, there)
        pattern = rf'(<compiler\b[^>]*?)\s{attribute}="[^"]*"'
        xml = re.sub(pattern, r"\1", xml, count=1)
        if "<compiler" in xml:
            xml = xml.replace("<compiler", f'<compiler {attribute}="{value}"', 1)
        else:
            xml = re.sub(r"(<mujoco\b[^>]*>)", rf'\1\n  <compiler {attribute}="{value}"/>', xml, count=1)
    return xml


def write_mjcf(
    spec: mujoco.MjSpec,
    output: str | os.PathLike[str],
    *,
    source: str | os.PathLike[str] | None = None,
    force: bool = False,
) -> mujoco.MjModel:
    """Write ``spec`` as MJCF to ``output`` atomically, after compiling it from there.

    Unlike ``spec.to_xml()`` alone (6 significant digits), every number keeps every digit: MuJoCo's
    writer is switched to 17 digits meanwhile and each number is written as its shortest exact text
    (:mod:`~drive_envelope._src.adapters.mujoco.precision`); the drives' ``dynprm`` are rewritten
    exactly in any case. The written file is compiled and compared with the model compiled in
    memory: a relative difference above 1e-9 in any number (a MuJoCo without the precision entry
    point) is a warning naming the worst one. The file is known to load before it replaces anything.

    Args:
        spec: The robot (with its drives).
        output: The ``.xml`` file to write.
        source: The MJCF file ``spec`` was read from: relative asset folders (meshdir, texturedir)
            are re-pointed to reach the same files from ``output``'s folder. None: no re-pointing.
        force: Replace a read-only output.

    Returns:
        The model compiled from the written file.

    Raises:
        InputError: ``output`` is not an ``.xml`` file name, the result does not compile (nothing is
            written), or the file cannot be written.
    """
    import mujoco

    if Path(output).suffix.lower() != ".xml":
        raise InputError(f"write_mjcf: output {os.fspath(output)!r}: expected an .xml file name (MJCF)")
    from drive_envelope._src.adapters.mujoco.precision import (
        LOSS_TOLERANCE,
        full_precision,
        precision_loss,
        shortest_numbers,
    )
    from drive_envelope._src.io.atomic import atomic_path

    try:
        with warnings.catch_warnings(), mujoco_warnings():
            warnings.simplefilter("ignore")  # the compiled file gives the plugin's warnings below
            reference = spec.compile()
            with full_precision() as exact:
                xml = spec.to_xml()
    except ValueError as exc:
        where = os.fspath(source if source is not None else output)
        raise InputError(f"{where}: MuJoCo cannot write the result: {' '.join(str(exc).split())}") from None
    xml = _exact_dynprm(shortest_numbers(xml) if exact else xml, spec)
    if source is not None:
        xml = _repoint_assets(xml, spec, Path(source), Path(output))
    with atomic_path(output, force=force) as tmp:
        tmp.write_text(xml, encoding="utf-8")
        try:
            with mujoco_warnings():
                model = mujoco.MjModel.from_xml_path(str(tmp))
        except ValueError as exc:
            raise InputError(
                f"{os.fspath(output)}: the result does not load in MuJoCo, nothing written: "
                f"{' '.join(str(exc).split())}"
            ) from None
    loss, where = precision_loss(reference, model)
    if loss > LOSS_TOLERANCE:
        warnings.warn(
            f"{os.fspath(output)}: MuJoCo's MJCF writer kept fewer digits than the model had: its "
            f"numbers differ by up to {loss:.2g} relative (e.g. {where}); the drives' numbers are exact",
            stacklevel=2,
        )
    return model

"""Finding and loading the built plugin library into the running MuJoCo (idempotent).

The library is looked up at ``$DRIVE_ENVELOPE_MUJOCO_PLUGIN`` (a file) or in the default build
directory (``plugin/mujoco/build`` in a checkout, else the cache folder of this MuJoCo version and
environment: :func:`~drive_envelope._src.adapters.mujoco.build.default_build_dir`), where
``drive-envelope mujoco build-plugin`` puts it. Before it is loaded, the MuJoCo version recorded at build time
is compared with the installed one: a stale build gives a :class:`PluginError` naming the command
to run, never a crash from reading another version's ``mjModel`` layout.
"""

from __future__ import annotations

import ctypes
import json
import os
import threading
from pathlib import Path

from drive_envelope._src.adapters.mujoco.build import (
    BUILD_COMMAND,
    BUILD_INFO,
    PluginError,
    default_build_dir,
    library_name,
)

PLUGIN_NAME = "drive_envelope.envelope"
"""Name the plugin registers under (``<plugin plugin="drive_envelope.envelope">``)."""
ENV_VAR = "DRIVE_ENVELOPE_MUJOCO_PLUGIN"
"""Environment variable that may name the plugin library file explicitly."""

_LOCK = threading.Lock()
_LOADED: dict[str, ctypes.CDLL] = {}
_SLOT: list[int] = []  # MuJoCo's registry slot of the plugin, once loaded

_PROBE = """<mujoco><extension><plugin plugin="drive_envelope.envelope"/></extension>
<worldbody><body><joint name="j"/><geom size="0.1"/></body></worldbody>
<actuator><plugin joint="j" plugin="drive_envelope.envelope" dynprm="1 -1 0 0 0 0"/></actuator></mujoco>"""


def plugin_library_path() -> Path:
    """Path of the plugin library that :func:`load_plugin` would load (it may not exist yet)."""
    override = os.environ.get(ENV_VAR, "").strip()
    if override:
        return Path(override)
    return default_build_dir() / library_name()


def _check_build_info(library: Path, installed: str) -> None:
    info_file = library.parent / BUILD_INFO
    try:
        info = json.loads(info_file.read_text(encoding="utf-8"))
        built_for = str(info["mujoco_version"])
    except (OSError, ValueError, KeyError, TypeError):
        return  # a library built by hand (plain cmake) has no record; the C++ side checks again
    if built_for != installed:
        raise PluginError(
            f"{library}: built for MuJoCo {built_for} but MuJoCo {installed} is installed; "
            f"rebuild it with `{BUILD_COMMAND}`"
        )


def load_plugin(path: str | os.PathLike[str] | None = None) -> Path:
    """Load the ``drive_envelope.envelope`` plugin into MuJoCo; calling it again does nothing.

    Args:
        path: The library file; default ``$DRIVE_ENVELOPE_MUJOCO_PLUGIN`` or the build directory.

    Returns:
        The path of the loaded library.

    Raises:
        PluginError: mujoco is missing, the library was not built, was built for another MuJoCo
            version, or does not register the plugin. The message names the build command.
    """
    try:
        import mujoco
    except ImportError:
        raise PluginError(
            "the MuJoCo plugin needs the 'mujoco' extra: pip install 'drive-envelope[mujoco]'"
        ) from None
    library = (Path(path) if path is not None else plugin_library_path()).resolve()
    key = str(library)
    with _LOCK:
        if key in _LOADED:
            return library
        if not library.is_file():
            raise PluginError(
                f"MuJoCo plugin not built: {library} is missing; run `{BUILD_COMMAND}` (part of `make setup`)"
            )
        _check_build_info(library, str(mujoco.__version__))
        try:
            handle = ctypes.CDLL(key)  # runs the library's registration (once per process)
        except OSError as exc:
            raise PluginError(
                f"{library}: cannot be loaded ({exc}); rebuild it with `{BUILD_COMMAND}`"
            ) from None
        built_for = int(handle.drive_envelope_mujoco_header_version())
        if built_for != int(mujoco.mj_version()):
            raise PluginError(
                f"{library}: built for MuJoCo {built_for} but MuJoCo {mujoco.mj_version()} is loaded; "
                f"rebuild it with `{BUILD_COMMAND}`"
            )
        mujoco.mj_loadPluginLibrary(key)  # the official entry point; a no-op for a loaded library
        try:
            probe = mujoco.MjModel.from_xml_string(_PROBE)
        except ValueError as exc:
            raise PluginError(f"{library}: loaded but {PLUGIN_NAME!r} is not usable: {exc}") from None
        _SLOT.append(int(probe.plugin[0]))
        _LOADED[key] = handle
    return library


def plugin_library() -> ctypes.CDLL:
    """The loaded plugin library as a ``ctypes.CDLL`` (loading it first), for its C entry points."""
    library = load_plugin()
    return _LOADED[str(library)]


def plugin_slot() -> int:
    """MuJoCo's registry slot of the plugin (``model.plugin[i]`` of its instances), loading it first."""
    load_plugin()
    return _SLOT[0]

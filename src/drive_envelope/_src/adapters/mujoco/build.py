"""Build the MuJoCo plugin ``drive_envelope.envelope`` against the installed ``mujoco`` wheel.

Run ``drive-envelope mujoco build-plugin`` (``make setup`` runs it through :func:`main`). The wheel
ships the headers (``mujoco/include``) and the library (``mujoco/libmujoco.so.X.Y.Z``); CMake
compiles ``plugin/mujoco`` against exactly those and writes the library plus ``build-info.json``
(the MuJoCo version it was built for) to ``plugin/mujoco/build`` (git-ignored) in a source
checkout, or for an installed wheel (which ships the sources too) to a cache folder of its own per
MuJoCo version and Python environment, so two environments never load each other's build.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

from drive_envelope._src.errors import DriveEnvelopeError
from drive_envelope._src.io.atomic import atomic_write_text

BUILD_COMMAND = "drive-envelope mujoco build-plugin"
"""The command that builds the plugin (quoted in every error about a missing or stale build)."""
BUILD_INFO = "build-info.json"
"""File beside the library that records the MuJoCo version it was built against."""


class PluginError(DriveEnvelopeError, RuntimeError):
    """The MuJoCo plugin is missing, stale (another MuJoCo version) or cannot be built or loaded."""


PLUGIN_SOURCES = (
    "CMakeLists.txt",
    "articulation.cc",
    "constrained.cc",
    "coupled.cc",
    "coupled.h",
    "drive_math.h",
    "envelope.cc",
    "envelope.h",
    "exports.cc",
    "register.cc",
    "solve.cc",
)
"""The plugin's source files; a wheel ships them as ``drive_envelope/_plugin/mujoco`` (pyproject.toml)."""


def _checkout_source_dir() -> Path:
    return Path(__file__).resolve().parents[5] / "plugin" / "mujoco"


def _packaged_source_dir() -> Path:
    return Path(__file__).resolve().parents[3] / "_plugin" / "mujoco"


def plugin_source_dir() -> Path:
    """The plugin sources: ``plugin/mujoco`` of a source checkout, else the copy inside the wheel."""
    checkout = _checkout_source_dir()
    return checkout if (checkout / "CMakeLists.txt").is_file() else _packaged_source_dir()


def default_build_dir() -> Path:
    """Where the build goes and where :func:`load_plugin` looks.

    ``plugin/mujoco/build`` in a source checkout; for an installed wheel (whose site-packages may be
    read-only) ``$XDG_CACHE_HOME/drive-envelope/mujoco-plugin/mujoco-<version>-<env>`` (default
    ``~/.cache/...``), ``<env>`` a hash of the environment's ``sys.prefix``: a build is never shared
    between MuJoCo versions or environments.
    """
    if (_checkout_source_dir() / "CMakeLists.txt").is_file():
        return _checkout_source_dir() / "build"
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "drive-envelope" / "mujoco-plugin" / cache_key()


def cache_key(prefix: str | None = None, version: str | None = None) -> str:
    """``mujoco-<version>-<hash of sys.prefix>``: the cache folder of one MuJoCo and environment."""
    import hashlib
    from importlib import metadata

    if version is None:
        try:
            version = metadata.version("mujoco")  # no import of mujoco itself: this is cheap
        except metadata.PackageNotFoundError:
            version = "none"
    where = os.path.realpath(prefix if prefix is not None else sys.prefix)
    return f"mujoco-{version}-{hashlib.sha256(where.encode()).hexdigest()[:12]}"


def current_build(build_dir: str | os.PathLike[str] | None = None) -> Path | None:
    """The library of ``build_dir`` if it was built for the installed MuJoCo from today's sources, else None.

    A source (``*.cc``, ``*.h``, ``CMakeLists.txt``) newer than the library makes it stale: an
    edited plugin is rebuilt, never silently reused.
    """
    out = Path(build_dir) if build_dir is not None else default_build_dir()
    library, info = out / library_name(), out / BUILD_INFO
    try:
        recorded = json.loads(info.read_text(encoding="utf-8")).get("mujoco_version")
        built_at = library.stat().st_mtime
    except (OSError, ValueError, AttributeError):
        return None
    if recorded != mujoco_paths()[2] or _newest_source() > built_at:
        return None
    return library


def _newest_source() -> float:
    """Modification time of the newest plugin source [s since the epoch]; 0 when none is found."""
    source = plugin_source_dir()
    files = [*source.glob("*.cc"), *source.glob("*.h"), source / "CMakeLists.txt"]
    return max((f.stat().st_mtime for f in files if f.is_file()), default=0.0)


def library_name() -> str:
    """File name of the plugin library on this platform."""
    if sys.platform == "darwin":
        return "libdrive_envelope_mujoco.dylib"
    if sys.platform == "win32":
        return "drive_envelope_mujoco.dll"
    return "libdrive_envelope_mujoco.so"


def mujoco_paths() -> tuple[Path, Path, str]:
    """Headers directory, shared library and version of the installed ``mujoco`` wheel.

    Raises:
        PluginError: mujoco is not installed or its wheel lacks the headers or the library.
    """
    try:
        import mujoco
    except ImportError:
        raise PluginError(
            "the MuJoCo plugin needs the 'mujoco' extra: pip install 'drive-envelope[mujoco]'"
        ) from None
    root = Path(mujoco.__file__).resolve().parent
    include = root / "include"
    if not (include / "mujoco" / "mujoco.h").is_file():
        raise PluginError(f"{include}: the mujoco wheel has no headers (mujoco/mujoco.h)")
    patterns = ("libmujoco.so*", "libmujoco*.dylib", "mujoco.lib")
    libraries = sorted(p for pattern in patterns for p in root.glob(pattern) if p.is_file())
    if not libraries:
        raise PluginError(f"{root}: the mujoco wheel has no MuJoCo library (libmujoco.so*)")
    return include, libraries[-1], str(mujoco.__version__)


def _run(command: list[str], quiet: bool) -> None:
    result = subprocess.run(command, capture_output=quiet, text=True, check=False)
    if result.returncode != 0:
        detail = (result.stderr or result.stdout or "").strip().splitlines()[-20:] if quiet else []
        tail = ("\n" + "\n".join(detail)) if detail else ""
        raise PluginError(
            f"building the MuJoCo plugin failed: {' '.join(command)} exited {result.returncode}{tail}"
        )


def build_plugin(
    *, build_dir: str | os.PathLike[str] | None = None, quiet: bool = False, force: bool = True
) -> Path:
    """Configure and build the plugin with CMake; return the path of the library.

    Args:
        build_dir: Build directory (default :func:`default_build_dir`).
        quiet: Capture the compiler output and show it only on failure.
        force: Build even when ``build_dir`` holds a build for the installed MuJoCo (else reuse it).

    Raises:
        PluginError: no cmake, no sources, no mujoco wheel, or the build failed.
    """
    if not force and (built := current_build(build_dir)) is not None:
        return built
    source = plugin_source_dir()
    if not (source / "CMakeLists.txt").is_file():
        raise PluginError(
            f"{source}: plugin sources not found (reinstall drive-envelope, or build from a source checkout)"
        )
    cmake = shutil.which("cmake")
    if cmake is None:
        raise PluginError(
            "building the MuJoCo plugin needs cmake >= 3.16 (apt install cmake, or pip install cmake)"
        )
    include, library, version = mujoco_paths()
    out = Path(build_dir) if build_dir is not None else default_build_dir()
    out.mkdir(parents=True, exist_ok=True)
    configure = [
        cmake,
        "-S",
        str(source),
        "-B",
        str(out),
        "-DCMAKE_BUILD_TYPE=Release",
        f"-DMUJOCO_INCLUDE_DIR={include}",
        f"-DMUJOCO_LIBRARY={library}",
        f"-DCMAKE_LIBRARY_OUTPUT_DIRECTORY={out.resolve()}",
    ]
    _run(configure, quiet)
    _run([cmake, "--build", str(out), "--config", "Release", "--parallel", "2"], quiet)
    built = out / library_name()
    if not built.is_file():
        raise PluginError(f"building the MuJoCo plugin produced no {built}")
    info = {"mujoco_version": version, "mujoco_library": str(library), "library": library_name()}
    atomic_write_text(out / BUILD_INFO, json.dumps(info, indent=2) + "\n")
    return built


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: build the plugin, print the library path; exit 2 with one line on failure."""
    parser = argparse.ArgumentParser(
        prog=BUILD_COMMAND, description=__doc__.splitlines()[0] if __doc__ else None
    )
    parser.add_argument("--build-dir", default=None, help="build directory (default: plugin/mujoco/build)")
    parser.add_argument("--quiet", action="store_true", help="show compiler output only on failure")
    parser.add_argument(
        "--force", action="store_true", help="rebuild even when a build for this MuJoCo exists"
    )
    args = parser.parse_args(argv)
    try:
        path = build_plugin(build_dir=args.build_dir, quiet=args.quiet, force=args.force)
    except PluginError as exc:
        print(f"drive-envelope: error: {exc}", file=sys.stderr)
        return 2
    print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

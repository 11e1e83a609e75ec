"""``drive-envelope mujoco build-plugin`` and its cache per MuJoCo version and environment (issue 24)."""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import pytest

from drive_envelope._src.adapters.mujoco import build
from drive_envelope._src.cli.main import main


def test_cache_key_differs_per_mujoco_version_and_environment() -> None:
    """Two environments or two MuJoCo versions never share a cache folder; the same pair always does."""
    a = build.cache_key("/envs/a", "3.3.0")
    assert a.startswith("mujoco-3.3.0-") and len(a) == len("mujoco-3.3.0-") + 12
    assert a == build.cache_key("/envs/a", "3.3.0")
    assert a != build.cache_key("/envs/b", "3.3.0")
    assert a != build.cache_key("/envs/a", "3.3.1")


def test_an_installed_package_builds_into_its_own_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without a checkout's sources the build goes to $XDG_CACHE_HOME/drive-envelope/mujoco-plugin/KEY."""
    monkeypatch.setattr(build, "_checkout_source_dir", lambda: tmp_path / "no-checkout")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    expected = tmp_path / "cache" / "drive-envelope" / "mujoco-plugin" / build.cache_key()
    assert build.default_build_dir() == expected


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="needs mujoco")
def test_a_build_for_another_mujoco_is_not_current(tmp_path: Path) -> None:
    """Reuse a build only when its build-info.json names the installed MuJoCo version."""
    version = build.mujoco_paths()[2]
    (tmp_path / build.library_name()).write_bytes(b"\x7fELF")
    info = tmp_path / build.BUILD_INFO
    info.write_text(json.dumps({"mujoco_version": "0.0.1"}), encoding="utf-8")
    assert build.current_build(tmp_path) is None
    info.write_text(json.dumps({"mujoco_version": version}), encoding="utf-8")
    assert build.current_build(tmp_path) == tmp_path / build.library_name()


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="needs mujoco")
def test_a_build_older_than_a_source_is_not_current(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An edited plugin source makes the build stale, so `build-plugin` rebuilds instead of reusing it."""
    sources, out = tmp_path / "src", tmp_path / "build"
    sources.mkdir()
    out.mkdir()
    (sources / "CMakeLists.txt").write_text("project(x)\n", encoding="utf-8")
    monkeypatch.setattr(build, "plugin_source_dir", lambda: sources)
    library = out / build.library_name()
    library.write_bytes(b"\x7fELF")
    (out / build.BUILD_INFO).write_text(
        json.dumps({"mujoco_version": build.mujoco_paths()[2]}), encoding="utf-8"
    )
    os.utime(sources / "CMakeLists.txt", (1_000, 1_000))
    os.utime(library, (2_000, 2_000))
    assert build.current_build(out) == library
    (sources / "envelope.cc").write_text("// edited\n", encoding="utf-8")
    os.utime(sources / "envelope.cc", (3_000, 3_000))
    assert build.current_build(out) is None


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="needs mujoco")
def test_build_plugin_command_reuses_a_current_build(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The public command prints the library path; without --force a current build is not rebuilt."""
    version = build.mujoco_paths()[2]
    library = tmp_path / build.library_name()
    library.write_bytes(b"\x7fELF")
    (tmp_path / build.BUILD_INFO).write_text(json.dumps({"mujoco_version": version}), encoding="utf-8")
    assert main(["mujoco", "build-plugin", "--build-dir", str(tmp_path)]) == 0
    assert capsys.readouterr().out == f"{library}\n"
    assert library.read_bytes() == b"\x7fELF"  # not rebuilt
    assert build.BUILD_COMMAND == "drive-envelope mujoco build-plugin"

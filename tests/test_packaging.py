"""The sdist and the wheel, built from the tracked files only, as a release would be (issue 24).

One build per session: ``python -m build`` (an isolated environment with hatchling, as a user's
``pip install .`` gets) on a copy of the tracked files, then ``twine check --strict`` and the lists
of what each archive holds. The wheel is also imported from where it was unpacked, so package data
(the catalog, the robot maps, the plugin sources) is found without the checkout.
"""

from __future__ import annotations

import email.parser
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

from _checkout import ROOT, copy_checkout, tracked_files

pytestmark = pytest.mark.slow

# what pyproject.toml's [tool.hatch.build.targets.sdist] only-include names (hatch adds .gitignore)
SDIST_ROOTS = (
    ".gitignore",
    "src/drive_envelope/",
    "plugin/mujoco/",
    "tests/",
    "docs/",
    "examples/",
    "benchmarks/",
    "scripts/",
    "README.md",
    "CHANGELOG.md",
    "CITATION.cff",
    "LICENSE",
    "Makefile",
    "pyproject.toml",
)


def _in_sdist(name: str) -> bool:
    return any(name == root or (root.endswith("/") and name.startswith(root)) for root in SDIST_ROOTS)


@pytest.fixture(scope="module")
def dist(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    pytest.importorskip("build", reason="the test extra's `build` (python -m build)")
    source = copy_checkout(tmp_path_factory.mktemp("checkout"))
    out = tmp_path_factory.mktemp("dist")
    run = subprocess.run(
        [sys.executable, "-m", "build", "--outdir", str(out), str(source)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, f"python -m build failed:\n{run.stdout[-3000:]}\n{run.stderr[-3000:]}"
    wheels = sorted(out.glob("*.whl"))
    sdists = sorted(out.glob("*.tar.gz"))
    assert len(wheels) == 1 and len(sdists) == 1, sorted(p.name for p in out.iterdir())
    return {"wheel": wheels[0], "sdist": sdists[0]}


def test_twine_check_passes_strict(dist: dict[str, Path]) -> None:
    pytest.importorskip("twine", reason="the test extra's `twine`")
    run = subprocess.run(
        [sys.executable, "-m", "twine", "check", "--strict", str(dist["wheel"]), str(dist["sdist"])],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.count("PASSED") == 2, run.stdout


def test_wheel_holds_the_package_data_license_and_plugin_sources(dist: dict[str, Path]) -> None:
    from drive_envelope._src.adapters.mujoco.build import PLUGIN_SOURCES

    with zipfile.ZipFile(dist["wheel"]) as wheel:
        names = set(wheel.namelist())
        license_text = wheel.read("drive_envelope-0.1.0.dist-info/licenses/LICENSE").decode()
    tracked = tracked_files()
    package = {n.removeprefix("src/") for n in tracked if n.startswith("src/drive_envelope/")}
    # every tracked file of the package is in the wheel (the catalog and maps included), nothing else of it
    assert package <= names, sorted(package - names)
    assert {
        n for n in names if n.startswith("drive_envelope/") and not n.startswith("drive_envelope/_plugin/")
    } == (package)
    catalog = {n for n in names if n.startswith("drive_envelope/catalog/") and n.endswith(".toml")}
    maps = {n for n in names if n.startswith("drive_envelope/maps/") and n.endswith(".toml")}
    assert len(catalog) >= 60 and "drive_envelope/catalog/tmotor-ak80-6.toml" in catalog
    assert "drive_envelope/maps/unitree-go2.toml" in maps and "drive_envelope/maps/franka-panda.toml" in maps
    assert "drive_envelope/py.typed" in names
    assert {f"drive_envelope/_plugin/mujoco/{n}" for n in PLUGIN_SOURCES} <= names
    assert license_text == (ROOT / "LICENSE").read_text()
    assert license_text.startswith("BSD 3-Clause License")
    assert "the drive-envelope developers" in license_text
    # no test, cache or build output travels in the wheel
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc") or n.startswith("tests/")]


def test_sdist_holds_tracked_files_only(dist: dict[str, Path]) -> None:
    with tarfile.open(dist["sdist"]) as sdist:
        members = [m.name for m in sdist.getmembers() if m.isfile()]
    prefix = "drive_envelope-0.1.0/"
    assert all(m.startswith(prefix) for m in members), members[:5]
    names = {m.removeprefix(prefix) for m in members} - {"PKG-INFO"}
    expected = {n for n in tracked_files() if _in_sdist(n)}
    assert names == expected, {"untracked": sorted(names - expected), "missing": sorted(expected - names)}
    assert {"LICENSE", "README.md", "CITATION.cff", "pyproject.toml", "plugin/mujoco/CMakeLists.txt"} <= names


def test_metadata_names_license_authors_and_classifiers(dist: dict[str, Path]) -> None:
    with zipfile.ZipFile(dist["wheel"]) as wheel:
        text = wheel.read("drive_envelope-0.1.0.dist-info/METADATA").decode()
    meta = email.parser.Parser().parsestr(text)
    assert meta["Name"] == "drive-envelope"
    assert meta["License"] == "BSD-3-Clause"
    assert meta["Author"] == "the drive-envelope developers"
    classifiers = meta.get_all("Classifier") or []
    assert "Typing :: Typed" in classifiers
    assert "Topic :: Scientific/Engineering :: Physics" in classifiers
    assert "physx" in meta["Keywords"].split(",")
    # the core stays numpy + pint; engines are extras
    core = [r for r in meta.get_all("Requires-Dist") or [] if "extra ==" not in r]
    assert sorted(r.split(">")[0].split(";")[0] for r in core) == ["numpy", "pint", "tomli"]
    assert {"plot", "mujoco", "all", "test"} <= set(meta.get_all("Provides-Extra") or [])


def test_unpacked_wheel_runs_without_the_checkout(dist: dict[str, Path], tmp_path: Path) -> None:
    with zipfile.ZipFile(dist["wheel"]) as wheel:
        wheel.extractall(tmp_path / "site")
    script = (
        "import drive_envelope, pathlib, sys\n"
        "from drive_envelope._src.adapters.mujoco.build import plugin_source_dir\n"
        "from drive_envelope.datasheet import derive, load_catalog_datasheet, robot_map_path\n"
        "assert pathlib.Path(drive_envelope.__file__).is_relative_to(sys.argv[1]), drive_envelope.__file__\n"
        "print(plugin_source_dir().relative_to(sys.argv[1]))\n"
        "print(pathlib.Path(robot_map_path('unitree-go2')).relative_to(sys.argv[1]))\n"
        "print(derive(load_catalog_datasheet('tmotor-ak80-6')).envelope.max_effort)\n"
    )
    run = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path / "site")],
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(tmp_path / "site")},
    )
    assert run.returncode == 0, run.stderr[-3000:]
    # the catalog's AK80-6 is rated 12 N*m at the output (its datasheet file)
    assert run.stdout.split() == [
        "drive_envelope/_plugin/mujoco",
        "drive_envelope/maps/unitree-go2.toml",
        "12.0",
    ]

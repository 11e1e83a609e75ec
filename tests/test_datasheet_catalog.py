"""The catalog of real actuators, resolve_envelope, and the public datasheet API."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

import drive_envelope.datasheet as public
from drive_envelope._src.datasheet.catalog import catalog_entries, catalog_text, load_catalog_datasheet
from drive_envelope._src.datasheet.derive import derive
from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.io.envelope_file import save_envelope
from drive_envelope.errors import InputError

CATALOG = Path(public.__file__).parent / "catalog"
KEYS = sorted(p.stem for p in CATALOG.glob("*.toml"))
_VALUE_LINE = re.compile(r"^\s*(\w+)\s*=\s*(.+)$")
_FREE_TEXT_KEYS = {"name", "description", "joint"}


def test_catalog_has_the_required_kinds() -> None:
    """Ship at least 40 actuators covering QDD, strain-wave, gearmotor, hobby servo and linear."""
    entries = catalog_entries()
    assert len(entries) >= 40
    assert len({e.name for e in entries}) == len(entries)
    assert sum(e.joint == "prismatic" for e in entries) >= 2
    text = " ".join(e.description.lower() for e in entries)
    for word in ("quasi-direct-drive", "strain-wave", "gearmotor", "hobby servo", "linear"):
        assert word in text


@pytest.mark.parametrize(
    "keys",
    [
        ("unitree-go-m8010-6", "unitree-go1-joint", "unitree-a1-motor"),  # Go2, Go1, A1
        ("unitree-g1-5020", "unitree-g1-7520-14", "unitree-g1-7520-22", "unitree-h1-knee"),  # G1 / H1
        ("cubemars-ak60-6-v3", "cubemars-ak70-10", "cubemars-ak80-9-v3"),
        ("myactuator-rmd-x8-120", "myactuator-rmd-x12-320"),
        ("robstride-rs01", "robstride-rs02", "robstride-rs03", "robstride-rs04", "damiao-dm-j4310-2ec"),
        ("feetech-sts3215-c001", "feetech-sts3250"),
        ("dynamixel-xl330-m288", "dynamixel-xm430-w350", "dynamixel-xh540-w270"),
        ("harmonic-drive-fha-8c-50",),
        ("actuonix-l16-63-6-r", "actuonix-l12-50-210-12-s"),
        ("franka-panda-joint1-4", "franka-panda-joint5-7"),
    ],
)
def test_catalog_covers_the_robots_people_simulate(keys: tuple[str, ...]) -> None:
    """The motors issue 18 asks for (those with a source) are in the catalog."""
    assert set(keys) <= set(KEYS)


def test_every_entry_names_its_documents() -> None:
    """Every entry lists at least one source document URL."""
    for entry in catalog_entries():
        assert entry.sources, f"{entry.key}: no sources"
        assert all(url.startswith("https://") for url in entry.sources), entry.key


@pytest.mark.parametrize("key", KEYS)
def test_every_entry_derives(key: str) -> None:
    """Derive every catalog entry (peak duty) to a valid finite envelope."""
    env = derive(load_catalog_datasheet(key)).envelope
    assert env.max_effort > 0.0 and 0.0 < env.max_actuator_velocity < float("inf")


@pytest.mark.parametrize("key", KEYS)
def test_continuous_duty_derives_or_names_the_missing_rating(key: str) -> None:
    """Derive continuous duty, or refuse it naming continuous_torque when nothing else limits effort."""
    try:
        env = derive(load_catalog_datasheet(key), duty="continuous").envelope
    except InputError as exc:
        assert "continuous_torque" in str(exc)
    else:
        assert env.max_effort > 0.0


@pytest.mark.parametrize("key", KEYS)
def test_every_number_has_a_source_comment(key: str) -> None:
    """Give each value in a catalog file a comment, and the file at least one document URL."""
    text = catalog_text(key)
    assert "https://" in text
    sheet = load_catalog_datasheet(key)
    assert sheet.sources and all(s.startswith("https://") for s in sheet.sources)
    in_list = False
    for line in text.splitlines():
        stripped = line.strip()
        if in_list or stripped.startswith("sources"):
            in_list = not stripped.endswith("]")
            continue
        match = _VALUE_LINE.match(line)
        if match is None or match.group(1) in _FREE_TEXT_KEYS:
            continue
        assert "#" in match.group(2), f"{key}: no source comment on {line!r}"


def test_resolve_envelope_accepts_all_three_kinds(tmp_path: Path) -> None:
    """Resolve an envelope file, a datasheet file and a catalog name to envelopes."""
    by_name = resolve_envelope("tmotor-ak80-6")
    env_file = tmp_path / "env.toml"
    save_envelope(by_name, env_file)
    assert resolve_envelope(str(env_file)) == by_name
    sheet_file = tmp_path / "sheet.toml"
    sheet_file.write_text(catalog_text("tmotor-ak80-6"), encoding="utf-8")
    assert resolve_envelope(str(sheet_file)) == by_name
    assert resolve_envelope("harmonic-drive-fha-8c-50", duty="continuous").max_effort == pytest.approx(1.5)


def test_resolve_envelope_errors() -> None:
    """Refuse unknown names, missing files and bad duties with an InputError."""
    with pytest.raises(InputError, match="did you mean"):
        resolve_envelope("tmotor-ak80")
    with pytest.raises(InputError, match="no such file"):
        resolve_envelope("missing/file.toml")
    with pytest.raises(InputError, match="duty"):
        resolve_envelope("tmotor-ak80-6", duty="boost")


def test_public_api_names_exist() -> None:
    """Export every name in drive_envelope.datasheet.__all__."""
    for name in public.__all__:
        assert hasattr(public, name), name


def test_import_stays_light() -> None:
    """Import the datasheet API and the CLI parser without heavy packages."""
    code = (
        "import sys, drive_envelope.datasheet\n"
        "from drive_envelope._src.cli.commands import derive, catalog\n"
        "heavy = {'mujoco', 'warp', 'torch', 'pxr', 'matplotlib', 'newton', 'pyarrow', 'pandas', 'yaml'}\n"
        "print(sorted(heavy & set(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_no_catalog_actuator_draws_a_warning() -> None:
    """Real vendor numbers are consistent: the warnings fire on slips, not on datasheets as printed."""
    for entry in catalog_entries():
        assert derive(load_catalog_datasheet(entry.key)).warnings == (), entry.key


def test_the_docs_count_the_catalog_as_it_is() -> None:
    # README.md and docs/datasheet.md said 61 after three entries were added (a new user counted 64)
    root = Path(__file__).resolve().parents[1]
    count = len(catalog_entries())
    pages = (("README.md", r"\| (\d+) real actuators"), ("docs/datasheet.md", r"ships (\d+) real"))
    for page, pattern in pages:
        found = re.findall(pattern, (root / page).read_text(encoding="utf-8"))
        assert found == [str(count)], f"{page} says {found} real actuators; the catalog has {count}"

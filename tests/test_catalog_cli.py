"""`drive-envelope catalog`: filters, --sources, --maps and the CLI conventions (--format, --json, errors)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import drive_envelope.datasheet as public
from drive_envelope._src.cli.main import main
from drive_envelope._src.datasheet.catalog import catalog_entries, catalog_sources

CATALOG = Path(public.__file__).parent / "catalog"


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """Run the CLI; return (exit code, stdout, stderr)."""
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_joint_filter_lists_only_linear_actuators(capsys: pytest.CaptureFixture[str]) -> None:
    """--joint prismatic: the Actuonix linear servos and nothing rotary."""
    code, out, _ = run(capsys, "catalog", "--joint", "prismatic", "--json")
    assert code == 0
    data = json.loads(out)  # an object, as every command's JSON (issue 24)
    assert data["filters"] == {"joint": "prismatic", "search": None}
    items = data["actuators"]
    assert data["count"] == len(items)
    assert items and all(item["joint"] == "prismatic" for item in items)
    assert {"actuonix-l16-63-6-r", "actuonix-l12-50-210-12-s"} <= {item["key"] for item in items}
    expected = {e.key for e in catalog_entries() if e.joint == "prismatic"}
    assert {item["key"] for item in items} == expected


def test_search_matches_all_words_case_insensitively(capsys: pytest.CaptureFixture[str]) -> None:
    """--search 'Unitree G1': every G1 motor, no Go2 or H1 entry."""
    code, out, _ = run(capsys, "catalog", "--search", "Unitree G1", "--json")
    keys = {item["key"] for item in json.loads(out)["actuators"]}
    assert code == 0
    assert {"unitree-g1-5020", "unitree-g1-7520-14", "unitree-g1-7520-22", "unitree-g1-4010"} <= keys
    assert not any(k.startswith(("unitree-go", "unitree-h1")) for k in keys)


def test_search_words_match_at_the_start_of_a_word(capsys: pytest.CaptureFixture[str]) -> None:
    """'tech' finds no FEETECH servo (inside a word), 'feetech' all of them, 'ak80-6' the AK80-6.

    A new user's --search "EC 45" (a maxon motor) listed Damiao's 2EC, FEETECH and Magmotor entries.
    """

    def keys(query: str) -> set[str]:
        code, out, _ = run(capsys, "catalog", "--search", query, "--json")
        return {item["key"] for item in json.loads(out)["actuators"]} if code == 0 else set()

    feetech = {p.stem for p in CATALOG.glob("feetech-*.toml")}
    assert feetech and feetech <= keys("feetech") and not feetech & keys("tech")
    assert "tmotor-ak80-6" in keys("ak80-6")
    assert keys("EC 45") == set()


def test_search_unitree_finds_every_unitree_entry(capsys: pytest.CaptureFixture[str]) -> None:
    """--search unitree: the entries whose key starts with unitree- (and only Unitree's)."""
    code, out, _ = run(capsys, "catalog", "--search", "unitree")
    assert code == 0
    listed = {line.split()[0] for line in out.splitlines() if line.startswith("unitree-")}
    assert listed == {p.stem for p in CATALOG.glob("unitree-*.toml")}


def test_listing_shows_the_derived_envelope(capsys: pytest.CaptureFixture[str]) -> None:
    """The JSON list carries the derived numbers: the Go2 calf is 45.43 N*m, 15.70 rad/s (Unitree URDF)."""
    _, out, _ = run(capsys, "catalog", "--search", "go2 calf", "--json")
    (item,) = json.loads(out)["actuators"]
    assert item["max_effort"] == 45.43 and item["max_actuator_velocity"] == 15.70
    assert item["sources"] and all(url.startswith("https://") for url in item["sources"])


def test_no_match_is_an_error_naming_the_query(capsys: pytest.CaptureFixture[str]) -> None:
    """A search that matches nothing exits 2 in one line: the query and how to list (issue 26: was exit 0)."""
    count = len(catalog_entries())
    for argv in (["--search", "zzzz"], ["--search", "zzzz", "--json"]):
        code, out, err = run(capsys, "catalog", *argv)
        assert code == 2 and out == ""
        assert err.strip() == (
            f"drive-envelope: error: catalog --search 'zzzz': no catalog actuator matches; "
            f"`drive-envelope catalog` lists all {count}"
        )
    code, out, err = run(capsys, "catalog", "--search", "no such vendor")
    assert code == 2 and out == "" and "no catalog actuator matches" in err


@pytest.mark.parametrize(
    ("search", "hint"),
    [
        ("robstride-rs1", "(did you mean 'robstride-rs01'?)"),
        ("ak-80", "(did you mean --search 'ak80'? it lists cubemars-ak80-9-v3, tmotor-ak80-6)"),
        ("dynamixel zzzz", "('zzzz' is in no entry)"),
    ],
)
def test_no_match_suggests_the_nearest_entry_or_search(
    capsys: pytest.CaptureFixture[str], search: str, hint: str
) -> None:
    """The nearest key, a corrected word that finds entries, or the word that no entry holds."""
    code, out, err = run(capsys, "catalog", "--search", search)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert f"catalog --search {search!r}: no catalog actuator matches {hint}; `drive-envelope catalog`" in err
    _, _, err = run(capsys, "catalog", "--search", "zzzz", "--joint", "prismatic")
    assert "`drive-envelope catalog --joint prismatic` lists all" in err


def test_sources_table_quotes_the_document(capsys: pytest.CaptureFixture[str]) -> None:
    """catalog KEY --sources prints each value with the text it was typed from, and the documents."""
    code, out, _ = run(capsys, "catalog", "robstride-rs01", "--sources")
    assert code == 0
    assert '"17 N.m"' in out and "Peak load: 17 N.m" in out
    assert "RS01User%20Manual260428.pdf" in out


def test_sources_json_has_every_value_of_the_file(capsys: pytest.CaptureFixture[str]) -> None:
    """--sources --json: one item per value in the file, each with a non-empty source."""
    code, out, _ = run(capsys, "catalog", "unitree-go-m8010-6", "--sources", "--json")
    data = json.loads(out)
    assert code == 0 and data["key"] == "unitree-go-m8010-6" and data["joint"] == "revolute"
    assert data["values"] == [
        {"key": v.key, "value": v.value, "source": v.source} for v in catalog_sources("unitree-go-m8010-6")
    ]
    assert all(v["source"] for v in data["values"])


def test_show_prints_the_file(capsys: pytest.CaptureFixture[str]) -> None:
    """catalog KEY prints the datasheet file itself (a user can copy and edit it)."""
    code, out, _ = run(capsys, "catalog", "feetech-sts3215-c001")
    assert code == 0 and out == (CATALOG / "feetech-sts3215-c001.toml").read_text(encoding="utf-8")


def test_maps_lists_the_shipped_robot_maps(capsys: pytest.CaptureFixture[str]) -> None:
    """catalog --maps --json: every shipped map with its robot and installed file."""
    code, out, _ = run(capsys, "catalog", "--maps", "--json")
    maps = {m["key"]: m for m in json.loads(out)["maps"]}
    assert code == 0
    assert {"unitree-go2", "unitree-g1", "so101", "franka-panda"} <= set(maps)
    assert Path(maps["unitree-go2"]["path"]).is_file()


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["catalog", "--sources"], "--sources needs an actuator NAME"),
        (["catalog", "robstride-rs1", "--sources"], "did you mean 'robstride-rs01'?"),
        (["catalog", "robstride-rs01", "--joint", "revolute"], "give them without NAME"),
        (["catalog", "--maps", "--search", "go2"], "give it alone"),
        (["catalog", "--joint", "ball"], "invalid choice"),
    ],
)
def test_mistakes_are_one_line_errors(
    capsys: pytest.CaptureFixture[str], argv: list[str], fragment: str
) -> None:
    """Bad combinations exit 2 with one line on stderr naming the problem."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own usage errors
        code = int(exc.code or 0)
    err = capsys.readouterr().err
    assert code == 2 and fragment in err
    if "invalid choice" not in fragment:
        assert err.strip().count("\n") == 0


def test_a_robot_map_name_is_named_as_a_map(capsys: pytest.CaptureFixture[str]) -> None:
    """catalog/derive of a map's name suggested the nearest actuator ('unitree-go2-calf')."""
    for argv in (["catalog", "unitree-go2"], ["derive", "unitree-go2"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "'unitree-go2' is a robot map, not an actuator: " in err and "unitree-go2.toml" in err
        assert "--map unitree-go2" in err and "did you mean" not in err

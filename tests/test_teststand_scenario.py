"""Scenario files: reading, units, --set overrides, envelope precedence and one-line errors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from drive_envelope import InputError, PerformanceEnvelope
from drive_envelope._src.scenario.overrides import parse_override
from drive_envelope._src.scenario.spec import (
    DriveSpec,
    JointSpec,
    Scenario,
    load_scenario,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"

FULL = """
[joint]
type = "revolute"
inertia = 0.5
initial_position = 0.0
initial_velocity = 0.0

[drive]
type = "force"
stiffness = 2864.79
damping = 286.48
target_position = 1.5708
target_velocity = 0.0
max_effort = 10.0

[envelope]
max_actuator_velocity = 3.14159
velocity_dependent_resistance = 1.1459
speed_effort_gradient = 0.31416

[load]
external_effort = 0.0
applied_effort = 0.0

[simulation]
dt = 0.0083333333
duration = 2.0
solver = "pgs"
position_iterations = 4
velocity_iterations = 1
"""


def write(tmp_path: Path, text: str, name: str = "stand.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_issue_example_file_reads_as_si(tmp_path: Path) -> None:
    """The scenario file of the issue reads into SI floats with its envelope."""
    scenario = load_scenario(write(tmp_path, FULL))
    assert scenario.joint == JointSpec(type="revolute", inertia=0.5)
    assert scenario.drive.max_effort == 10.0
    assert scenario.envelope == PerformanceEnvelope(
        max_effort=10.0,
        max_actuator_velocity=3.14159,
        velocity_dependent_resistance=1.1459,
        speed_effort_gradient=0.31416,
    )
    assert scenario.simulation.solver == "pgs"
    assert scenario.simulation.steps == 240
    assert scenario.name == "stand"


def test_strings_with_units_convert_to_si(tmp_path: Path) -> None:
    """Quantities may carry units: degrees, rpm, grams, milliseconds, N*mm."""
    text = """
[joint]
inertia = "5000 g*cm**2"
initial_position = "90 deg"
[drive]
target_velocity = "60 rpm"
max_effort = "2000 N*mm"
[envelope]
max_actuator_velocity = "180 deg/s"
velocity_dependent_resistance = "0.02 N*m*s/deg"
[simulation]
dt = "10 ms"
duration = "0.5 s"
"""
    scenario = load_scenario(write(tmp_path, text))
    assert scenario.joint.inertia == pytest.approx(5e-4)
    assert scenario.joint.initial_position == pytest.approx(math.pi / 2)
    assert scenario.drive.target_velocity == pytest.approx(2 * math.pi)
    assert scenario.drive.max_effort == pytest.approx(2.0)
    assert scenario.envelope is not None
    assert scenario.envelope.max_actuator_velocity == pytest.approx(math.pi)
    assert scenario.envelope.velocity_dependent_resistance == pytest.approx(0.02 * 180 / math.pi)
    assert scenario.simulation.dt == pytest.approx(0.01)


def test_defaults_give_tgs_and_an_unlimited_plain_drive(tmp_path: Path) -> None:
    """Only [joint] is required: TGS 4/1, unlimited drive, no envelope."""
    scenario = load_scenario(write(tmp_path, "[joint]\ninertia = 1.0\n"))
    assert scenario.simulation.solver == "tgs"
    assert (scenario.simulation.position_iterations, scenario.simulation.velocity_iterations) == (4, 1)
    assert math.isinf(scenario.drive.max_effort)
    assert scenario.envelope is None
    assert scenario.effective_envelope() is None


def test_plain_drive_has_the_physx_default_envelope(tmp_path: Path) -> None:
    """Without [envelope] a finite max_effort acts as the envelope (max_effort, inf, 0, 0)."""
    scenario = load_scenario(write(tmp_path, "[joint]\ninertia = 1.0\n[drive]\nmax_effort = 3.0\n"))
    assert scenario.effective_envelope() == PerformanceEnvelope(max_effort=3.0)


def test_overrides_replace_values_in_order(tmp_path: Path) -> None:
    """--set section.key=value overrides the file; later overrides win; strings keep their units."""
    path = write(tmp_path, FULL)
    scenario = load_scenario(
        path,
        [
            "drive.target_velocity=12",
            "simulation.solver=tgs",
            "drive.max_effort='5 N*m'",
            "drive.max_effort=6",
        ],
    )
    assert scenario.drive.target_velocity == 12.0
    assert scenario.simulation.solver == "tgs"
    assert scenario.drive.max_effort == 6.0
    assert scenario.envelope is not None and scenario.envelope.max_effort == 6.0


def test_override_values_parse_as_toml_or_plain_text() -> None:
    """Override values are TOML literals when they parse, plain strings otherwise."""
    assert parse_override("drive.target_velocity=12") == ("drive", "target_velocity", 12)
    assert parse_override("drive.target_velocity = 30 rpm") == ("drive", "target_velocity", "30 rpm")
    assert parse_override('simulation.solver="pgs"') == ("simulation", "solver", "pgs")


@pytest.mark.parametrize(
    ("override", "needle"),
    [
        ("drive", "expected section.key=value"),
        ("drive.target_velocity", "expected section.key=value"),
        ("driv.target_velocity=1", "unknown section 'driv' (did you mean 'drive'?)"),
        ("drive.targte_velocity=1", "unknown key 'drive.targte_velocity' (did you mean 'target_velocity'?)"),
        ("drive.max_effort=-1", "drive.max_effort must be >= 0, got -1.0"),
        ("joint.inertia=0", "joint.inertia must be > 0"),
        ("joint.inertia='3 N'", "key 'joint.inertia'"),
        ("simulation.solver=euler", "key 'simulation.solver': expected one of 'tgs', 'pgs', got 'euler'"),
        ("simulation.position_iterations=0", "simulation.position_iterations must be an integer in 1..255"),
        ("simulation.velocity_iterations=1.5", "key 'simulation.velocity_iterations': expected an integer"),
        ("simulation.dt=0", "simulation.dt must be > 0"),
        ("drive.target_velocity='3 Hz'", "angle"),
        ("envelope.max_actuator_velocity=-1", "key 'envelope.max_actuator_velocity': expected a number >= 0"),
        ("envelope.speed_effort_gradient='inf'", "key 'envelope.speed_effort_gradient': expected a finite"),
        ("simulation.dt=5e-324", "simulation.dt must give a (sub)step within float32's range"),
        ("simulation.dt=2e39", "simulation.dt must give a (sub)step within float32's range"),
        ("simulation.duration=1e308", "simulation.duration / simulation.dt must be a finite number of steps"),
        ("envelope.max_effort=3", "unknown key 'envelope.max_effort'"),
        ("drive.type=position", "key 'drive.type'"),
    ],
)
def test_bad_values_raise_one_line_naming_the_key(tmp_path: Path, override: str, needle: str) -> None:
    """Every bad value gives one InputError line naming the file (or --set) and the key."""
    with pytest.raises(InputError) as info:
        load_scenario(write(tmp_path, FULL), [override])
    message = str(info.value)
    assert needle in message
    assert "\n" not in message
    assert message.startswith((str(tmp_path / "stand.toml"), "--set"))


def test_missing_joint_and_malformed_files_are_reported(tmp_path: Path) -> None:
    """A file without [joint], a malformed file and a missing file each give one line."""
    with pytest.raises(InputError, match=r"missing required table \[joint\]"):
        load_scenario(write(tmp_path, "[drive]\nmax_effort = 1.0\n"))
    with pytest.raises(InputError, match=r"missing required key 'joint\.inertia'"):
        load_scenario(write(tmp_path, "[joint]\ntype = 'revolute'\n"))
    with pytest.raises(InputError, match="malformed TOML"):
        load_scenario(write(tmp_path, "[joint\n"))
    with pytest.raises(InputError, match="no such file"):
        load_scenario(tmp_path / "absent.toml")
    with pytest.raises(InputError, match="unknown key 'joints'"):
        load_scenario(write(tmp_path, "[joints]\ninertia = 1.0\n"))


def test_envelope_without_max_effort_keeps_the_speed_line(tmp_path: Path) -> None:
    """An [envelope] without drive.max_effort is PhysX's unlimited maxForce: eq. 2 alone."""
    scenario = load_scenario(
        write(tmp_path, "[joint]\ninertia = 1.0\n[envelope]\nmax_actuator_velocity = 3.0\n")
    )
    assert scenario.envelope is not None and scenario.envelope.max_effort == math.inf
    assert scenario.envelope.max_actuator_velocity == 3.0


def test_envelope_from_an_envelope_file_with_overrides(tmp_path: Path) -> None:
    """envelope.datasheet names a file beside the scenario; explicit keys and max_effort override it."""
    (tmp_path / "act.toml").write_text(
        'name = "act"\nmax_effort = 12.0\nmax_actuator_velocity = 30.0\nspeed_effort_gradient = 0.5\n',
        encoding="utf-8",
    )
    base = "[joint]\ninertia = 0.1\n[envelope]\ndatasheet = 'act.toml'\n"
    scenario = load_scenario(write(tmp_path, base))
    assert scenario.envelope is not None
    assert (scenario.envelope.max_effort, scenario.envelope.max_actuator_velocity) == (12.0, 30.0)
    assert scenario.drive.max_effort == 12.0  # the drive's maxForce is the envelope's maxEffort
    scenario = load_scenario(
        write(tmp_path, base), ["envelope.max_actuator_velocity=20", "drive.max_effort=8"]
    )
    assert scenario.envelope is not None
    assert (scenario.envelope.max_effort, scenario.envelope.max_actuator_velocity) == (8.0, 20.0)
    assert scenario.envelope.speed_effort_gradient == 0.5
    with pytest.raises(InputError, match=r"key 'envelope\.datasheet'"):
        load_scenario(write(tmp_path, base), ["envelope.datasheet=no-such-actuator-xyz"])


def test_envelope_joint_type_must_match(tmp_path: Path) -> None:
    """A prismatic envelope on a revolute joint is refused."""
    (tmp_path / "lin.toml").write_text('joint = "prismatic"\nmax_effort = 100.0\n', encoding="utf-8")
    with pytest.raises(InputError, match="prismatic"):
        load_scenario(write(tmp_path, "[joint]\ninertia = 0.1\n[envelope]\ndatasheet = 'lin.toml'\n"))


def test_scenario_checks_max_effort_consistency() -> None:
    """Scenario(...) refuses an envelope whose max_effort differs from the drive's."""
    with pytest.raises(InputError, match=r"must equal drive\.max_effort"):
        Scenario(
            joint=JointSpec(inertia=1.0),
            drive=DriveSpec(max_effort=5.0),
            envelope=PerformanceEnvelope(max_effort=4.0),
        )


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.stem)
def test_bundled_scenarios_load(path: Path) -> None:
    """Every bundled scenario file reads without error."""
    scenario = load_scenario(path)
    assert scenario.simulation.steps > 0
    assert scenario.name

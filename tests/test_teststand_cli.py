"""`drive-envelope simulate`: files, formats, overrides, engines and exit status 2 on bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from drive_envelope import InputError
from drive_envelope._src.cli.main import main
from drive_envelope._src.scenario.spec import load_scenario
from drive_envelope._src.teststand import engines

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
SATURATION = EXAMPLES / "velocity_saturation_tgs.toml"


def test_simulate_writes_the_specified_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """simulate --output OUT.csv writes the header, the initial row and one row per step."""
    out = tmp_path / "out.csv"
    assert main(["simulate", str(SATURATION), "--engine", "reference", "--output", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == "time,position,velocity,effort"
    assert len(lines) == 1 + 1 + 120
    assert lines[1] == "0.0,0.0,0.0,0.0"
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert data[-1, 2] == pytest.approx(3.0, abs=1e-12)  # saturates exactly at max_actuator_velocity
    assert "wrote 121 rows" in capsys.readouterr().err  # status lines go to stderr


def test_simulate_json_and_overrides(tmp_path: Path) -> None:
    """--format json and --set change the output format and the scenario."""
    out = tmp_path / "out.txt"
    argv = ["simulate", str(SATURATION), "-o", str(out), "--format", "json"]
    assert main([*argv, "--set", "envelope.max_actuator_velocity=2", "--set", "simulation.duration=0.5"]) == 0
    data = json.loads(out.read_text())
    assert len(data["time"]) == 61
    assert data["velocity"][-1] == pytest.approx(2.0, abs=1e-12)
    assert data["engine"] == "reference"


def test_simulate_without_output_prints_csv(capsys: pytest.CaptureFixture[str]) -> None:
    """Without --output the CSV goes to stdout."""
    assert main(["simulate", str(SATURATION), "--set", "simulation.duration=0.05"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == "time,position,velocity,effort"


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--set", "drive.stifness=3"], "unknown key 'drive.stifness' (did you mean 'stiffness'?)"),
        (["--set", "nonsense"], "expected section.key=value"),
        (["--set", "joint.inertia=-1"], "joint.inertia must be > 0"),
    ],
)
def test_bad_scenarios_exit_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], needle: str
) -> None:
    """Invalid scenario values exit 2 with one 'drive-envelope: error:' line and write nothing."""
    out = tmp_path / "out.csv"
    assert main(["simulate", str(SATURATION), "-o", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("drive-envelope: error: ")
    assert needle in err
    assert err.count("\n") == 1
    assert not out.exists()


def test_bad_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A scenario file with a wrong unit exits 2 naming the file and key."""
    bad = tmp_path / "bad.toml"
    bad.write_text("[joint]\ninertia = '2 m'\n")
    assert main(["simulate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "joint.inertia" in err


def test_missing_engine_package_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    """An engine whose package is absent raises one line naming the extra to install."""
    real = engines.importlib.util.find_spec
    monkeypatch.setattr(
        engines.importlib.util, "find_spec", lambda name: None if name == "ovphysx" else real(name)
    )
    with pytest.raises(InputError, match=r"pip install 'drive-envelope\[physx\]'"):
        engines.engine_module("physx")


def test_unknown_engine_is_refused() -> None:
    """An unknown engine name lists the valid ones."""
    with pytest.raises(InputError, match="valid engines: reference, mujoco, physx"):
        engines.engine_module("bullet")


def test_engine_failing_to_import_its_package_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    """A lazily imported package that is missing at run time is reported as the engine's extra."""

    class FakeEngine:
        @staticmethod
        def simulate(_: object) -> None:
            raise ModuleNotFoundError("No module named 'mujoco'", name="mujoco")

    monkeypatch.setattr(engines, "engine_module", lambda name: FakeEngine)
    with pytest.raises(InputError, match=r"drive-envelope\[mujoco\]"):
        engines.simulate(load_scenario(SATURATION), "mujoco")


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.stem)
def test_bundled_scenarios_run(path: Path, tmp_path: Path) -> None:
    """Every bundled scenario simulates to finite values with the reference engine."""
    out = tmp_path / "out.csv"
    assert main(["simulate", str(path), "-o", str(out), "--set", "simulation.duration=0.1"]) == 0
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.all(np.isfinite(data))


def test_unwritable_output_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """An output below a file (not a folder) exits 2 with one line; a missing folder is created."""
    (tmp_path / "plain").write_text("x", encoding="utf-8")
    out = tmp_path / "plain" / "out.csv"
    assert main(["simulate", str(SATURATION), "-o", str(out), "--set", "simulation.duration=0.05"]) == 2
    assert "cannot write" in capsys.readouterr().err
    made = tmp_path / "missing" / "out.csv"
    assert main(["simulate", str(SATURATION), "-o", str(made), "--set", "simulation.duration=0.05"]) == 0
    assert made.read_text(encoding="utf-8").startswith("time,")


def test_step_limit_is_checked_before_the_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Refuse more than max_steps steps before any engine starts (or allocates); --max-steps raises it."""
    scenario = load_scenario(SATURATION, ["simulation.duration=1"])  # 120 steps
    started = []
    monkeypatch.setattr(engines, "engine_module", lambda name: started.append(name))
    with pytest.raises(
        InputError, match=r"= 120 steps; expected at most 100 \(raise the limit with --max-steps"
    ):
        engines.simulate(scenario, max_steps=100)
    assert started == []
    assert engines.check_steps(scenario, 120) == 120
    assert engines.MAX_STEPS == 10**8


def test_simulate_refuses_a_run_over_the_limit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Exit 2 with one line naming the file for dt = 1e-9 (1e9 steps), at once, writing nothing."""
    out = tmp_path / "run.csv"
    assert main(["simulate", str(SATURATION), "--set", "simulation.dt=1e-9", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"drive-envelope: error: {SATURATION}: ")
    assert "1e+09 steps; expected at most 1000000" in err
    assert main(["simulate", str(SATURATION), "--max-steps", "100", "-o", str(out)]) == 2
    assert main(["simulate", str(SATURATION), "--max-steps", "1e3", "-o", str(out)]) == 0
    assert list(tmp_path.iterdir()) == [out]


def test_engines_get_the_progress_callback(tmp_path: Path) -> None:
    """Report (done, total) to an engine's progress callback, ending at total."""
    calls: list[tuple[int, int]] = []
    scenario = load_scenario(SATURATION, ["simulation.duration=100"])  # 12000 steps
    engines.simulate(scenario, progress=lambda done, total: calls.append((done, total)))
    assert calls[-1] == (12000, 12000) and calls[0] == (4096, 12000)
    assert [done for done, _ in calls] == sorted(done for done, _ in calls)


def test_simulate_streams_to_stdout(capsys: pytest.CaptureFixture[str]) -> None:
    """Write CSV or JSON to stdout (no file), the same text save_trajectory writes."""
    assert main(["simulate", str(SATURATION), "--set", "simulation.duration=0.05"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == "time,position,velocity,effort"
    assert main(["simulate", str(SATURATION), "--json", "--set", "simulation.duration=0.05"]) == 0
    assert len(json.loads(capsys.readouterr().out)["time"]) == 7


@pytest.mark.parametrize(
    ("override", "what"),
    [
        ("drive.damping=1e308", "the implicit drive law"),
        ("load.external_effort=1e308", "overflowed float64"),
        ("joint.inertia=5e-324", "overflowed float64"),
    ],
)
def test_overflow_is_one_line_never_a_wrong_number(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], override: str, what: str
) -> None:
    """Stop with one line when a drive quantity overflows (an infinite request clamps to a wrong effort)."""
    out = tmp_path / "run.csv"
    assert main(["simulate", str(SATURATION), "--set", override, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and what in err and "t = 0 s" in err
    assert not out.exists()


def _last_velocity(path: Path) -> float:
    """The velocity column of a trajectory CSV's last row."""
    header, *_, last = path.read_text().splitlines()
    return float(last.split(",")[header.split(",").index("velocity")])


@pytest.mark.mujoco
def test_mujoco_runs_a_tgs_scenario_as_physx_tgs_without_a_warning(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    tgs = subprocess.run(
        [
            sys.executable,
            "-m",
            "drive_envelope",
            "simulate",
            str(root / "examples/scenarios/actuator_swing.toml"),
            "--engine",
            "mujoco",
            "-o",
            str(tmp_path / "tgs.csv"),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert tgs.returncode == 0, tgs.stderr
    assert "TGS" not in tgs.stderr  # the stand runs set_solver('tgs'), the reference to 1e-13
    final = _last_velocity(tmp_path / "tgs.csv")
    assert final == pytest.approx(0.12655, abs=1e-4)  # real PhysX's final velocity (issue 21)
    pgs = subprocess.run(
        [
            sys.executable,
            "-m",
            "drive_envelope",
            "simulate",
            str(root / "examples/scenarios/braking_pgs.toml"),
            "--engine",
            "mujoco",
            "-o",
            str(tmp_path / "pgs.csv"),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert pgs.returncode == 0, pgs.stderr
    assert "TGS" not in pgs.stderr


CORPUS = Path(__file__).resolve().parent / "corpus" / "good"


def test_a_run_of_no_step_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run.csv"
    argv = ["simulate", str(CORPUS / "scenario.toml"), "-o", str(out), "--set", "simulation.dt=1"]
    assert main(argv) == 2  # the scenario's duration is 0.1 s
    assert "simulation.dt = 1 s is longer than simulation.duration = 0.1 s" in capsys.readouterr().err
    assert not out.exists()
    argv[-1] = "simulation.dt=0.15"  # round(0.1 / 0.15) = 1 step, but dt > duration all the same
    assert main(argv) == 2 and "is longer than simulation.duration" in capsys.readouterr().err


def test_a_duration_that_is_not_whole_steps_says_where_the_run_ends(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run.csv"
    argv = ["simulate", str(CORPUS / "scenario.toml"), "-o", str(out), "--set", "simulation.dt=0.03"]
    assert main(argv) == 0  # 0.1 s / 0.03 s = 3.33: 3 steps, to 0.09 s
    assert "simulating round(duration / dt) = 3 steps, to 0.09 s" in capsys.readouterr().err
    assert len(out.read_text().strip().splitlines()) == 1 + 4  # header, initial state, 3 steps


def test_the_output_cannot_be_the_scenario(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """simulate RUN.json -o RUN.json replaced the scenario with its trajectory without a word."""
    import tomllib

    scenario = tmp_path / "run.json"
    text = json.dumps(tomllib.loads(SATURATION.read_text(encoding="utf-8")))
    scenario.write_text(text, encoding="utf-8")
    (tmp_path / "link.json").symlink_to(scenario)
    for output in (scenario, tmp_path / "link.json"):
        assert main(["simulate", str(scenario), "-o", str(output)]) == 2
        err = capsys.readouterr().err
        assert f"--output '{output}' is the scenario itself: write the trajectory to a new file" in err
    assert scenario.read_text(encoding="utf-8") == text

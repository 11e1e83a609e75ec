"""``drive-envelope identify``: the command line, its JSON object, its files and its engines.

Uses small synthetic logs the reference stand produced (a few seconds of search at most); the real
BAM logs are in ``tests/test_identify_bam.py``.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.identify.logs import read_bench_log
from drive_envelope._src.identify.run import log_scenario, log_schedule
from drive_envelope._src.identify.stand import read_stand
from drive_envelope._src.io.envelope_file import load_envelope
from drive_envelope._src.teststand.engines import reference

pytest.importorskip("scipy")

STAND = """
name = "cli servo"
[joint]
inertia = 1e-6
armature = 0.0015
[drive]
max_effort = 0.5
damping = 0.02
[envelope]
max_actuator_velocity = 20.0
[servo]
duty_per_rad = 1.0
[pendulum]
mass = 0.49
distance = 0.1
[friction]
static_friction = 0.02
dynamic_friction = 0.02
[simulation]
solver = "pgs"
position_iterations = 1
velocity_iterations = 0
"""
FIT = "max_effort,damping,static_friction"


@pytest.fixture
def main(monkeypatch: pytest.MonkeyPatch) -> Callable[[list[str]], int]:
    """The CLI's main with ``identify`` registered (the lead registers it in COMMANDS)."""
    from drive_envelope._src.cli import main as cli
    from drive_envelope._src.cli.commands import identify

    if identify not in cli.COMMANDS:
        monkeypatch.setattr(cli, "COMMANDS", (*cli.COMMANDS, identify))
    return cli.main


@pytest.fixture
def bench(tmp_path: Path) -> tuple[Path, list[Path]]:
    """A stand and two logs its own values produced (effort column included)."""
    stand = tmp_path / "stand.toml"
    stand.write_text(STAND, encoding="utf-8")
    setup = read_stand(stand)
    truth = {"max_effort": 0.45, "duty_effort": 0.45, "damping": 0.025, "static_friction": 0.03}
    t = np.arange(301) * 0.005
    paths = []
    for i, target in enumerate((0.8 * np.sin(2 * np.pi * 1.5 * t), np.where(t < 0.7, 1.0, -0.3))):
        path = tmp_path / f"run{i}.csv"
        np.savetxt(path, np.column_stack([t, np.zeros_like(t), target]), delimiter=",",
                   header="time,position,target_position", comments="")  # fmt: skip
        log = read_bench_log(path)
        values = {name: estimate for name, estimate in _values(setup).items()} | truth
        run = reference.simulate(log_scenario(setup, values, log), schedule=log_schedule(log))
        table = np.column_stack([t, run.position, target, run.velocity, run.effort])
        np.savetxt(
            path, table, delimiter=",", header="time,position,target_position,velocity,effort", comments=""
        )
        paths.append(path)
    return stand, paths


def _values(setup: object) -> dict[str, float]:
    from drive_envelope._src.identify.parameters import start_values

    return start_values(setup.scenario)  # type: ignore[attr-defined]


def test_json_object_has_the_issue_keys(
    main: Callable[[list[str]], int],
    bench: tuple[Path, list[Path]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Print one JSON object: parameters {value, std, fixed}, train/validation MAEs, wall time."""
    stand, logs = bench
    out = tmp_path / "identified.toml"
    envelope_file = tmp_path / "envelope.toml"
    argv = ["identify", str(logs[0]), "--stand", str(stand), "--validate", str(logs[1]), "--fit", FIT,
            "--json", "-o", str(out), "--envelope-output", str(envelope_file),
            "--generations", "20"]  # fmt: skip
    assert main(argv) == 0
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert set(data) >= {"parameters", "train", "validation", "wall_time_s"}
    assert set(data["parameters"]) == {
        "max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient",
        "stiffness", "duty_effort", "damping", "static_friction", "dynamic_friction", "viscous_friction",
        "armature", "angle_offset",
    }  # fmt: skip
    for name, entry in data["parameters"].items():
        if name == "stiffness":  # [servo] duty_per_rad = 1: stiffness follows duty_effort per log
            assert entry == {
                "value": None,
                "std": None,
                "spread": None,
                "fixed": True,
                "derived": "duty_per_rad * duty_effort, per log",
            }
            continue
        assert set(entry) == {"value", "std", "spread", "fixed"}
        # duty_effort and dynamic_friction follow max_effort and static_friction
        assert entry["fixed"] == (name not in [*FIT.split(","), "dynamic_friction", "duty_effort"])
        if not entry["fixed"]:  # three restarts: the range of the values they ended at holds the result
            low, high = entry["spread"]
            assert low <= entry["value"] <= high
    assert data["parameters"]["armature"]["std"] is None
    assert data["parameters"]["max_effort"]["value"] == pytest.approx(0.45, rel=0.02)
    assert set(data["train"]["mae_position"]) == {"run0.csv"}
    assert set(data["validation"]["mae_position"]) == {"run1.csv"}
    assert data["train"]["mae_position_mean"] < 1e-3 and data["validation"]["mae_position_mean"] < 2e-3
    assert data["wall_time_s"] > 0 and "engine" not in data
    envelope = load_envelope(envelope_file)
    assert envelope.max_effort == data["parameters"]["max_effort"]["value"]
    assert f"wrote {out}" in captured.err and f"wrote {envelope_file}" in captured.err
    written = read_stand(out)  # the identified stand: every value, to the last digit
    assert written.scenario.drive.max_effort == data["parameters"]["max_effort"]["value"]
    assert written.scenario.friction.static_friction == data["parameters"]["static_friction"]["value"]
    assert written.scenario.drive.damping == data["parameters"]["damping"]["value"]
    assert written.duty_per_rad == 1.0 and written.scenario.pendulum is not None
    assert main(["replay", str(logs[1]), "--stand", str(out), "--json"]) == 0
    replayed = json.loads(capsys.readouterr().out)
    assert replayed["mae_position"]["run1.csv"] == pytest.approx(
        data["validation"]["mae_position"]["run1.csv"], abs=1e-12
    )


def test_text_report_and_plot(
    main: Callable[[list[str]], int],
    bench: tuple[Path, list[Path]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Print the parameter table and per-log errors; write the figure."""
    pytest.importorskip("matplotlib")
    stand, logs = bench
    figure = tmp_path / "fit.png"
    argv = ["identify", *map(str, logs), "--stand", str(stand), "--fit", "max_effort", "--plot", str(figure),
            "--generations", "3", "--population", "4"]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "max_effort" in text and "fixed" in text and "run1.csv" in text and "mean position error" in text
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_mujoco_replay_reports_its_error(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    """Replay the result in MuJoCo and report its error beside the reference's (PGS, no viscous)."""
    pytest.importorskip("mujoco")
    from drive_envelope._src.adapters.mujoco import build, loader

    try:
        loader.load_plugin()
    except build.PluginError:
        build.build_plugin(quiet=True)
    stand, logs = bench
    argv = ["identify", str(logs[0]), "--stand", str(stand), "--validate", str(logs[1]), "--fit", FIT,
            "--engine", "mujoco", "--json", "--generations", "5"]  # fmt: skip
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["engine"]["name"] == "mujoco"
    ours = data["validation"]["mae_position"]["run1.csv"]
    theirs = data["engine"]["validation"]["mae_position"]["run1.csv"]
    # 0.8 mrad apart since the reference runs PhysX's velocity sweep at 0 velocity iterations (the
    # drive answers the stand's Coulomb friction within the step; MuJoCo's frictionloss acts after it)
    assert theirs == pytest.approx(ours, abs=1.5e-3)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--fit", "max_torque"], "--fit 'max_torque': unknown parameter"),
        (["--fit", "max_effort,,damping"], "expected comma-separated parameter names"),
        (["-o", "{tmp}/env.txt"], "expected a stand file name ending in .toml or .json"),
        (["--envelope-output", "{tmp}/env.txt"], "expected an envelope file name ending in .toml or .json"),
        (["--plot", "{tmp}/fig.gif"], "expected a .png, .svg or .pdf file name"),
        (["--fit", "stiffness"], "ties stiffness to max_effort"),
        (["--restarts", "0"], "--restarts: expected an integer in 1..100"),
        (  # both were written, the envelope last: the identified stand was lost
            ["-o", "{tmp}/out.toml", "--envelope-output", "{tmp}/out.toml"],
            "--envelope-output '{tmp}/out.toml' is also --output",
        ),
        (
            ["--envelope-output", "{tmp}/stand.toml"],
            "--envelope-output '{tmp}/stand.toml' is the --stand file",
        ),
    ],
)
def test_bad_requests_are_one_line(
    main: Callable[[list[str]], int],
    bench: tuple[Path, list[Path]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    extra: list[str],
    message: str,
) -> None:
    """Exit 2 with one line for a bad --fit, output name or figure name, and write nothing."""
    stand, logs = bench
    argv = [
        "identify",
        str(logs[0]),
        "--stand",
        str(stand),
        *[a.replace("{tmp}", str(tmp_path)) for a in extra],
    ]
    before = set(tmp_path.iterdir())
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message.replace("{tmp}", str(tmp_path)) in err[0]
    assert set(tmp_path.iterdir()) == before


def test_bound_reached_is_a_warning(
    main: Callable[[list[str]], int],
    bench: tuple[Path, list[Path]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Warn on stderr when a fitted parameter ends at its bound (widen [bounds])."""
    stand, logs = bench
    narrow = tmp_path / "narrow.toml"
    narrow.write_text(
        stand.read_text(encoding="utf-8") + "[bounds]\nmax_effort = [0.48, 0.6]\n", encoding="utf-8"
    )
    argv = [
        "identify",
        str(logs[0]),
        "--stand",
        str(narrow),
        "--fit",
        "max_effort",
        "--generations",
        "5",
        "--population",
        "4",
    ]
    assert main(argv) == 0
    assert "max_effort = 0.48 ended at its lower bound 0.48" in capsys.readouterr().err


# --- what a new user got wrong: sidecars, stands and outputs ----------------------------------------


def _sidecar(log: Path, **data: object) -> None:
    log.with_suffix(".json").write_text(json.dumps(data), encoding="utf-8")


def _warnings(main: Callable[[list[str]], int], argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main([*argv, "--generations", "1", "--population", "2"]) == 0
    return capsys.readouterr().err


def test_a_sidecar_copied_from_another_log_is_a_warning(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    stand, logs = bench
    _sidecar(logs[0], name="2026-01-15_10h30m10", kp_duty_per_rad=2.3, mass_kg=0.49, length_m=0.1)
    err = _warnings(main, ["identify", str(logs[0]), "--stand", str(stand), "--fit", "max_effort"], capsys)
    assert f"{logs[0]}: its sidecar names the log '2026-01-15_10h30m10': a sidecar copied" in err
    assert "(its kp_duty_per_rad is used as it is; the pendulum is the stand's)" in err


def test_replay_warns_about_sidecars_as_identify_does(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    """A copied sidecar and a pendulum that differs from the stand's: replay said nothing of either."""
    stand, logs = bench
    _sidecar(logs[0], name="2026-01-15_10h30m10", mass_kg=1.5, length_m=0.1)
    assert main(["replay", str(logs[0]), "--stand", str(stand)]) == 0
    err = capsys.readouterr().err
    assert f"{logs[0]}: its sidecar names the log '2026-01-15_10h30m10': a sidecar copied" in err
    assert "its sidecar gives mass_kg = 1.5 but" in err and "the replay uses the stand's 0.49" in err


def test_a_sidecar_bench_that_differs_from_the_stand_is_a_warning(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    stand, logs = bench
    _sidecar(logs[0], name="run0", mass_kg=1.5, length_m=0.1)  # the stand says 0.49 kg at 0.1 m
    err = _warnings(main, ["identify", str(logs[0]), "--stand", str(stand), "--fit", "max_effort"], capsys)
    assert "its sidecar gives mass_kg = 1.5 but" in err and "has pendulum.mass = 0.49" in err
    assert "the replay uses the stand's 0.49" in err  # what is used, said as it is (issue 26, item 5)
    assert "length_m" not in err


def test_a_stand_without_the_sidecars_pendulum_is_a_warning(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    stand, logs = bench
    text = stand.read_text().replace("[pendulum]\nmass = 0.49\ndistance = 0.1\n", "")
    stand.write_text(text, encoding="utf-8")
    _sidecar(logs[0], name="run0", mass_kg=0.49, length_m=0.1)
    err = _warnings(main, ["identify", str(logs[0]), "--stand", str(stand), "--fit", "max_effort"], capsys)
    assert "its sidecar gives a pendulum (mass_kg = 0.49) but" in err and "has no [pendulum]" in err


def test_a_log_without_the_duty_gain_the_others_have_is_a_warning(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    stand, logs = bench
    _sidecar(logs[0], name="run0", kp_duty_per_rad=2.0)
    argv = [
        "identify",
        str(logs[0]),
        "--validate",
        str(logs[1]),
        "--stand",
        str(stand),
        "--fit",
        "max_effort",
    ]
    err = _warnings(main, argv, capsys)
    assert (
        f"{logs[1]}: no kp_duty_per_rad in a sidecar (other logs have one; looked for run1.json, "
        "run1.csv.json): uses the stand's" in err
    )
    assert str(logs[0]) + ":" not in err  # matching sidecars say nothing


def test_a_log_without_the_duty_gain_is_warned_once_even_given_twice(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    """A log both trained on and validated on is one log: one warning."""
    stand, logs = bench
    _sidecar(logs[0], name="run0", kp_duty_per_rad=2.0)
    argv = ["identify", str(logs[0]), str(logs[1]), "--validate", str(logs[1]), "--stand", str(stand)]
    err = _warnings(main, [*argv, "--fit", "max_effort"], capsys)
    assert err.count(f"{logs[1]}: no kp_duty_per_rad in a sidecar (other logs have one; looked for") == 1


def test_replay_warns_a_log_without_the_duty_gain_the_others_have(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    """replay uses the stand's [servo] gain for it, as identify does, and says so once on stderr."""
    stand, logs = bench
    _sidecar(logs[0], name="run0", kp_duty_per_rad=2.0)
    assert main(["replay", str(logs[0]), str(logs[1]), "--stand", str(stand)]) == 0
    err = capsys.readouterr().err
    line = (
        f"{logs[1]}: no kp_duty_per_rad in a sidecar (other logs have one; looked for run1.json, "
        "run1.csv.json): uses the stand's servo.duty_per_rad = 1"
    )
    assert err.count(line) == 1
    assert str(logs[0]) + ":" not in err
    assert main(["replay", str(logs[1]), "--stand", str(stand)]) == 0  # no sidecar anywhere: the stand's
    assert capsys.readouterr().err == ""


def test_stiffness_tied_to_the_duty_gain_is_shown_as_derived(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    stand, logs = bench
    assert (
        main(["identify", str(logs[0]), "--stand", str(stand), "--fit", "max_effort", "--generations", "1"])
        == 0
    )
    (row,) = [line for line in capsys.readouterr().out.splitlines() if line.startswith("stiffness")]
    assert "duty_per_rad * duty_effort, per log" in row and " 0 " not in row


def test_outputs_are_checked_before_the_search(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    stand, logs = bench
    (stand.parent / "plain").write_text("x", encoding="utf-8")  # a file where a folder should be
    for flag, name in (("-o", "plain/e.toml"), ("--plot", "plain/e.png")):
        target = str(stand.parent / name)
        argv = ["identify", str(logs[0]), "--stand", str(stand), flag, target]
        assert main(argv) == 2
        assert "cannot write: " in (err := capsys.readouterr().err) and "is a file, not a folder" in err


def test_zero_generations_and_unknown_stand_keys(
    main: Callable[[list[str]], int], bench: tuple[Path, list[Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    stand, logs = bench
    assert main(["identify", str(logs[0]), "--stand", str(stand), "--generations", "0"]) == 2
    assert "--generations" in capsys.readouterr().err
    stand.write_text("max_effort = 1\n" + STAND, encoding="utf-8")  # a top-level key, as in an envelope
    assert main(["identify", str(logs[0]), "--stand", str(stand)]) == 2
    valid = "name, description, joint, drive, envelope, load, pendulum, friction, simulation, servo, bounds"
    assert f"unknown key 'max_effort'; valid keys: {valid}" in capsys.readouterr().err


def test_progress_lines_when_stderr_is_not_a_terminal(
    main: Callable[[list[str]], int],
    bench: tuple[Path, list[Path]],
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Off a terminal (a log file, CI) a line per report period names restart, phase and best cost."""
    from drive_envelope._src.cli.commands import identify as command

    monkeypatch.setattr(command, "_REPORT_EVERY", 0.0)  # every step, instead of every 10 s
    stand, logs = bench
    argv = ["identify", str(logs[0]), "--stand", str(stand), "--fit", "max_effort", "--generations", "2",
            "--population", "2", "--restarts", "2"]  # fmt: skip
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "identify: restart 1/2, search 1/2, best cost " in err
    assert "identify: restart 2/2, polish 1/30, best cost " in err  # the polish is shown too


@pytest.mark.parametrize("command", ["identify", "replay"])
def test_a_position_beyond_1e100_is_bad_input(
    main: Callable[[list[str]], int],
    bench: tuple[Path, list[Path]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    command: str,
) -> None:
    """Exit 2 naming the cell: identify overflowed inside SciPy (exit 1), replay printed 300 digits."""
    stand, logs = bench
    lines = logs[0].read_text(encoding="utf-8").splitlines()
    fields = lines[51].split(",")
    fields[1] = "1e300"
    lines[51] = ",".join(fields)
    log = tmp_path / "huge.csv"
    log.write_text("\n".join(lines) + "\n", encoding="utf-8")
    argv = [command, str(log), "--stand", str(stand)]
    if command == "identify":
        argv += ["--fit", "max_effort", "--generations", "1", "--population", "1", "--restarts", "1"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "huge.csv: row 51, column 'position': got 1e+300 [SI]" in err[0]

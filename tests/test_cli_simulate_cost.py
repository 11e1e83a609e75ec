"""simulate says what a long run costs before it starts, and refuses past a default cap (issue 25)."""

from __future__ import annotations

from pathlib import Path

import pytest

from drive_envelope._src.cli.commands import simulate
from drive_envelope._src.cli.main import main

REPO = Path(__file__).resolve().parents[1]
SATURATION = REPO / "examples" / "scenarios" / "velocity_saturation_tgs.toml"  # dt = 1/120 s


def test_an_example_with_a_huge_duration_is_refused_by_default(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--set simulation.duration=1e5`` (1.2e7 steps, about 80 min) is refused in one line, at once."""
    out = tmp_path / "run.csv"
    argv = ["simulate", str(SATURATION), "--set", "simulation.duration=1e5", "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "= 1.2e+07 steps; expected at most 1000000 (raise the limit with --max-steps" in err
    assert list(tmp_path.iterdir()) == []


def test_cost_is_said_before_a_long_run(capsys: pytest.CaptureFixture[str]) -> None:
    """Give steps, time (0.4 ms a reference step) and memory (102 bytes a step) above 1e4 steps only."""
    simulate._say_cost(10_000, "reference")
    assert capsys.readouterr().err == ""
    simulate._say_cost(100_000, "reference")  # 40 s; 10.2e6 bytes = 9.73 MiB
    assert capsys.readouterr().err == (
        "simulate: 100000 steps with the reference engine: about 40 s, about 9.73 MiB of memory and output\n"
    )
    simulate._say_cost(90_000_000, "reference")  # 36000 s = 10 h; 9.18e9 bytes = 8.55 GiB
    assert "about 10 h, about 8.55 GiB" in capsys.readouterr().err
    simulate._say_cost(20_000, "mujoco")
    assert "time not estimated for this engine, about 1.95 MiB" in capsys.readouterr().err


def test_the_cost_line_is_on_stderr_of_a_real_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A run of 12000 steps says its cost on stderr first; stdout stays the trajectory alone."""
    assert main(["simulate", str(SATURATION), "--set", "simulation.duration=100"]) == 0
    captured = capsys.readouterr()
    assert captured.err.startswith("simulate: 12000 steps with the reference engine: about 4.8 s")
    assert captured.out.startswith("time,") and "simulate:" not in captured.out

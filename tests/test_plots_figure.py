"""Envelope figures and `drive-envelope plot`: files are written, handles and artists are right."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from _bench_logs import run_cli, write_log
from drive_envelope import InputError, PerformanceEnvelope
from drive_envelope._src.cli.main import main
from drive_envelope._src.scenario.spec import load_scenario
from drive_envelope._src.teststand.engines.reference import simulate

pytestmark = pytest.mark.plot

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SCENARIO = EXAMPLES / "scenarios" / "step_response_tgs.toml"
ENV = PerformanceEnvelope(
    max_effort=10.0,
    max_actuator_velocity=6.0,
    velocity_dependent_resistance=0.5,
    speed_effort_gradient=0.2,
    name="demo",
)


def test_plot_envelope_returns_a_handle_with_the_boundary_drawn() -> None:
    """plot_envelope gives .figure, .axes and .lines; the region is the curve's polygon."""
    from drive_envelope.plots import envelope_curve, plot_envelope

    curve = envelope_curve(ENV)
    plot = plot_envelope(curve)
    assert len(plot.axes) == 1
    assert plot.curve is curve
    outline = plot.lines["region"][1]
    np.testing.assert_allclose(outline.get_xydata()[:-1], curve.boundary)
    assert len(plot.lines["eq1"]) == len(plot.lines["eq2"]) == 4
    labels = plot.axes[0].get_legend_handles_labels()[1]
    assert any(label.startswith("eq. 1:") for label in labels)


def test_trajectory_adds_points_and_a_time_panel() -> None:
    """With a trajectory the plane gets its points (coloured by time) and a velocity/effort panel."""
    from drive_envelope.plots import OperatingPoints, plot_envelope

    trajectory = simulate(load_scenario(SCENARIO, ["simulation.duration=0.2"]))
    mask = np.zeros(len(trajectory), dtype=bool)
    mask[3] = True
    points = OperatingPoints(
        velocity=trajectory.velocity, effort=trajectory.effort, time=trajectory.time, label=trajectory.name
    )
    plot = plot_envelope(ENV, points=points, highlight=mask)
    assert len(plot.axes) == 3
    points = plot.lines[f"points:{trajectory.name}"][0]
    np.testing.assert_allclose(
        points.get_offsets(), np.column_stack([trajectory.velocity, trajectory.effort])
    )
    np.testing.assert_allclose(points.get_array(), trajectory.time)
    np.testing.assert_allclose(
        plot.lines["highlight"][0].get_xydata(), [[trajectory.velocity[3], trajectory.effort[3]]]
    )
    # the window grows to hold every operating point
    assert plot.curve is not None
    assert plot.curve.velocity_extent >= np.max(np.abs(trajectory.velocity))


def test_plot_into_given_axes_and_bad_highlight() -> None:
    """ax= draws into an existing axes; a mask of the wrong length raises InputError."""
    from matplotlib.figure import Figure

    from drive_envelope.plots import OperatingPoints, plot_envelope

    ax = Figure().add_subplot()
    plot = plot_envelope(ENV, ax=ax)
    assert plot.axes == (ax,)
    trajectory = simulate(load_scenario(SCENARIO, ["simulation.duration=0.05"]))
    points = OperatingPoints(velocity=trajectory.velocity, effort=trajectory.effort, time=trajectory.time)
    with pytest.raises(InputError, match="highlight must be a boolean mask"):
        plot_envelope(ENV, points=points, highlight=[True])


def test_points_without_time_use_the_sample_index() -> None:
    """Colour a log without a time column by sample index, and label the time panel 'sample'."""
    from drive_envelope.plots import OperatingPoints, plot_envelope

    points = OperatingPoints(velocity=[0.0, 1.0, 2.0], effort=[5.0, 4.0, 3.0], label="bench")
    plot = plot_envelope(ENV, points=points)
    np.testing.assert_allclose(plot.lines["points:bench"][0].get_array(), [0.0, 1.0, 2.0])
    assert plot.axes[1].get_xlabel() == "sample"
    with pytest.raises(InputError, match="one length"):
        OperatingPoints(velocity=[0.0, 1.0], effort=[1.0])


def test_plot_takes_repeated_trajectory_options(tmp_path: Path) -> None:
    """Accept `plot -t a.csv -t b.csv ENV -o x.png` (a repeatable option, not a greedy list)."""
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    for path, velocity in ((a, "1"), (b, "2")):
        assert main(["simulate", str(SCENARIO), "-o", str(path), "--set", f"drive.target_velocity={velocity}",
                     "--set", "simulation.duration=0.1"]) == 0  # fmt: skip
    figure = tmp_path / "x.png"
    assert main(["plot", "-t", str(a), "-t", str(b), str(SCENARIO), "-o", str(figure)]) == 0
    assert figure.stat().st_size > 0


@pytest.mark.parametrize("suffix", [".png", ".svg", ".pdf"])
def test_plot_command_writes_each_format(tmp_path: Path, suffix: str) -> None:
    """`drive-envelope plot SCENARIO --trajectory CSV --output fig.*` writes a non-empty file."""
    csv = tmp_path / "run.csv"
    assert main(["simulate", str(SCENARIO), "-o", str(csv), "--set", "simulation.duration=0.3"]) == 0
    figure = tmp_path / f"fig{suffix}"
    assert main(["plot", str(SCENARIO), "--trajectory", str(csv), "--output", str(figure)]) == 0
    assert figure.stat().st_size > 1000
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_plot_reads_a_parquet_bench_log_as_check_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Units in Parquet headers and any case, as check reads them (only simulate's Parquet went there)."""
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    log = tmp_path / "bench.parquet"
    pq.write_table(
        pa.table({"Velocity [rpm]": [0.0, 60.0, 120.0], "Effort [mNm]": [500.0, 400.0, 300.0]}), log
    )
    figure = tmp_path / "bench.png"
    code, out, err = run_cli(
        ["plot", str(EXAMPLES / "envelopes" / "demo.toml"), "-t", str(log), "-o", str(figure), "--json"],
        capsys,
    )
    assert code == 0, err
    assert json.loads(out)["trajectories"] == [{"file": str(log), "label": "bench", "samples": 3}]


def test_plot_command_reads_envelope_files(tmp_path: Path) -> None:
    """An envelope file is plotted without a trajectory."""
    figure = tmp_path / "env.png"
    assert main(["plot", str(EXAMPLES / "envelopes" / "demo.toml"), "-o", str(figure)]) == 0
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_command_bad_suffix_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """An unsupported output suffix exits 2 with one line and writes nothing."""
    assert main(["plot", str(SCENARIO), "-o", str(tmp_path / "fig.bmp")]) == 2
    assert "expected a .png, .svg or .pdf" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_importing_plots_does_not_import_matplotlib() -> None:
    """drive_envelope.plots and the CLI parser import matplotlib only when a figure is drawn."""
    code = (
        "import sys, drive_envelope.plots, drive_envelope.teststand;"
        "from drive_envelope._src.cli.main import build_parser; build_parser();"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_plot_below_a_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A figure path below a file (not a folder) exits 2 with one line; a missing folder is made."""
    (tmp_path / "plain").write_text("x", encoding="utf-8")
    assert main(["plot", str(SCENARIO), "-o", str(tmp_path / "plain" / "fig.png")]) == 2
    assert "cannot write" in capsys.readouterr().err
    assert main(["plot", str(SCENARIO), "-o", str(tmp_path / "missing" / "fig.png")]) == 0
    assert (tmp_path / "missing" / "fig.png").read_bytes()[:4] == b"\x89PNG"


def test_names_from_files_are_drawn_literally(tmp_path: Path) -> None:
    """Draw a name with dollar signs ('$x^$', broken mathtext) as text: the figure is written."""
    from drive_envelope.plots import OperatingPoints, plot_envelope, save_figure

    named = PerformanceEnvelope(max_effort=1.0, name="$x^$ motor")
    env_file = tmp_path / "env.toml"
    env_file.write_text('name = "$x^$ motor"\nmax_effort = 1.0\n', encoding="utf-8")
    assert main(["plot", str(env_file), "-o", str(tmp_path / "a.png")]) == 0
    plot = plot_envelope(named)
    assert plot.figure.get_suptitle() == r"\$x^\$ motor"
    save_figure(plot, tmp_path / "b.svg")
    with pytest.raises(InputError, match=r"points 1 label '\$x\^\$': not valid matplotlib mathtext"):
        plot_envelope(named, points=OperatingPoints(velocity=[0.0], effort=[0.0], label="$x^$"))


def test_title_mathtext_is_checked_before_drawing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Accept valid mathtext in --title; refuse '$x^$' in one line before any file is written."""
    assert main(["plot", str(SCENARIO), "--title", r"$\tau_{max}$ test", "-o", str(tmp_path / "ok.png")]) == 0
    capsys.readouterr()
    assert main(["plot", str(SCENARIO), "--title", "$x^$", "-o", str(tmp_path / "bad.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--title '$x^$': not valid matplotlib mathtext" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ok.png"]


def test_raster_size_is_bounded() -> None:
    """Refuse a dpi that would make a PNG wider than 65535 pixels or over 2**27 pixels; suggest one."""
    from drive_envelope.plots import plot_envelope, save_figure

    plot = plot_envelope(ENV)  # 7 x 6.4 in
    with pytest.raises(InputError, match=r"--dpi 100000: .* 700000 x 640000 pixels.*\(--dpi 1730 or less\)"):
        save_figure(plot, "never.png", dpi=100_000)
    with pytest.raises(InputError, match="--dpi 0: expected a positive integer"):
        save_figure(plot, "never.png", dpi=0)


def test_nan_operating_points_are_refused_not_dropped(tmp_path: Path) -> None:
    """Refuse NaN points (matplotlib would drop them silently), in the API and in a trajectory file."""
    from drive_envelope.plots import OperatingPoints

    with pytest.raises(InputError, match=r"operating points 'log': effort\[1\] is nan"):
        OperatingPoints(velocity=[0.0, 1.0], effort=[0.0, float("nan")], label="log")
    trajectory = tmp_path / "run.csv"
    trajectory.write_text("time,position,velocity,effort\n0,0,0,0\n0.1,0,NaN,1\n", encoding="utf-8")
    assert main(["plot", str(SCENARIO), "-t", str(trajectory), "-o", str(tmp_path / "x.png")]) == 2


def test_extreme_envelopes_are_drawn_to_scale_or_refused() -> None:
    """Draw an envelope of 1e-200 N*m with its whole region; refuse one whose window overflows."""
    from drive_envelope.plots import plot_envelope

    tiny = PerformanceEnvelope(
        max_effort=1e-200,
        max_actuator_velocity=1e-200,
        velocity_dependent_resistance=0.5,
        speed_effort_gradient=0.2,
    )
    plot = plot_envelope(tiny)
    assert plot.curve is not None and plot.curve.boundary.shape[0] == 8
    assert plot.axes[0].get_xlim()[1] == pytest.approx(1.15e-200)
    with pytest.raises(InputError, match="too large to draw to scale"):
        plot_envelope(PerformanceEnvelope(max_effort=1e308))


def test_a_glyph_the_font_lacks_is_one_warning_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plot", "tmotor-ak80-6", "--title", "AK 日", "-o", str(tmp_path / "t.svg")]) == 0
    lines = capsys.readouterr().err.splitlines()
    (line,) = [line for line in lines if "Glyph" in line]  # once, without matplotlib's source line
    assert line.startswith("drive-envelope: warning: Glyph 26085 (") and "missing from font" in line


# bench logs of a new user: plot -t draws a log without a position column


def test_plot_draws_a_bench_log_without_position(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A log `check` reads (`time,velocity,effort`) is plotted; `velocity,effort` alone too."""
    pytest.importorskip("matplotlib")
    log = write_log(tmp_path / "bench.csv", "time,velocity,effort\n0,0,1\n0.1,5,11\n0.2,20,9\n")
    assert run_cli(["check", str(bench_envelope_file), str(log)], capsys)[0] == 0
    figure = tmp_path / "bench.png"
    code, _, err = run_cli(["plot", str(bench_envelope_file), "-t", str(log), "-o", str(figure)], capsys)
    assert code == 0 and figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", err
    bare = write_log(tmp_path / "bare.csv", "velocity,effort\n0,1\n5,11\n")
    argv = ["plot", str(bench_envelope_file), "-t", str(bare), "-o", str(tmp_path / "bare.png")]
    assert run_cli(argv, capsys)[0] == 0
    argv = ["plot", str(bench_envelope_file), "-t", str(log), "-o", str(tmp_path / "b.png"), "--json"]
    code, out, _ = run_cli(argv, capsys)
    assert code == 0 and json.loads(out)["trajectories"][0]["label"] == "bench"  # the file's name


def test_plot_reads_a_log_as_check_reads_it(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Units and case in the header (issue 29: plot -t refused `Velocity [rpm]`, which check reads)."""
    pytest.importorskip("matplotlib")
    log = write_log(tmp_path / "rpm.csv", "Time,Velocity [rpm],Effort [mNm]\n0,0,1000\n0.1,60,11000\n")
    assert run_cli(["check", str(bench_envelope_file), str(log)], capsys)[0] in (0, 1)
    argv = ["plot", str(bench_envelope_file), "-t", str(log), "-o", str(tmp_path / "rpm.png"), "--json"]
    code, out, _ = run_cli(argv, capsys)
    assert code == 0 and json.loads(out)["trajectories"] == [{"file": str(log), "label": "rpm", "samples": 2}]
    bad = write_log(tmp_path / "bad.csv", "time,velocity,velocity,effort\n0,1,1,1\n")
    code, _, err = run_cli(
        ["plot", str(bench_envelope_file), "-t", str(bad), "-o", str(tmp_path / "x.png")], capsys
    )
    assert code == 2 and "column 'velocity' is ambiguous" in err


def test_plot_takes_the_column_flags_its_errors_name(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The missing-column error names --velocity-column, which plot refused; a chain run's are named."""
    pytest.importorskip("matplotlib")
    log = write_log(tmp_path / "chain.csv", "time,hip.velocity,hip.effort\n0,0,1\n0.1,5,11\n0.2,20,9\n")
    code, _, err = run_cli(
        ["plot", str(bench_envelope_file), "-t", str(log), "-o", str(tmp_path / "a.png")], capsys
    )
    assert (
        code == 2
        and "per joint (hip): name one with --velocity-column hip.velocity --effort-column hip.effort" in err
    )
    columns = ["--velocity-column", "hip.velocity", "--effort-column", "hip.effort", "--time-column", "time"]
    argv = [
        "plot",
        str(bench_envelope_file),
        "-t",
        str(log),
        *columns,
        "-o",
        str(tmp_path / "a.png"),
        "--json",
    ]
    code, out, err = run_cli(argv, capsys)
    assert code == 0, err
    assert json.loads(out)["trajectories"] == [{"file": str(log), "label": "chain", "samples": 3}]


def test_plot_refuses_a_log_of_several_joints(
    tmp_path: Path, bench_envelope_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two joints' points were drawn as one series over one envelope; one joint's log still plots."""
    pytest.importorskip("matplotlib")
    log = write_log(tmp_path / "long.csv", "time,joint,velocity,effort\n0,a,0,1\n0,b,5,11\n0.1,a,1,2\n")
    figure = str(tmp_path / "a.png")
    code, _, err = run_cli(["plot", str(bench_envelope_file), "-t", str(log), "-o", figure], capsys)
    assert code == 2 and "the log holds 2 joints (a, b); plot draws one joint over one envelope" in err
    one = write_log(tmp_path / "one.csv", "time,joint,velocity,effort\n0,a,0,1\n0.1,a,1,2\n")
    assert run_cli(["plot", str(bench_envelope_file), "-t", str(one), "-o", figure], capsys)[0] == 0

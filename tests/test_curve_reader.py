"""`fit --from-curve` reads a curve with the reader `check` uses (issue 29): same delimiters, units, rows.

Golden values by hand: 2500 rpm = 2500 * 2*pi/60 = 261.79938779914943 rad/s, 760 mN*m = 0.76 N*m; the
three points lie on one line of slope (0.82 - 0.70) N*m / (5000 rpm) = 2.2918311805e-4 N*m*s/rad.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Literal

import numpy as np
import pytest

from drive_envelope._src.cli.main import main
from drive_envelope.analysis import LogColumns, read_curve, read_log

RPM = 2.0 * math.pi / 60.0  # rad/s per rev/min
VELOCITY = [0.0, 2500 * RPM, 5000 * RPM]  # [rad/s]
EFFORT = [0.82, 0.76, 0.70]  # [N*m]


@pytest.mark.parametrize("delimiter", [";", ",", "\t"])
@pytest.mark.parametrize("engine", ["pyarrow", "python"])
def test_curve_points_are_those_of_checks_reader(
    tmp_path: Path, delimiter: str, engine: Literal["pyarrow", "python"]
) -> None:
    if engine == "pyarrow":
        pytest.importorskip("pyarrow.csv")
    path = tmp_path / "curve.csv"
    rows = ["speed [rpm]", "torque [mNm]"], ["0", "820"], ["2500", "760"], ["5000", "700"]
    path.write_text("# digitized\n" + "".join(delimiter.join(row) + "\n" for row in rows))
    velocity, effort = read_curve(path, engine=engine)
    log = read_log(path, LogColumns(velocity="speed", effort="torque", time=None), engine=engine)
    np.testing.assert_allclose(velocity, VELOCITY, rtol=1e-15)
    np.testing.assert_allclose(effort, EFFORT, rtol=1e-15)
    assert np.array_equal(velocity, log.velocity) and np.array_equal(effort, log.effort)


def test_fit_from_a_semicolon_curve_exits_0_with_the_lines_numbers(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The file of the issue: it failed with "no column 'effort' (columns: speed)"."""
    path = tmp_path / "semi.csv"
    path.write_text("speed [rpm];torque [mNm]\n0;820\n2500;760\n5000;700\n")
    assert main(["fit", "--from-curve", str(path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["max_effort"] == pytest.approx(0.82, rel=1e-12)
    assert result["velocity_dependent_resistance"] == pytest.approx(0.12 / (5000 * RPM), rel=1e-9)


def test_a_row_short_of_a_field_is_refused_as_check_refuses_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "short.csv"
    path.write_text("speed [rpm];torque [mNm]\n0;820\n2500\n5000;700\n")
    assert main(["fit", "--from-curve", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "row 2" in err


@pytest.mark.parametrize(
    "text", ["speed [rpm],torque [mNm]\n0,820\n2500,760\n", "Speed;Effort\n0;1\n1;0.5\n"]
)
def test_fit_of_a_curve_without_from_curve_says_that_from_curve_reads_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str
) -> None:
    """`fit curve.csv` (issue 26): the missing column, then that --from-curve reads such curves."""
    path = tmp_path / "curve.csv"
    path.write_text(text)
    assert main(["fit", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and f"{path}: no column 'velocity'" in err
    hint = f"the columns look like a speed-torque curve: drive-envelope fit --from-curve {path} reads"
    assert err.endswith(hint + " such curves")


@pytest.mark.parametrize(
    "text", ["time,speed,torque\n0,1,1\n1,2,1\n", "time,position\n0,1\n1,1\n", "speed,current\n0,1\n1,1\n"]
)
def test_a_log_that_is_no_curve_gets_no_curve_hint(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str
) -> None:
    """A time column, or no effort-like column: a log with other names, not a curve."""
    path = tmp_path / "log.csv"
    path.write_text(text)
    assert main(["fit", str(path)]) == 2
    assert "--from-curve" not in capsys.readouterr().err

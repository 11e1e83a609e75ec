"""identify's bench logs are read by check's CSV reader (issue 29): one header, delimiter and unit rule.

Golden values by hand: 600 rpm = 600 * 2*pi/60 = 62.83185307179586 rad/s, 250 mN*m = 0.25 N*m,
10 ms = 0.01 s, 90 deg = pi/2 rad.
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.logs import read_bench_log
from drive_envelope.analysis import LogColumns, read_log

HEADER = ["time [ms]", "position [deg]", "target_position [deg]", "velocity [rpm]", "effort [mNm]"]
ROWS = [["0", "0", "90", "600", "250"], ["10", "45", "90", "300", "125"], ["20", "90", "90", "0", "0"]]


def _write(path: Path, delimiter: str) -> Path:
    text = "\ufeff# bench run 7\n" + "".join(delimiter.join(row) + "\n" for row in [HEADER, *ROWS])
    if path.suffix == ".gz":
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("name", ["log.csv", "log.csv.gz"])
@pytest.mark.parametrize("delimiter", [";", ",", "\t"])
def test_a_bench_log_gives_the_samples_check_reads(tmp_path: Path, delimiter: str, name: str) -> None:
    path = _write(tmp_path / name, delimiter)
    bench = read_bench_log(path)
    log = read_log(path, LogColumns(joint=None))
    assert bench.velocity is not None and bench.effort is not None and log.time is not None
    np.testing.assert_allclose(bench.time, [0.0, 0.01, 0.02], rtol=1e-15)
    np.testing.assert_allclose(bench.position, [0.0, math.pi / 4, math.pi / 2], rtol=1e-15)
    np.testing.assert_allclose(bench.velocity, [600 * math.pi / 30, 300 * math.pi / 30, 0.0], rtol=1e-15)
    np.testing.assert_allclose(bench.effort, [0.25, 0.125, 0.0], rtol=1e-15)
    assert np.array_equal(bench.time, log.time)
    assert np.array_equal(bench.velocity, log.velocity) and np.array_equal(bench.effort, log.effort)


def test_an_empty_bench_log_is_refused_as_check_refuses_it(tmp_path: Path) -> None:
    path = tmp_path / "empty.csv"
    path.write_text("# only a comment\n\n")
    with pytest.raises(InputError) as bench:
        read_bench_log(path)
    with pytest.raises(InputError) as check:
        read_log(path)
    assert str(bench.value) == str(check.value)
    assert str(bench.value) == (
        f"{path}: empty file (expected a header line naming the columns, then rows of numbers)"
    )


def test_a_parquet_bench_log_gives_the_samples_check_reads(tmp_path: Path) -> None:
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    columns = {name: pa.array([float(row[i]) for row in ROWS]) for i, name in enumerate(HEADER)}
    columns["torque_enable"] = pa.array([True, True, False])
    path = tmp_path / "log.parquet"
    pq.write_table(pa.table(columns), path)
    bench = read_bench_log(path)
    log = read_log(path, LogColumns(joint=None))
    assert bench.velocity is not None and bench.effort is not None
    np.testing.assert_allclose(bench.velocity, [600 * math.pi / 30, 300 * math.pi / 30, 0.0], rtol=1e-15)
    assert np.array_equal(bench.velocity, log.velocity) and np.array_equal(bench.effort, log.effort)
    assert bench.enabled.tolist() == [True, True, False]


def test_a_parquet_text_column_is_refused_as_check_refuses_it(tmp_path: Path) -> None:
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / "text.parquet"
    table = {"time": [0.0, 0.01, 0.02], "position": ["a", "b", "c"], "target_position": [1.0, 1.0, 1.0]}
    pq.write_table(pa.table(table), path)
    with pytest.raises(InputError) as caught:
        read_bench_log(path)
    assert str(caught.value) == f"{path}: column 'position' has type string; expected numbers"

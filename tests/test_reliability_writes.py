"""Writes of simulate, plot, fit and check --plot: read-only targets, --force, a full disk, no leftovers.

The faults are injected where the operating system reports them (``os.access`` for a read-only
file, ``os.replace`` for an immutable one or a full disk), so the tests hold whoever runs them (root
may write a 0444 file) and need no small file system.
"""

from __future__ import annotations

import errno
import importlib.util
import os
import stat
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from drive_envelope._src.cli.main import main
from drive_envelope._src.io import atomic

CORPUS = Path(__file__).resolve().parent / "corpus" / "good"
HAS_MPL = importlib.util.find_spec("matplotlib") is not None


def _commands(out: Path) -> dict[str, list[str]]:
    return {
        "simulate": ["simulate", str(CORPUS / "scenario.toml"), "-o", str(out / "run.csv")],
        "simulate-json": ["simulate", str(CORPUS / "scenario.toml"), "-o", str(out / "run.json")],
        "fit": ["fit", str(CORPUS / "sweep.csv"), "--bootstrap", "0", "-o", str(out / "fit.toml")],
        "plot": ["plot", str(CORPUS / "envelope.toml"), "-o", str(out / "env.png")],
        "check --plot": [
            "check", str(CORPUS / "envelope.toml"), str(CORPUS / "log.csv"), "--plot", str(out / "check.png"),
        ],
    }  # fmt: skip


def _target(argv: list[str]) -> Path:
    return Path(argv[argv.index("--plot") + 1] if "--plot" in argv else argv[argv.index("-o") + 1])


COMMANDS = ["simulate", "simulate-json", "fit", "plot", "check --plot"]


def _needs(name: str) -> None:
    if name in ("plot", "check --plot") and not HAS_MPL:
        pytest.skip("needs matplotlib")


@pytest.mark.parametrize("name", COMMANDS)
def test_read_only_target_is_kept_unless_forced(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Refuse a read-only output in one line and keep it; --force replaces it."""
    _needs(name)
    argv = _commands(tmp_path)[name]
    target = _target(argv)
    target.write_text("keep", encoding="utf-8")
    real_access = os.access
    monkeypatch.setattr(
        atomic.os, "access", lambda path, mode: False if Path(path) == target else real_access(path, mode)
    )
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the file is read-only (pass --force to replace it)" in err
    assert target.read_text(encoding="utf-8") == "keep"
    assert main([*argv, "--force"]) in (0, 1)  # check exits 1 when samples are outside
    assert target.read_bytes() != b"keep"
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]


def _failing_replace(code: int) -> Callable[[object, object], None]:
    def replace(source: object, destination: object) -> None:
        raise OSError(code, os.strerror(code))

    return replace


@pytest.mark.parametrize("name", COMMANDS)
@pytest.mark.parametrize(
    ("code", "message"),
    [(errno.ENOSPC, "no space left on the device"), (errno.EPERM, "Operation not permitted")],
)
def test_full_disk_or_immutable_file_is_one_line_and_leaves_nothing(
    name: str,
    code: int,
    message: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Report a full disk (ENOSPC) or an immutable target (EPERM) in one line; leave no temporary file."""
    _needs(name)
    argv = _commands(tmp_path)[name]
    monkeypatch.setattr(atomic.os, "replace", _failing_replace(code))
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and f"{_target(argv)}: cannot write: {message}" in captured.err
    assert captured.out == ""  # a failed write prints no report either
    assert list(tmp_path.iterdir()) == []


def test_simulate_writes_parquet_that_reads_back(tmp_path: Path) -> None:
    """Write Parquet for a .parquet name (not CSV text), readable by plot's reader and by check."""
    pytest.importorskip("pyarrow")
    from drive_envelope.analysis import check_log
    from drive_envelope.teststand import read_trajectory

    out = tmp_path / "run.parquet"
    assert main(["simulate", str(CORPUS / "scenario.toml"), "-o", str(out)]) == 0
    assert out.read_bytes()[:4] == b"PAR1"
    back = read_trajectory(out)
    assert back.engine == "reference" and len(back) == 11 and back.metadata["solver"] == "tgs"
    assert check_log(str(CORPUS / "envelope.toml"), out).joints[0].samples == 11


def test_parquet_without_pyarrow_is_refused_before_the_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Refuse .parquet in one line when pyarrow is missing, before simulating anything."""
    from drive_envelope._src.scenario import trajectory_parquet

    monkeypatch.setattr(trajectory_parquet, "have_parquet", lambda: False)
    out = tmp_path / "run.parquet"
    assert main(["simulate", str(CORPUS / "scenario.toml"), "-o", str(out)]) == 2
    assert "Parquet needs pyarrow" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


REPO = Path(__file__).resolve().parents[1]
MENAGERIE = REPO.parent / "shared" / "data" / "menagerie"


def _device_commands(out: Path) -> dict[str, list[str]]:
    """One -o run per command that writes, onto ``out`` (a FIFO or a device node)."""
    envelope = str(CORPUS / "envelope.toml")
    return {
        "simulate": ["simulate", str(CORPUS / "scenario.toml"), "-o", str(out)],
        "derive": ["derive", "tmotor-ak80-6", "-o", str(out)],
        "fit": ["fit", str(CORPUS / "sweep.csv"), "--bootstrap", "0", "-o", str(out)],
        "usd apply": [
            "usd", "apply", str(REPO / "examples" / "usd" / "robot.usda"), "--joint",
            "/Robot/joints/shoulder", "--envelope", envelope, "-o", str(out),
        ],
        "mujoco apply": [
            "mujoco", "apply", str(MENAGERIE / "go2.xml"), "--joint", "FL_hip_joint", "--envelope",
            envelope, "--stiffness", "20", "--damping", "0.5", "-o", str(out),
        ],
    }  # fmt: skip


_SUFFIX = {
    "simulate": ".csv",
    "derive": ".toml",
    "fit": ".toml",
    "usd apply": ".usda",
    "mujoco apply": ".xml",
}


def _needs_engine(name: str) -> None:
    if name == "usd apply" and importlib.util.find_spec("pxr") is None:
        pytest.skip("needs pxr")
    if name == "mujoco apply":
        if importlib.util.find_spec("mujoco") is None:
            pytest.skip("needs mujoco")
        if not (MENAGERIE / "go2.xml").is_file():
            pytest.skip("needs ../shared/data/menagerie/go2.xml")


@pytest.mark.parametrize("name", list(_SUFFIX))
def test_output_onto_a_device_node_keeps_it_a_device(name: str, tmp_path: Path) -> None:
    """Write through a character device (a /dev/null twin) given to -o: it stays a device node."""
    _needs_engine(name)
    node = tmp_path / f"n{_SUFFIX[name]}"
    try:
        os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a device node needs root")
    assert main(_device_commands(node)[name]) == 0
    assert stat.S_ISCHR(os.stat(node).st_mode) and os.stat(node).st_rdev == os.makedev(1, 3)
    assert [p.name for p in tmp_path.iterdir()] == [node.name]


@pytest.mark.parametrize("name", list(_SUFFIX))
def test_output_onto_a_fifo_gives_its_reader_the_file(name: str, tmp_path: Path) -> None:
    """Give a FIFO's reader the whole output; the FIFO stays a FIFO; without a reader: exit 2 at once."""
    _needs_engine(name)
    fifo = tmp_path / f"f{_SUFFIX[name]}"
    os.mkfifo(fifo)
    argv = _device_commands(fifo)[name]
    assert main(argv) == 2  # nobody reads yet: refused, never blocked
    got: list[bytes] = []

    def read() -> None:
        with open(fifo, "rb") as handle:
            got.append(handle.read())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    deadline = time.monotonic() + 20
    while main(argv) == 2 and time.monotonic() < deadline:  # until the reader's open() is pending
        time.sleep(0.05)
    reader.join(timeout=20)
    assert got and len(got[0]) > 20
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == [fifo.name]

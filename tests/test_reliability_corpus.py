"""The bad-input corpus: every bad input, through every command that reads it, fails in one line.

``tests/corpus/cases.toml`` lists the cases: one bad input each (a file of ``tests/corpus/``, a file
built here, or a bad flag), the commands it is run through and a fragment of the expected error.
Every run must exit with status 2, print exactly one line on stderr (``drive-envelope...: error:
...``, containing the fragment, no traceback, no warning), print nothing on stdout and write no
file (the output folder, the corpus and the repository's examples are compared before and after).
Runs go through ``drive_envelope._src.cli.main.main`` in-process, so the corpus stays fast; a few
runs also go through ``python -m drive_envelope`` to prove the same of the real entry point.

Extending the corpus (a new command such as ``identify`` included):

1. put the bad input under ``tests/corpus/<kind>/`` (small text files; a large or binary input is
   built by a function registered in :data:`GENERATED` and named ``generated/NAME``);
2. add a ``[[case]]`` to ``cases.toml`` with ``id``, ``input``, ``error`` and ``run`` (one argument
   list per command; placeholders are described at the top of that file), and ``needs`` for
   optional packages;
3. add the new command's runs to the existing cases whose input it reads.

:func:`test_every_command_is_in_the_corpus` fails until every command registered in
``COMMANDS`` appears in some case, and :func:`test_every_corpus_file_is_used` until every file is.
"""

from __future__ import annotations

import gzip
import importlib.util
import os
import stat
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import tomllib

from drive_envelope._src.cli.main import COMMANDS, main

CORPUS = Path(__file__).resolve().parent / "corpus"
REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared" / "data"


def _truncated_gzip(path: Path) -> None:
    rows = "".join(f"{i * 0.01!r},1.0,2.0\n" for i in range(5000))
    data = gzip.compress(("time,velocity,effort\n" + rows).encode())
    path.write_bytes(data[: len(data) // 2])


def _long_header(path: Path) -> None:
    path.write_text("time,velocity,effort," + "x" * 200_000 + "\n0,1,2,3\n", encoding="utf-8")


def _many_joints(path: Path) -> None:
    rows = "".join(f"{i},joint_{i},0.0,0.0\n" for i in range(1001))
    path.write_text("time,joint,velocity,effort\n" + rows, encoding="utf-8")


def _long_field_trajectory(path: Path) -> None:
    path.write_text("time,position,velocity,effort\n0,0,0," + "1" * 200_000 + "\n", encoding="utf-8")


LONG_NAME = "n" * 300
"""A file name over the 255 bytes a name may have (``{long/SUFFIX}`` is a path ending in it)."""


def _fifo(path: Path) -> None:
    os.mkfifo(path)  # nobody ever writes: a reader that opened it would block for ever


def _endless(path: Path) -> None:
    path.symlink_to("/dev/zero")  # x.json that never ends: read whole, it would fill the memory


def _not_utf8_usda(path: Path) -> None:
    text = (REPO / "examples" / "usd" / "robot.usda").read_bytes()
    start = text.index(b"def ")
    path.write_bytes(text[:start] + b'def Xform "caf\xe9" {}\n' + text[start:])  # Latin-1, not UTF-8


def _many_points(path: Path) -> None:
    points = ", ".join(f'["{i} rpm", "0.2 N*m"]' for i in range(10_001))
    path.write_text(
        'name = "many"\njoint = "revolute"\n[motor]\ntorque_constant = "0.091 N*m/A"\n'
        'speed_constant = "100 rpm/V"\nterminal_resistance = "170 mohm"\n[gear]\nratio = 6.0\n'
        f"[losses]\noperating_points = [{points}]\n",
        encoding="utf-8",
    )


def _long_value_map(path: Path) -> None:
    path.write_text(f'[joints]\nhip = "{LONG_NAME}.toml"\n', encoding="utf-8")


GENERATED: dict[str, Callable[[Path], None]] = {
    "truncated.csv.gz": _truncated_gzip,
    "long_header.csv": _long_header,
    "many_joints.csv": _many_joints,
    "long_field_trajectory.csv": _long_field_trajectory,
    "not_utf8.usda": _not_utf8_usda,
    "long_value_map.toml": _long_value_map,
    "many_points.toml": _many_points,
    **{f"fifo.{suffix}": _fifo for suffix in ("toml", "json", "csv", "usda", "xml")},
    **{f"endless.{suffix}": _endless for suffix in ("toml", "json", "csv", "usda", "xml", "parquet")},
}
"""Inputs built at test time (``generated/NAME``): too large or binary to keep in the repository."""


def _cases() -> list[dict[str, Any]]:
    with open(CORPUS / "cases.toml", "rb") as handle:
        return list(tomllib.load(handle)["case"])


CASES = _cases()
RUNS = [
    pytest.param(case, index, id=f"{case['id']}-{index}")
    for case in CASES
    for index in range(len(case["run"]))
]


class _Paths:
    """Resolves the placeholders of a run for one test (a fresh output and generated folder)."""

    def __init__(self, tmp_path: Path) -> None:
        self.out = tmp_path / "out"
        self.generated = tmp_path / "generated"
        self.out.mkdir()
        self.generated.mkdir()

    def path(self, name: str) -> Path:
        kind, _, rest = name.partition("/")
        if kind == "out":
            return self.out / rest
        if kind == "repo":
            return REPO / rest
        if kind == "shared":
            if not SHARED.is_dir():
                pytest.skip(f"needs ../shared/data (real inputs; absent in this checkout): {rest}")
            return SHARED / rest
        if kind == "long":
            return self.out / f"{LONG_NAME}{rest}"
        if kind == "generated":
            target = self.generated / rest
            if not os.path.lexists(target):
                GENERATED[rest](target)
            return target
        return CORPUS / name

    def argument(self, text: str, case: dict[str, Any]) -> str:
        if "={" in text and text.endswith("}"):  # KEY={PATH}: a --set value
            key, _, rest = text.partition("={")
            return f"{key}={self.argument('{' + rest, case)}"
        if text.startswith("{") and "}/" in text:  # {PATH}/rest: a name below a file (not a folder)
            head, _, rest = text.partition("}/")
            return f"{self.argument(head + '}', case)}/{rest}"
        if not (text.startswith("{") and text.endswith("}")):
            return text
        name = text[1:-1]
        if name == "tmp":
            return str(self.out)
        if name == "input":
            return str(self.path(case["input"]))
        return str(self.path(name))


def _placeholder(argument: str) -> str:
    """The placeholder name in ``{NAME}``, ``{NAME}/rest`` or ``KEY={NAME}``, else ``''``."""
    start = argument.find("{")
    if start != 0 and not (start > 0 and argument[start - 1] == "="):
        return ""
    return argument[start + 1 :].partition("}")[0]


def _snapshot(*folders: Path) -> set[tuple[str, int, int, int]]:
    """Every entry under ``folders`` with its type, and a file's size and time: a write changes the set.

    The type is the entry's own (``lstat``): a FIFO or a link to ``/dev/zero`` replaced by a regular
    file changes it.
    """
    found = set()
    for folder in folders:
        for path in folder.rglob("*"):
            info = path.lstat()
            if stat.S_ISREG(info.st_mode):
                found.add((str(path), stat.S_IFMT(info.st_mode), info.st_size, info.st_mtime_ns))
            elif not stat.S_ISDIR(info.st_mode):
                found.add((str(path), stat.S_IFMT(info.st_mode), 0, 0))
    return found


def _run_main(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # argparse's errors exit through the parser
        return int(exc.code or 0)


@pytest.mark.parametrize(("case", "index"), RUNS)
def test_bad_input_fails_in_one_line_and_writes_nothing(
    case: dict[str, Any],
    index: int,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Exit 2 with one 'error:' line holding the expected fragment; no stdout, no warning, no file."""
    for package in case.get("needs", []):
        if importlib.util.find_spec(package) is None:
            pytest.skip(f"needs {package}")
    paths = _Paths(tmp_path)
    argv = [paths.argument(text, case) for text in case["run"][index]]
    monkeypatch.chdir(paths.out)  # a stray file in the working folder is caught too
    monkeypatch.delenv("DRIVE_ENVELOPE_TRACEBACK", raising=False)
    watched = (paths.out, paths.generated, CORPUS, REPO / "examples")
    before = _snapshot(*watched)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status = _run_main(argv)
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert status == 2, f"exit {status}; stderr: {err!r}"
    assert len(lines) == 1, f"expected one line on stderr, got: {err!r}"
    assert lines[0].startswith("drive-envelope") and ": error: " in lines[0], lines[0]
    assert case["error"] in lines[0], f"expected {case['error']!r} in {lines[0]!r}"
    assert "Traceback" not in err and out == "", f"stdout: {out!r}"
    assert [str(w.message) for w in caught] == []
    assert _snapshot(*watched) == before, "the failed command wrote or changed a file"


def test_corpus_is_well_formed() -> None:
    """Give every case a unique id, an error fragment and at least one run; name only known inputs."""
    ids = [case["id"] for case in CASES]
    assert len(ids) == len(set(ids)), "duplicate case ids"
    for case in CASES:
        assert set(case) <= {"id", "input", "error", "run", "needs"}, case["id"]
        assert case["error"] and case["run"], case["id"]
        uses_input = any("{input}" in argv for argv in case["run"])
        assert uses_input == ("input" in case), f"{case['id']}: input and {{input}} go together"
        placeholders = [_placeholder(a) for argv in case["run"] for a in argv if _placeholder(a)]
        for name in [case.get("input", ""), *placeholders]:
            kind = name.partition("/")[0]
            if kind == "generated":
                assert name.partition("/")[2] in GENERATED, f"{case['id']}: no generator for {name}"
            elif name and kind not in ("out", "repo", "shared", "tmp", "input", "long"):
                assert (CORPUS / name).is_file(), f"{case['id']}: no corpus file {name}"


def test_every_corpus_file_is_used() -> None:
    """Run every file of tests/corpus through at least one case (no forgotten input)."""
    used = {case.get("input", "") for case in CASES}
    used |= {_placeholder(a) for case in CASES for argv in case["run"] for a in argv}
    files = {str(p.relative_to(CORPUS)) for p in CORPUS.rglob("*") if p.is_file() and p.name != "cases.toml"}
    assert files - used == set()


def test_every_command_is_in_the_corpus() -> None:
    """Give every registered command (and usd/envelope action) at least one bad-input run."""
    commands = {module.__name__.rpartition(".")[2] for module in COMMANDS}
    covered = {argv[0] for case in CASES for argv in case["run"]}
    assert commands - covered == set(), "commands without a bad-input case in tests/corpus/cases.toml"
    actions = {
        (argv[0], argv[1])
        for case in CASES
        for argv in case["run"]
        if argv[0] in ("usd", "envelope", "mujoco")
    }
    expected = {
        ("usd", "apply"),
        ("usd", "show"),
        ("envelope", "show"),
        ("mujoco", "apply"),
        ("mujoco", "show"),
    }
    assert expected <= actions


@pytest.mark.parametrize(
    "case_id",
    [
        "log-duplicate-column",
        "scenario-over-the-step-limit",
        "fit-negative-seed",
        "mujoco-engine-diverged-state",  # MuJoCo's own C warning line must not reach stderr either
    ],
)
def test_the_real_entry_point_fails_in_one_line(case_id: str, tmp_path: Path) -> None:
    """Show no traceback and exit 2 through ``python -m drive_envelope`` (a fresh interpreter)."""
    case = next(case for case in CASES if case["id"] == case_id)
    for package in case.get("needs", []):
        pytest.importorskip(package)
    paths = _Paths(tmp_path)
    argv = [paths.argument(text, case) for text in case["run"][0]]
    result = subprocess.run(
        [sys.executable, "-m", "drive_envelope", *argv], capture_output=True, text=True, cwd=paths.out
    )
    assert result.returncode == 2, result.stderr
    assert len(result.stderr.splitlines()) == 1 and case["error"] in result.stderr
    assert "Traceback" not in result.stderr and result.stdout == ""
    assert list(paths.out.iterdir()) == []

"""Every documented command runs as written (issue 24): README.md and docs/*.md, from a fresh checkout.

Each page gets a copy of the tracked files (``tmp/x/main``, with ``tmp/x/shared`` linking the real
``shared/`` folder, so ``../shared/data`` resolves as in CI) and runs, in order and in that folder:

- every command of a fenced ``sh``/``bash``/``shell`` block (one per line, ``\\`` continues it) and
  every ``$ `` line of a ``console`` block, through bash; it must exit 0, or the status its trailing
  comment states (``# exits 1: ...``);
- every ``python`` block as a script (``python -`` in that folder).

Not run, but checked: ``pip install`` lines (each extra they name exists in pyproject.toml) and
``make demo`` / ``make test`` (the README's two set-up commands). A block that needs a GPU or Isaac
Sim says so in an HTML comment right before its fence, ``<!-- docs-test: skip gpu -->`` or
``<!-- docs-test: skip isaacsim -->``. ``<!-- docs-test: skip broken -->`` marks a block known to
fail today; their number is held by a ratchet (``KNOWN_BROKEN_BLOCKS``) that only goes down.
``<!-- docs-test: continues -->`` before a python block runs the page's previous python block
first (a snippet that goes on from the last one); ``<!-- docs-test: venv .venv-mjlab -->`` runs
it with that environment's python (skipped while that environment is not created, as the mjlab
tests are). A command that reads ``../shared/`` is skipped when the shared data is absent, as
the data tests are, and so is every snippet after it on that page (they go on from what it made:
``cp ../shared/...`` then a command on the copy).

Each page is one test; its failure lists every failing snippet as ``file:line``.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

from _checkout import ROOT, SHARED, copy_checkout

pytestmark = pytest.mark.slow

SKIP_REASONS = {
    "gpu": "needs a CUDA device",
    "isaacsim": "needs Isaac Sim",
    "broken": "known to fail as written (issue 24: an input not shipped yet, or undefined names)",
}
KNOWN_BROKEN_BLOCKS = 0
"""Blocks marked ``skip broken`` (35 failing commands in 21 blocks when the docs test landed).

0 since every block was fixed (issue 24): the ratchet test below fails when a marker is added; a
new block that does not run is fixed, not marked.
"""
SHELL_LANGS = {"sh", "bash", "shell", "console"}
COMMAND_TIMEOUT_S = 240.0
_FENCE = re.compile(r"^(\s*)```(\w*)\s*$")
_MARKER = re.compile(r"<!--\s*docs-test:\s*(.*?)\s*-->")
_EXIT = re.compile(r"#\s*exits?\s+(\d+)\b")


@dataclass(frozen=True, kw_only=True)
class Snippet:
    """One fenced block of a page."""

    page: str
    """The page, relative to the root."""
    line: int
    """1-based line of the opening fence."""
    lang: str
    """The fence's language."""
    body: list[tuple[int, str]]
    """(1-based line, text) of each line inside the fence."""
    markers: tuple[str, ...]
    """The ``docs-test:`` markers right before the fence."""


def _pages() -> list[str]:
    return ["README.md", *sorted(f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md"))]


def snippets(root: Path, page: str) -> list[Snippet]:
    """The page's fenced blocks in the languages this test runs."""
    lines = (root / page).read_text(encoding="utf-8").splitlines()
    found = []
    i = 0
    while i < len(lines):
        match = _FENCE.match(lines[i])
        if not match:
            i += 1
            continue
        end = i + 1
        while end < len(lines) and not lines[end].strip().startswith("```"):
            end += 1
        markers = []
        k = i - 1
        while k >= 0 and (not lines[k].strip() or _MARKER.search(lines[k])):
            markers += [m.group(1) for m in _MARKER.finditer(lines[k])]
            k -= 1
        lang = match.group(2)
        if lang in SHELL_LANGS or lang == "python":
            body = [(n + 1, lines[n]) for n in range(i + 1, end)]
            found.append(Snippet(page=page, line=i + 1, lang=lang, body=body, markers=tuple(markers)))
        i = end + 1
    return found


def shell_commands(snippet: Snippet) -> list[tuple[int, str]]:
    """(line, command) of each command of a shell block; continuation lines joined."""
    commands: list[tuple[int, str]] = []
    pending: tuple[int, str] | None = None
    for number, raw in snippet.body:
        text = raw.strip()
        if pending is not None:
            pending = (pending[0], pending[1] + " " + text)
        elif snippet.lang == "console":
            if not text.startswith("$ "):
                continue  # printed output
            pending = (number, text[2:])
        else:
            if not text or text.startswith("#"):
                continue
            pending = (number, text)
        if pending[1].endswith("\\"):
            pending = (pending[0], pending[1][:-1].rstrip())
            continue
        commands.append(pending)
        pending = None
    if pending is not None:
        commands.append(pending)
    return commands


def _extras() -> set[str]:
    with open(ROOT / "pyproject.toml", "rb") as f:
        return set(tomllib.load(f)["project"]["optional-dependencies"])


def check_install(command: str) -> str | None:
    """A problem with a ``pip install`` line (an extra that does not exist), or None."""
    extras = _extras()
    for word in shlex.split(command.split("#", 1)[0]):
        match = re.fullmatch(r"(drive-envelope|\.)\[([\w,\-]+)\]", word)
        if match:
            unknown = sorted(set(match.group(2).split(",")) - extras)
            if unknown:
                return f"unknown extra(s) {unknown}; pyproject.toml has {sorted(extras)}"
        elif word == "drive-envelope":
            return "'pip install drive-envelope' needs a release on the index; say `pip install .`"
    return None


def _expected_status(command: str) -> int:
    match = _EXIT.search(command)
    return int(match.group(1)) if match else 0


def _env(main: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    env.pop("DRIVE_ENVELOPE_TRACEBACK", None)
    env["HOME"] = env.get("HOME", str(main))
    return env


def _run(args: list[str], main: Path, *, stdin: str | None = None) -> subprocess.CompletedProcess[str]:
    try:
        return subprocess.run(
            args,
            cwd=main,
            env=_env(main),
            input=stdin,
            capture_output=True,
            text=True,
            timeout=COMMAND_TIMEOUT_S,
        )
    except subprocess.TimeoutExpired as exc:
        return subprocess.CompletedProcess(args, 124, "", f"timed out after {exc.timeout:.0f} s")


def _tail(run: subprocess.CompletedProcess[str]) -> str:
    text = (run.stderr or run.stdout or "").strip().splitlines()
    return " | ".join(text[-3:])[-600:]


def _fresh_checkout(tmp_path: Path) -> Path:
    main = copy_checkout(tmp_path / "x" / "main")
    if SHARED.is_dir():
        (tmp_path / "x" / "shared").symlink_to(SHARED, target_is_directory=True)
    venv = Path(sys.prefix)
    if venv != Path(sys.base_prefix):  # `.venv/bin/python ...` in the docs: the environment under test
        (main / ".venv").symlink_to(venv, target_is_directory=True)
    return main


def run_page(page: str, tmp_path: Path) -> tuple[list[str], list[str]]:
    """Run one page; return (failures, skips), each as ``file:line: ...`` lines."""
    main = _fresh_checkout(tmp_path)
    failures: list[str] = []
    skips: list[str] = []
    previous_python: Snippet | None = None
    shared_skipped = False  # what follows a skipped ../shared command may read what it would have made
    for snippet in snippets(main, page):
        where = f"{page}:{snippet.line}"
        if shared_skipped:
            skips.append(f"{where}: skipped (follows a command that needs ../shared/data, absent)")
            continue
        skip = [m.split(None, 1)[1] for m in snippet.markers if m.startswith("skip ")]
        bad = [reason for reason in skip if reason not in SKIP_REASONS]
        if bad:
            failures.append(f"{where}: unknown docs-test skip reason {bad} (known: {sorted(SKIP_REASONS)})")
        if skip:
            skips.append(f"{where}: skipped ({', '.join(SKIP_REASONS.get(r, r) for r in skip)})")
            if snippet.lang == "python":
                previous_python = snippet
            continue
        if snippet.lang == "python":
            failures += _run_python(snippet, previous_python, main, skips)
            shared_skipped = "../shared/" in _python_code(snippet, previous_python) and not SHARED.is_dir()
            previous_python = snippet
            continue
        for number, command in shell_commands(snippet):
            spot = f"{page}:{number}"
            if shared_skipped:
                skips.append(f"{spot}: skipped (follows a command that needs ../shared/data, absent)")
                continue
            head = command.split("#", 1)[0].strip()
            if re.fullmatch(r"make (demo|test)", head):
                continue  # the README's set-up commands: `make test` runs this test
            if re.match(r"(python -m )?pip install ", head):
                problem = check_install(head)
                if problem:
                    failures.append(f"{spot}: {command}: {problem}")
                continue
            if "../shared/" in command and not SHARED.is_dir():
                skips.append(f"{spot}: skipped (../shared/data is absent)")
                shared_skipped = True
                continue
            run = _run(["bash", "-c", command], main)
            expected = _expected_status(command)
            if run.returncode != expected:
                failures.append(
                    f"{spot}: `{head}` exited {run.returncode} (expected {expected}): {_tail(run)}"
                )
    return failures, skips


def _run_python(snippet: Snippet, previous: Snippet | None, main: Path, skips: list[str]) -> list[str]:
    where = f"{snippet.page}:{snippet.line}"
    if "continues" in snippet.markers and previous is None:
        return [f"{where}: marked 'continues' but no python block comes before it"]
    code = _python_code(snippet, previous)
    python = sys.executable
    venvs = [m.split(None, 1)[1] for m in snippet.markers if m.startswith("venv ")]
    if venvs:
        other = ROOT / venvs[0] / "bin" / "python"
        if not other.exists():
            skips.append(f"{where}: skipped ({venvs[0]} is not created; `make test-mjlab` creates it)")
            return []
        python = str(other)
    if "../shared/" in code and not SHARED.is_dir():
        skips.append(f"{where}: skipped (../shared/data is absent)")
        return []
    run = _run([python, "-"], main, stdin=code)
    if run.returncode != 0:
        return [f"{where}: python block exited {run.returncode}: {_tail(run)}"]
    return []


def _python_code(snippet: Snippet, previous: Snippet | None) -> str:
    """The script a python block runs: the block, after the previous one when it ``continues``."""
    code = "\n".join(text for _, text in snippet.body)
    if "continues" in snippet.markers and previous is not None:
        code = "\n".join(text for _, text in previous.body) + "\n" + code
    return code


@pytest.mark.parametrize("page", _pages())
def test_page_runs_as_written(page: str, tmp_path: Path) -> None:
    failures, skips = run_page(page, tmp_path)
    for line in skips:
        print(line)
    assert not failures, f"{len(failures)} failing snippet(s):\n" + "\n".join(failures)


def test_parser_reads_console_commands_markers_and_continuations(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text(
        "intro\n"
        "<!-- docs-test: skip gpu -->\n"
        "```python\nimport warp\n```\n"
        "```console\n$ drive-envelope a \\\n    --b   # exits 1: a gate\noutput line\n$ echo hi\n```\n"
        "```sh\n# comment\nmake demo\n```\n"
        "```text\n$ not run\n```\n",
        encoding="utf-8",
    )
    found = snippets(tmp_path, "page.md")
    assert [(s.line, s.lang, s.markers) for s in found] == [
        (3, "python", ("skip gpu",)),
        (6, "console", ()),
        (12, "sh", ()),
    ]
    assert shell_commands(found[1]) == [(7, "drive-envelope a --b   # exits 1: a gate"), (10, "echo hi")]
    assert _expected_status(shell_commands(found[1])[0][1]) == 1
    assert shell_commands(found[2]) == [(14, "make demo")]
    assert check_install("pip install '.[plot,nosuch]'") is not None
    assert check_install("pip install '.[plot,mujoco]'   # extras") is None


def test_known_broken_blocks_only_go_down() -> None:
    marked = [
        f"{page}:{snippet.line}"
        for page in _pages()
        for snippet in snippets(ROOT, page)
        if "skip broken" in snippet.markers
    ]
    assert len(marked) <= KNOWN_BROKEN_BLOCKS, (
        f"{len(marked)} blocks marked 'skip broken' (at most {KNOWN_BROKEN_BLOCKS}): fix new ones instead"
    )
    assert len(marked) == KNOWN_BROKEN_BLOCKS, (
        f"only {len(marked)} blocks are marked 'skip broken' now: lower KNOWN_BROKEN_BLOCKS to {len(marked)}"
    )


def test_what_follows_an_absent_shared_command_is_skipped(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a fresh clone without ../shared: `cp ../shared/...` is skipped, and so is the command on the copy
    page = tmp_path / "page.md"
    page.write_text(
        "```sh\necho first\ncp ../shared/data/robot.usda .\ncat robot.usda\n```\n"
        "```sh\ncat robot.usda\n```\n",
        encoding="utf-8",
    )
    monkeypatch.setattr(sys.modules[__name__], "SHARED", tmp_path / "no-shared")
    monkeypatch.setattr(sys.modules[__name__], "_fresh_checkout", lambda _: tmp_path)
    failures, skips = run_page("page.md", tmp_path)
    assert failures == []
    assert [line.split(":")[1] for line in skips] == ["3", "4", "6"]

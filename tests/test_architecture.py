"""The layer stack of ``drive_envelope._src``: no upward import, no cycle, lazy imports included.

Every ``import`` statement counts, at module level or inside a function: a lazy import that points
up the stack is still a dependency a reader has to follow. The ranks are the stack of
``docs/architecture.md``; a package may import its own rank and below, never above, and the
module graph has no cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "drive_envelope"
PRIVATE = SRC / "_src"

RANKS: dict[str, int] = {
    "errors": 0,
    "version": 0,
    "units": 0,
    "values": 0,
    "validation": 0,
    "format": 0,
    "params": 0,
    "envelope": 1,
    "io": 2,
    "datasheet": 3,
    "scenario": 4,
    "kernels": 5,
    "adapters": 6,
    "teststand": 7,
    "identify": 7,
    "analysis": 7,
    "plots": 7,
    "cli": 8,
}
"""Rank of each top-level package or module of ``_src`` (bottom 0)."""


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC.parent).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path, modules: set[str]) -> set[str]:
    """Every ``drive_envelope`` module ``path`` imports, lazy imports included."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path).rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            if base.startswith("drive_envelope"):
                # "from package import module" depends on the module, "from module import name" on it
                submodules = {f"{base}.{alias.name}" for alias in node.names} & modules
                found.update(submodules or {base})
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name.startswith("drive_envelope"))
    return found


def _graph() -> dict[str, set[str]]:
    modules = {_module_name(path): path for path in PRIVATE.rglob("*.py")}
    return {name: _imports(path, set(modules)) for name, path in modules.items()}


def _top(module: str) -> str:
    return module.removeprefix("drive_envelope._src.").split(".")[0]


def test_every_package_has_a_rank() -> None:
    """Give every package of _src a place in the stack."""
    tops = {_top(name) for name in _graph() if name != "drive_envelope._src"}
    assert tops <= set(RANKS), f"packages without a rank: {sorted(tops - set(RANKS))}"


def test_no_upward_import() -> None:
    """Import only from the same rank or below, and never from the public facade."""
    problems = []
    for module, deps in _graph().items():
        if module == "drive_envelope._src":
            continue
        rank = RANKS[_top(module)]
        for dep in deps:
            if not dep.startswith("drive_envelope._src"):
                problems.append(f"{module} imports the public module {dep}: import from _src instead")
                continue
            if dep == "drive_envelope._src":
                continue
            if RANKS[_top(dep)] > rank:
                problems.append(f"{module} (rank {rank}) imports {dep} (rank {RANKS[_top(dep)]})")
    assert not problems, "\n".join(sorted(problems))


def test_no_import_cycle() -> None:
    """Keep the module graph acyclic (package __init__ files included)."""
    graph = {m: {d for d in deps if d.startswith("drive_envelope._src")} for m, deps in _graph().items()}
    state: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for dep in sorted(graph.get(node, ())):
            if state.get(dep) == 1:
                cycles.append(" -> ".join([*stack[stack.index(dep) :], dep]))
            elif dep not in state:
                visit(dep)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)
    assert not cycles, "\n".join(cycles)


def _imported_packages(path: Path) -> set[str]:
    """Top-level names of every package ``path`` imports, lazy imports included."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            found.add(node.module.split(".")[0])
        elif isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
    return found


def test_matplotlib_is_imported_only_under_plots() -> None:
    """Figures are built in plots/ (issue 29): the layers beside it pass data, the CLI calls plots/."""
    plots = PRIVATE / "plots"
    outside = [
        str(path.relative_to(SRC))
        for path in sorted(SRC.rglob("*.py"))
        if "matplotlib" in _imported_packages(path) and not path.is_relative_to(plots)
    ]
    assert not outside, f"matplotlib imported outside _src/plots: {outside}"


@pytest.mark.parametrize("engine", ["mujoco", "mjwarp", "mjlab", "newton", "physx", "usd", "isaaclab"])
def test_each_engine_lives_in_one_adapter_package(engine: str) -> None:
    """Find an engine's code in one folder: nothing outside adapters/<engine> imports the engine."""
    heavy = {
        "mujoco": "mujoco",
        "mjwarp": "mujoco_warp",
        "mjlab": "mjlab",
        "newton": "newton",
        "physx": "ovphysx",
        "usd": "pxr",
        "isaaclab": "isaaclab",
    }
    # the PhysX adapter authors the stage PhysX reads, so it may use pxr too; MuJoCo Warp and mjlab
    # sit on MuJoCo (mjlab's own models are MjSpec/MjModel), so their adapters may import mujoco
    homes = {
        "usd": {"usd", "physx"},
        "mujoco": {"mujoco", "mjwarp", "mjlab"},
        "mjwarp": {"mjwarp", "mjlab"},
    }.get(engine, {engine})
    package = heavy[engine]
    outside = []
    for path in PRIVATE.rglob("*.py"):
        relative = path.relative_to(PRIVATE).parts
        if relative[0] == "adapters" and relative[1] in homes:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            names = (
                [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else []
            )
            if any(name == package or name.startswith(f"{package}.") for name in names):
                outside.append(str(path.relative_to(PRIVATE)))
    assert not outside, f"{package} imported outside adapters/{engine}: {sorted(set(outside))}"


def test_modules_stay_small() -> None:
    """Keep every module under about 500 lines (Newton's actuator package tops out near 440)."""
    large = {
        str(path.relative_to(SRC)): n
        for path in SRC.rglob("*.py")
        if (n := len(path.read_text(encoding="utf-8").splitlines())) > 550
    }
    assert not large, large

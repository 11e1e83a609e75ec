"""One model, every engine: the largest per-step difference of each engine against the reference.

Runs every shipped test-stand scenario (``examples/scenarios/*.toml``) on the ``reference`` engine
(the float64 model of PhysX's solver) and on each other engine installed here:

* ``physx``: real PhysX 5.6 (ovphysx 0.7, CPU, float32), the engine the model is of;
* ``mujoco``: the ``drive_envelope.envelope`` plugin (C++, float64) iterating the drive as the
  scenario's PhysX solver does (``set_solver``: PGS sweeps or TGS substeps, the scenario's counts);
* ``newton``: ``SolverFeatherstone`` (float32) with the drive's effort computed as the scenario's
  PhysX solver iterates it (a Warp kernel, float64 inside) and applied as joint effort;
* ``warp`` / ``torch``: the reference's own solver loop with its NumPy ``clamp_drive_impulse``
  replaced by the Warp / torch port in float32, closed loop (each step starts from the state the
  float32 clamp produced): the batched clamps on the exact calls the solver makes.

For each scenario and engine it reports the largest ``|difference|`` over all steps of velocity,
effort and position, and the worst of the three divided by its tolerance; ``<= 1`` passes. The
tolerances are those of the engines' own tests: the mujoco engine's (velocity ``1e-5 +
5e-5*max|v|``, effort ``1e-4 + 1e-3*max_effort``, position ``1e-5 + 1e-4*path length``) for
mujoco, warp, torch and newton on PGS; ``3e-3 * max(1, max|column|)`` for real PhysX, whose float32
noise is amplified about a thousandfold by braking along eq. 2 (``tests/test_teststand_physx.py``),
and for newton on TGS, whose float32 state the substeps' clamps amplify the same way
(``step_response_tgs``: 3.4e-4 rad/s, real PhysX 2.0e-3). Every row is held.
``docs/parity.md`` is written by this script (``--write``) and checked by
``tests/test_parity_engines.py``.

    .venv/bin/python benchmarks/parity_table.py [--write] [--engines physx,mujoco,newton,warp,torch]
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from unittest import mock

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "examples" / "scenarios"
DOC = ROOT / "docs" / "parity.md"
ENGINES = ("physx", "mujoco", "newton", "warp", "torch")
HELD_ON_TGS = ("physx", "mujoco", "newton", "warp", "torch")
"""Engines that model TGS as PhysX runs it: all of them (mujoco and newton with the scenario's solver)."""
FLOAT32_STATE = ("physx",)
"""Engines held to the float32 tolerance on every scenario; newton on TGS scenarios too."""
NEEDS = {"physx": "ovphysx", "mujoco": "mujoco", "newton": "newton", "warp": "warp", "torch": "torch"}
BEGIN, END = "<!-- parity-table:begin -->", "<!-- parity-table:end -->"


@dataclass(frozen=True, kw_only=True, slots=True)
class Row:
    """One engine on one scenario against the reference."""

    scenario: str
    solver: str
    engine: str
    velocity: float
    """Largest |velocity - reference| over the steps [rad/s or m/s]."""
    effort: float
    """Largest |effort - reference| over the steps [N*m or N]."""
    position: float
    """Largest |position - reference| over the steps [rad or m]."""
    ratio: float
    """The worst of the three over its tolerance (<= 1 passes)."""

    @property
    def held(self) -> bool:
        """Whether this row is held to the tolerance (PGS for every engine; TGS for PhysX's models)."""
        return self.solver == "pgs" or self.engine in HELD_ON_TGS


def tolerances(engine: str, scenario: object, ref: object) -> tuple[float, float, float]:
    """The per-step tolerances (velocity, effort, position) of ``engine`` for a reference run."""
    tgs = scenario.simulation.solver == "tgs"  # type: ignore[attr-defined]
    if engine in FLOAT32_STATE or (engine == "newton" and tgs):
        return tuple(  # type: ignore[return-value]
            3e-3 * max(1.0, float(np.abs(getattr(ref, column)).max()))
            for column in ("velocity", "effort", "position")
        )
    max_effort = scenario.drive.max_effort  # type: ignore[attr-defined]
    if not np.isfinite(max_effort):
        max_effort = float(np.abs(ref.effort).max())  # type: ignore[attr-defined]
    path = float(np.abs(np.diff(ref.position)).sum())  # type: ignore[attr-defined]
    return (
        1e-5 + 5e-5 * float(np.abs(ref.velocity).max()),  # type: ignore[attr-defined]
        1e-4 + 1e-3 * max_effort,
        1e-5 + 1e-4 * path,
    )


def available(engine: str) -> bool:
    """Whether the engine's package is installed (the mujoco plugin is built on first use)."""
    return importlib.util.find_spec(NEEDS[engine]) is not None


@contextmanager
def _clamp(backend: str) -> Iterator[None]:
    """The reference engine with its clamp replaced by the Warp or torch port (float32).

    The reference is a batch of one (``teststand/batch.py``): the clamp gets the batch's float64
    arrays and gives back float64 arrays of their broadcast shape.
    """
    from drive_envelope._src.teststand import batch

    if backend == "warp":
        from drive_envelope.warp import clamp_drive_impulse as port

        def clamp(*args: Any) -> np.ndarray:
            return np.asarray(port(*args), dtype=np.float64)
    else:
        import torch

        from drive_envelope.torch import clamp_drive_impulse as port

        def clamp(*args: Any) -> np.ndarray:
            tensors = (torch.as_tensor(np.asarray(a, dtype=np.float32)) for a in args)
            return port(*tensors).numpy().astype(np.float64)

    with mock.patch.object(batch, "clamp_drive_impulse", clamp):
        yield


def _runner(engine: str) -> Callable[[object], object]:
    from drive_envelope.teststand import simulate

    if engine in ("warp", "torch"):

        def run(scenario: object) -> object:
            with _clamp(engine):
                return simulate(scenario, "reference")  # type: ignore[arg-type]

        return run
    if engine == "mujoco":
        from drive_envelope._src.adapters.mujoco import build, loader

        try:
            loader.load_plugin()
        except build.PluginError:
            build.build_plugin(quiet=True)
            loader.load_plugin()
    return lambda scenario: simulate(scenario, engine)  # type: ignore[arg-type]


def measure(
    engines: Sequence[str],
    files: Sequence[Path] | None = None,
    known: Mapping[tuple[str, str], object] | None = None,
) -> list[Row]:
    """Run every scenario on the reference and on each engine; one row per (scenario, engine).

    ``known`` holds runs already made, by (engine, file stem): the tests pass PhysX's runs of the
    bundled scenarios, which they make once per test run for every module that needs them.
    """
    from drive_envelope.teststand import load_scenario, simulate

    rows = []
    runners = {engine: _runner(engine) for engine in engines}
    for file in files or sorted(SCENARIOS.glob("*.toml")):
        scenario = load_scenario(file)
        ref = simulate(scenario, "reference")
        for engine, run in runners.items():
            tol = tolerances(engine, scenario, ref)
            out = (known or {}).get((engine, file.stem))
            out = run(scenario) if out is None else out
            diffs = (
                float(np.abs(out.velocity - ref.velocity).max()),  # type: ignore[attr-defined]
                float(np.abs(out.effort - ref.effort).max()),  # type: ignore[attr-defined]
                float(np.abs(out.position - ref.position).max()),  # type: ignore[attr-defined]
            )
            rows.append(
                Row(
                    scenario=file.stem,
                    solver=scenario.simulation.solver,
                    engine=engine,
                    velocity=diffs[0],
                    effort=diffs[1],
                    position=diffs[2],
                    ratio=max(d / t for d, t in zip(diffs, tol, strict=True)),
                )
            )
    return rows


def _number(value: float) -> str:
    return "0" if value == 0.0 else f"{value:.1e}"


def render(rows: Sequence[Row]) -> str:
    """The Markdown table (between the markers of docs/parity.md)."""
    lines = [
        BEGIN,
        "| scenario | solver | engine | max \\|Δv\\| [rad/s, m/s] | max \\|Δeffort\\| [N*m, N] | "
        "max \\|Δq\\| [rad, m] | worst / tolerance | held |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for row in rows:
        verdict = ("pass" if row.ratio <= 1.0 else "FAIL") if row.held else "shown"
        lines.append(
            f"| {row.scenario} | {row.solver} | {row.engine} | {_number(row.velocity)} "
            f"| {_number(row.effort)} "
            f"| {_number(row.position)} | {row.ratio:.2g} | {verdict} |"
        )
    lines.append(END)
    return "\n".join(lines)


def documented(text: str) -> dict[tuple[str, str], tuple[float, float, float]]:
    """The (scenario, engine) -> (velocity, effort, position) numbers of docs/parity.md's table."""
    body = text.split(BEGIN, 1)[1].split(END, 1)[0]
    table = {}
    for line in body.strip().splitlines()[2:]:
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        table[(cells[0], cells[2])] = (float(cells[3]), float(cells[4]), float(cells[5]))
    return table


def write(rows: Sequence[Row]) -> None:
    """Replace the table of docs/parity.md with ``rows``."""
    text = DOC.read_text(encoding="utf-8")
    head, rest = text.split(BEGIN, 1)
    DOC.write_text(head + render(rows) + rest.split(END, 1)[1], encoding="utf-8")


CHAINS = sorted((Path(__file__).resolve().parent.parent / "examples" / "scenarios" / "chains").glob("*.toml"))
"""The multi-DOF scenario files of the robot-scale table (``--chains``)."""
CHAIN_BEGIN, CHAIN_END = "<!-- chain-table:begin -->", "<!-- chain-table:end -->"


def _robot_chains() -> object:
    """``benchmarks/robot_chains.py`` (the FR3 and Go2 stands built from ../shared/data)."""
    spec = importlib.util.spec_from_file_location("robot_chains", Path(__file__).with_name("robot_chains.py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def chain_scenarios() -> list[object]:
    """The robot-scale scenarios: the chain files, then each robot stand whose asset is here (PGS, TGS)."""
    from drive_envelope._src.scenario.chain import load_stand

    robots: Any = _robot_chains()
    found: list[object] = [load_stand(path) for path in CHAINS]
    for robot in robots.ROBOTS:
        if robots.available(robot):
            found.extend(robots.scenario(robot, solver) for solver in robots.SOLVERS)
    return found


def released_joint(scenario: object, velocity: object) -> int:
    """The joint that goes furthest past its speed line (``max |v| / max_actuator_velocity``)."""
    ratios = []
    for index, joint in enumerate(scenario.joints):  # type: ignore[attr-defined]
        envelope = joint.effective_envelope()
        speed = math.inf if envelope is None else envelope.max_actuator_velocity
        ratios.append(float(np.abs(np.asarray(velocity)[:, index]).max()) / speed)
    return int(np.argmax(ratios))


def release_step(effort: object, max_effort: float) -> int:
    """First step at which a joint's drive effort is 0 (|effort| < 1e-4 * max_effort): it let go."""
    hits = np.flatnonzero(np.abs(np.asarray(effort)[1:]) < 1e-4 * max_effort)
    return int(hits[0]) + 1 if hits.size else -1


@dataclass(frozen=True, kw_only=True, slots=True)
class ChainRow:
    """One engine on one multi-DOF scenario against real PhysX."""

    scenario: str
    engine: str
    joint: str
    """The joint that meets its speed line and lets go."""
    before: float
    """Largest |velocity - PhysX's| over every joint before PhysX's release step [rad/s or m/s]."""
    release: int
    """The engine's release step (-1: it never let go)."""
    physx_release: int
    """PhysX's release step."""
    after: float
    """Largest |velocity - PhysX's| over every joint from the release step on [rad/s or m/s]."""


def chain_measure(engines: Sequence[str], scenarios: Sequence[object] | None = None) -> list[ChainRow]:
    """Run each robot-scale scenario on real PhysX and on each engine; one row per (scenario, engine)."""
    from drive_envelope._src.teststand.engines import simulate

    rows = []
    for scenario in chain_scenarios() if scenarios is None else scenarios:
        physx: Any = simulate(scenario, "physx")  # type: ignore[call-overload]
        index = released_joint(scenario, physx.velocity)
        joint = scenario.joints[index]  # type: ignore[attr-defined]
        limit = joint.drive.max_effort
        released = release_step(physx.effort[:, index], limit)
        for engine in engines:
            run: Any = simulate(scenario, engine)  # type: ignore[call-overload]
            dv = np.abs(run.velocity - physx.velocity).max(axis=1)
            rows.append(
                ChainRow(
                    scenario=scenario.name,  # type: ignore[attr-defined]
                    engine=engine,
                    joint=joint.name,
                    before=float(dv[:released].max()),
                    release=release_step(run.effort[:, index], limit),
                    physx_release=released,
                    after=float(dv[released:].max()),
                )
            )
    return rows


def chain_render(rows: Sequence[ChainRow]) -> str:
    """The robot-scale Markdown table (between the chain markers of docs/parity.md)."""
    lines = [
        CHAIN_BEGIN,
        "| scenario | engine | joint at its speed line | max \\|dv\\| before release [rad/s] | "
        "release step (physx) | max \\|dv\\| after [rad/s] |",
        "|---|---|---|---|---|---|",
    ]
    for row in rows:
        lines.append(
            f"| {row.scenario} | {row.engine} | {row.joint} | {row.before:.2g} | "
            f"{row.release} ({row.physx_release}) | {row.after:.2g} |"
        )
    lines.append(CHAIN_END)
    return "\n".join(lines)


def chain_documented(text: str) -> dict[tuple[str, str], tuple[float, int, int, float]]:
    """(scenario, engine) -> (before, release, PhysX's release, after) of docs/parity.md's chain table."""
    body = text.split(CHAIN_BEGIN, 1)[1].split(CHAIN_END, 1)[0]
    table = {}
    for line in body.strip().splitlines()[2:]:
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        own, physx = cells[4].replace(")", "").split(" (")
        table[(cells[0], cells[1])] = (float(cells[3]), int(own), int(physx), float(cells[5]))
    return table


def chain_write(rows: Sequence[ChainRow]) -> None:
    """Replace the robot-scale table of docs/parity.md with ``rows``."""
    text = DOC.read_text(encoding="utf-8")
    head, rest = text.split(CHAIN_BEGIN, 1)
    DOC.write_text(head + chain_render(rows) + rest.split(CHAIN_END, 1)[1], encoding="utf-8")


def chain_rows(engines: Sequence[str]) -> str:
    """The robot-scale table: per multi-DOF scenario and engine, against real PhysX.

    Each row: the joint that meets its speed line, max |dv| over every joint before PhysX lets
    that joint go, the engine's release step (PhysX's beside), max |dv| after. PhysX's drive effort
    is recovered from its joint states.
    """
    return chain_render(chain_measure(engines))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="write the table into docs/parity.md")
    parser.add_argument("--engines", default=",".join(ENGINES), help="comma-separated engines")
    parser.add_argument(
        "--chains",
        action="store_true",
        help="the robot-scale table (multi-DOF chains vs real PhysX; with --write, into docs/parity.md)",
    )
    args = parser.parse_args()
    if args.chains:
        chain_table = chain_measure(["reference", *(["mujoco"] if available("mujoco") else [])])
        print(chain_render(chain_table))
        if args.write:
            chain_write(chain_table)
            print(f"wrote {DOC}")
        return
    engines = [name for name in args.engines.split(",") if name]
    missing = [name for name in engines if not available(name)]
    if missing:
        sys.exit(f"engines not installed here: {', '.join(missing)}")
    rows = measure(engines)
    print(render(rows))
    failed = [row for row in rows if row.held and not row.ratio <= 1.0]
    if args.write:
        write(rows)
        print(f"wrote {DOC}")
    if failed or any(math.isnan(row.ratio) for row in rows):
        sys.exit(f"{len(failed)} held row(s) above their tolerance")


if __name__ == "__main__":
    main()

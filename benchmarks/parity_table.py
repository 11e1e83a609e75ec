"""One model, every engine: the largest per-step difference of each engine against the reference.

Runs every shipped test-stand scenario (``examples/scenarios/*.toml``) on the ``reference`` engine
(the float64 model of PhysX's solver) and on each other engine installed here:

* ``physx``: real PhysX 5.6 (ovphysx 0.7, CPU, float32), the engine the model is of;
* ``mujoco``: the ``drive_envelope.envelope`` plugin (C++, float64), one implicit solve per step;
* ``newton``: Newton's ``DrivePD`` + ``ClampingPerformanceEnvelope`` in implicit mode on
  ``SolverFeatherstone`` (float32);
* ``warp`` / ``torch``: the reference's own solver loop with its NumPy ``clamp_drive_impulse``
  replaced by the Warp / torch port in float32, closed loop (each step starts from the state the
  float32 clamp produced): the batched clamps on the exact calls the solver makes.

For each scenario and engine it reports the largest ``|difference|`` over all steps of velocity,
effort and position, and the worst of the three divided by its tolerance; ``<= 1`` passes. The
tolerances are those of the engines' own tests: the mujoco engine's (velocity ``1e-5 +
5e-5*max|v|``, effort ``1e-4 + 1e-3*max_effort``, position ``1e-5 + 1e-4*path length``) for
mujoco, newton, warp and torch; ``3e-3 * max(1, max|column|)`` for real PhysX, whose float32
noise is amplified about a thousandfold by braking along eq. 2 (``tests/test_teststand_physx.py``).
mujoco and newton take one solve per step, so on TGS scenarios only their steady states agree
(``docs/teststand.md``); their TGS rows are shown, not held to the tolerance.
``docs/parity.md`` is written by this script (``--write``) and checked by
``tests/test_parity_engines.py``.

    .venv/bin/python benchmarks/parity_table.py [--write] [--engines physx,mujoco,newton,warp,torch]
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from unittest import mock

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "examples" / "scenarios"
DOC = ROOT / "docs" / "parity.md"
ENGINES = ("physx", "mujoco", "newton", "warp", "torch")
HELD_ON_TGS = ("physx", "warp", "torch")
"""Engines that model TGS as PhysX runs it (the others take one solve per step)."""
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
    if engine == "physx":
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
    """The reference engine with its clamp replaced by the Warp or torch port (float32)."""
    from drive_envelope._src.teststand.engines import reference

    if backend == "warp":
        from drive_envelope.warp import clamp_drive_impulse as port

        def clamp(*args: float) -> float:
            return float(np.asarray(port(*args))[0])
    else:
        import torch

        from drive_envelope.torch import clamp_drive_impulse as port

        def clamp(*args: float) -> float:
            return float(port(*(torch.tensor(float(a), dtype=torch.float32) for a in args)))

    with mock.patch.object(reference, "clamp_drive_impulse", clamp):
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


def measure(engines: Sequence[str], files: Sequence[Path] | None = None) -> list[Row]:
    """Run every scenario on the reference and on each engine; one row per (scenario, engine)."""
    from drive_envelope.teststand import load_scenario, simulate

    rows = []
    runners = {engine: _runner(engine) for engine in engines}
    for file in files or sorted(SCENARIOS.glob("*.toml")):
        scenario = load_scenario(file)
        ref = simulate(scenario, "reference")
        for engine, run in runners.items():
            tol = tolerances(engine, scenario, ref)
            out = run(scenario)
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
"""The multi-DOF scenarios of the robot-scale table (``--chains``)."""


def _release(effort: object, max_effort: float) -> int:
    """First step at which a joint's drive effort is 0 (|effort| < 1e-4 * max_effort): it let go."""
    import numpy as np

    hits = np.flatnonzero(np.abs(np.asarray(effort)[1:]) < 1e-4 * max_effort)
    return int(hits[0]) + 1 if hits.size else -1


def chain_rows(engines: Sequence[str]) -> str:
    """The robot-scale table: per chain scenario and engine, against real PhysX, on the first joint.

    Each row: max |dv| over every joint before the first joint lets go, its release step (PhysX's
    beside), max |dv| after. PhysX's drive effort is recovered from its joint states.
    """
    import numpy as np

    from drive_envelope._src.scenario.chain import load_stand
    from drive_envelope._src.teststand.engines import simulate

    lines = [
        "| scenario | engine | max \\|dv\\| before release [rad/s] | release step (physx) | "
        "max \\|dv\\| after [rad/s] |",
        "|---|---|---|---|---|",
    ]
    for path in CHAINS:
        scenario = load_stand(path)
        physx = simulate(scenario, "physx")
        limit = scenario.joints[0].drive.max_effort
        released = _release(physx.effort[:, 0], limit)
        for engine in engines:
            run = simulate(scenario, engine)
            dv = np.abs(run.velocity - physx.velocity).max(axis=1)
            own = _release(run.effort[:, 0], limit)
            lines.append(
                f"| {scenario.name} | {engine} | {dv[:released].max():.2g} | {own} ({released}) | "
                f"{dv[released:].max():.2g} |"
            )
    return "\n".join(lines).replace("\\\\", "\\")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="write the table into docs/parity.md")
    parser.add_argument("--engines", default=",".join(ENGINES), help="comma-separated engines")
    parser.add_argument(
        "--chains", action="store_true", help="print the robot-scale table (multi-DOF chains vs real PhysX)"
    )
    args = parser.parse_args()
    if args.chains:
        print(chain_rows(["reference", *(["mujoco"] if available("mujoco") else [])]))
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

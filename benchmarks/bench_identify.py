"""identify against BAM on the same bench logs: held-out error and wall time, side by side.

The data are Rhoban's 16 XL330 pendulum logs in ``../shared/data/bam/logs`` (each JSON sidecar names
its split: 12 ``train``, 4 ``holdout``). drive-envelope's ``identify`` fits the envelope model on the
training logs and replays the holdout logs; BAM (``better-actuator-models``, Python >= 3.12, in its own
environment: ``--bam-python``) fits its models on the same training logs, from its own processed JSON
logs of the same recordings (``--bam-logs``), with a stated trial budget (``--bam-trials``; BAM's
default is 100 000, about 70 minutes for M1 on this machine), and ``bam.mae`` scores them on the
holdout logs. BAM's shipped XL330 parameters (fitted on BAM's own, larger data set) are scored too.

Rounds are interleaved (identify, BAM, identify, BAM, ...) and wall times reported as medians ("+-" is
the spread over the held-out logs; the last column each round's held-out mean). Without BAM's
environment the BAM rows are left blank with a message. Errors are mean absolute position errors
over each log's rows, averaged over logs, in mrad (BAM truncates every log of a batch to the
shortest, 1200 rows; identify scores every row: the difference is below 0.1 %).

    python benchmarks/bench_identify.py                      # identify, and BAM when /tmp/bam/venv312 exists
    python benchmarks/bench_identify.py --bam-trials 3000 --rounds 3 --seeds 0,1,2
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data" / "bam" / "logs"
STAND = REPO / "examples" / "bam" / "xl330_pendulum.toml"
ENVELOPE_FIT = (
    "max_effort,max_actuator_velocity,velocity_dependent_resistance,speed_effort_gradient,"
    "damping,static_friction,viscous_friction,armature,angle_offset"
)


def split_logs(folder: Path) -> dict[str, list[Path]]:
    """The logs of ``folder`` by their sidecar's ``split``."""
    splits: dict[str, list[Path]] = {"train": [], "holdout": []}
    for sidecar in sorted(folder.glob("*.json")):
        split = json.loads(sidecar.read_text(encoding="utf-8")).get("split")
        if split in splits:
            splits[split].append(sidecar.with_suffix(".csv"))
    return splits


def run_identify(
    splits: dict[str, list[Path]],
    fit: str,
    seed: int,
    generations: int,
    restarts: int = 3,
    stand: Path = STAND,
) -> dict[str, object]:
    """One identification; its errors [mrad], wall time [s] and whether each reported line binds."""
    from drive_envelope._src.identify.canonical import binding_lines
    from drive_envelope.identify import SearchOptions, identify

    started = time.perf_counter()
    result = identify(
        splits["train"],
        stand,
        validate=splits["holdout"],
        fit=fit.split(","),
        options=SearchOptions(seed=seed, generations=generations, restarts=restarts),
    )
    wall = time.perf_counter() - started
    holdout = [1e3 * e.mae_position for e in result.validation]
    return {
        "train": 1e3 * float(np.mean([e.mae_position for e in result.train])),
        "holdout": float(np.mean(holdout)),
        "holdout_std": float(np.std(holdout)),
        "per_log": dict(zip([e.log.name for e in result.validation], holdout, strict=True)),
        "wall": wall,
        "values": {name: estimate.value for name, estimate in result.parameters.items()},
        "binds": binding_lines({name: estimate.value for name, estimate in result.parameters.items()}),
        "spread": {
            name: estimate.spread
            for name, estimate in result.parameters.items()
            if estimate.spread is not None
        },
    }


def bam_folders(bam_logs: Path, splits: dict[str, list[Path]], work: Path) -> dict[str, Path]:
    """BAM's processed logs of the same recordings, split as the sidecars say (copied to ``work``)."""
    folders = {}
    for split, logs in splits.items():
        folder = work / split
        folder.mkdir(parents=True, exist_ok=True)
        for log in logs:
            source = bam_logs / f"{log.stem}.json"
            if not source.is_file():
                raise SystemExit(f"bench_identify: BAM log {source} missing (--bam-logs)")
            shutil.copy(source, folder / source.name)
        folders[split] = folder
    return folders


def bam_mae(python: str, params: Path, logdir: Path, work: Path) -> dict[str, object]:
    """``bam.mae`` of one parameter file on one folder: mean, std and per-log errors [mrad]."""
    folder = work / f"params_{params.parent.name}_{params.stem}"  # bam.mae reads a folder of files
    folder.mkdir(exist_ok=True)
    shutil.copy(params, folder / params.name)
    out = work / f"mae_{folder.name}_{logdir.name}.json"
    subprocess.run(
        [python, "-m", "bam.mae", "--params", str(folder), "--logdir", str(logdir), "--json", str(out)],
        check=True,
        cwd=work,
        capture_output=True,
    )
    scores = json.loads(out.read_text(encoding="utf-8"))
    score = next(iter(scores.values()))
    return {
        "mean": 1e3 * score["mean"],
        "std": 1e3 * score["std"],
        "per_log": [1e3 * x for x in score["per_log"]],  # in BAM's (directory) order
    }


def run_bam(python: str, model: str, folders: dict[str, Path], trials: int, work: Path) -> dict[str, object]:
    """One ``bam.fit`` on the training folder; its wall time [s] and errors [mrad]."""
    params = work / "fitted" / f"{model}.json"
    params.parent.mkdir(exist_ok=True)
    command = [
        python, "-m", "bam.fit", "--actuator", "xl330", "--model", model,
        "--logdir", str(folders["train"]), "--trials", str(trials), "--output", str(params),
    ]  # fmt: skip
    started = time.perf_counter()
    subprocess.run(command, check=True, cwd=work, capture_output=True)
    wall = time.perf_counter() - started
    holdout = bam_mae(python, params, folders["holdout"], work)
    train = bam_mae(python, params, folders["train"], work)
    return {
        "train": train["mean"],
        "holdout": holdout["mean"],
        "holdout_std": holdout["std"],
        "per_log": holdout["per_log"],
        "wall": wall,
    }


def bam_shipped(python: str, model: str, folders: dict[str, Path], work: Path) -> dict[str, object] | None:
    """BAM's shipped xl330 parameters (fitted on BAM's own data) on the holdout folder."""
    found = subprocess.run(
        [python, "-c", "import bam, pathlib; print(pathlib.Path(bam.__file__).parent / 'params' / 'xl330')"],
        check=True,
        capture_output=True,
        text=True,
    )
    params = Path(found.stdout.strip()) / f"{model}.json"
    if not params.is_file():
        return None
    holdout = bam_mae(python, params, folders["holdout"], work)
    train = bam_mae(python, params, folders["train"], work)
    return {"train": train["mean"], "holdout": holdout["mean"], "holdout_std": holdout["std"]}


def _print_table(runs: dict[str, list[dict[str, object]]], shipped: dict[str, dict[str, object] | None],
                 args: argparse.Namespace, have_bam: bool) -> None:  # fmt: skip
    header = f"{'model':44s} {'train':>7s} {'holdout':>8s} {'+-':>6s} {'wall [s]':>9s}  holdout per round"
    print(header)
    print("-" * len(header))
    for name, items in runs.items():
        if name == "identify":
            label = f"identify, envelope model ({len(args.fit.split(','))} parameters)"
        else:
            label = f"BAM {name.split()[1].upper()} fitted here ({args.bam_trials} trials)"
        median = {
            key: statistics.median(float(item[key]) for item in items)  # type: ignore[arg-type]
            for key in ("train", "holdout", "wall")
        }
        spread = statistics.median(float(item["holdout_std"]) for item in items)  # type: ignore[arg-type]
        rounds = " ".join(f"{float(item['holdout']):.1f}" for item in items)  # type: ignore[arg-type]
        print(f"{label:44s} {median['train']:7.1f} {median['holdout']:8.1f} {spread:6.1f} "
              f"{median['wall']:9.1f}  {rounds}")  # fmt: skip
    for model, row in shipped.items():
        if row is not None:
            label = f"BAM {model.upper()} shipped (BAM data)"
            print(f"{label:44s} {float(row['train']):7.1f} {float(row['holdout']):8.1f} "  # type: ignore[arg-type]
                  f"{float(row['holdout_std']):6.1f} {'-':>9s}")  # type: ignore[arg-type]  # fmt: skip
    if not have_bam:
        print(f"{'BAM M1 fitted here':44s} {'-':>7s} {'-':>8s} {'-':>6s} {'-':>9s}  (BAM not installed)")


def _print_seed_study(items: list[dict[str, object]]) -> None:
    """identify's answer across seeds: held-out spread, the envelope, whether each line binds."""
    if len(items) < 2:
        return
    holdout = [float(item["holdout"]) for item in items]  # type: ignore[arg-type]
    print(f"\nidentify across {len(items)} seeds: held-out median {statistics.median(holdout):.2f} mrad, "
          f"max - min {max(holdout) - min(holdout):.2f} mrad")  # fmt: skip
    names = ("max_effort", "max_actuator_velocity", "velocity_dependent_resistance", "speed_effort_gradient",
             "duty_effort")  # fmt: skip
    for name in names:
        values = [float(item["values"][name]) for item in items if name in item["values"]]  # type: ignore[index, operator]
        if values:
            print(f"  {name:30s} " + " ".join(f"{value:.4g}" for value in values))
    binds = [dict(item["binds"]) for item in items]  # type: ignore[call-overload]
    print(
        "  every reported line binds: " + ", ".join("yes" if all(b.values()) else f"no ({b})" for b in binds)
    )


def main(argv: list[str] | None = None) -> int:
    """Run the comparison and print the table."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA, help="folder of the CSV logs and sidecars")
    parser.add_argument("--bam-python", default="/tmp/bam/venv312/bin/python", help="BAM's Python (>= 3.12)")
    parser.add_argument("--bam-logs", type=Path, default=Path("/tmp/bam/data/processed"),
                        help="BAM's processed JSON logs of the same recordings")  # fmt: skip
    parser.add_argument(
        "--bam-trials", type=int, default=3000, help="optuna trials per BAM fit (BAM: 100000)"
    )
    parser.add_argument("--bam-models", default="m1", help="BAM models to fit, comma-separated (m1..m6)")
    parser.add_argument("--rounds", type=int, default=1, help="interleaved rounds (medians reported)")
    parser.add_argument("--seeds", default="0", help="identify seeds, one per round (cycled)")
    parser.add_argument("--generations", type=int, default=60, help="identify's generations")
    parser.add_argument("--restarts", type=int, default=3, help="identify's restarts (default 3)")
    parser.add_argument("--fit", default=ENVELOPE_FIT, help="identify's --fit")
    parser.add_argument("--stand", type=Path, default=STAND, help="identify's stand (a variant to compare)")
    parser.add_argument("--json", type=Path, default=None, help="also write the results as JSON")
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"bench_identify: {args.data} is absent (the shared BAM logs); nothing to do", file=sys.stderr)
        return 0
    splits = split_logs(args.data)
    seeds = [int(s) for s in args.seeds.split(",")]
    have_bam = Path(args.bam_python).is_file() and args.bam_logs.is_dir()
    if not have_bam:
        print(f"bench_identify: BAM not found ({args.bam_python}, {args.bam_logs}): BAM's rows are left "
              "blank; install better-actuator-models in a Python >= 3.12 environment and pass --bam-python",
              file=sys.stderr)  # fmt: skip
    runs: dict[str, list[dict[str, object]]] = {}
    shipped: dict[str, dict[str, object] | None] = {}
    with tempfile.TemporaryDirectory(prefix="bench-identify-") as tmp:
        work = Path(tmp)
        folders = bam_folders(args.bam_logs, splits, work) if have_bam else {}
        for round_index in range(args.rounds):
            seed = seeds[round_index % len(seeds)]
            print(f"round {round_index + 1}: identify (seed {seed})", file=sys.stderr)
            runs.setdefault("identify", []).append(
                run_identify(splits, args.fit, seed, args.generations, args.restarts, args.stand)
            )
            for model in args.bam_models.split(",") if have_bam else ():
                print(f"round {round_index + 1}: bam.fit {model} ({args.bam_trials} trials)", file=sys.stderr)
                result = run_bam(args.bam_python, model, folders, args.bam_trials, work)
                runs.setdefault(f"bam {model}", []).append(result)
        for model in args.bam_models.split(",") if have_bam else ():
            shipped[model] = bam_shipped(args.bam_python, model, folders, work)
    print(f"{len(splits['train'])} training logs, {len(splits['holdout'])} held-out logs; "
          f"{args.rounds} round(s), medians; errors in mrad")  # fmt: skip
    _print_table(runs, shipped, args, have_bam)
    _print_seed_study(runs.get("identify", []))
    if args.json is not None:
        args.json.write_text(
            json.dumps({"runs": runs, "shipped": shipped}, indent=1) + "\n", encoding="utf-8"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())

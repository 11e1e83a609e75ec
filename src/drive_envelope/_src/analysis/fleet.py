"""Checking a fleet's logs: a folder, a glob or a partitioned Parquet dataset, one report per part, merged.

A fleet outgrows one process: each part (a log file, a ROS 2 bag folder, a Parquet part file) is
checked on its own (:func:`check_part`, streaming in bounded memory as one log is), and the part
reports are merged (:func:`merge_reports`) into one :class:`~.report.CheckReport` per joint name.
The merge is exact and associative: counts, durations and times on a limit add up, minimums take
the least, the margin histograms (0.1 % of the cap per bin) add up and give the quantiles again,
and the worst violation is the largest one, named with the part it came from (its row and time
are that part's).

Parts are found by :func:`fleet_parts`: every log below a folder (``.csv``, ``.tsv``, ``.txt``,
their ``.gz``, ``.parquet``, ``.pq``, and rosbag2 folders; JSON sidecars are not logs), the
matches of a glob (``logs/**/*.parquet``), or the part files of a partitioned Parquet dataset,
whose ``joint=NAME`` folder (hive partitioning) gives the joint of a part without a joint column.

:func:`check_fleet` runs in this process by default, part after part; with ``scheduler`` (the
address of a running Dask distributed scheduler, ``tcp://host:8786``) the parts are checked on
its workers and only the small reports (about 32 KiB per joint) travel back to be merged.
"""

from __future__ import annotations

import glob
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from drive_envelope._src.analysis.check import histogram_quantile, margin_scale
from drive_envelope._src.analysis.log_bag import is_bag
from drive_envelope._src.analysis.log_model import LogColumns
from drive_envelope._src.analysis.mapping import JointMapping
from drive_envelope._src.analysis.report import (
    MARGIN_QUANTILES,
    CheckOptions,
    CheckReport,
    JointCheck,
    MarginSummary,
    Violation,
)
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError

LOG_SUFFIXES = (".csv", ".tsv", ".txt", ".parquet", ".pq")
"""File endings a fleet folder's logs have (each also ``.gz`` but Parquet)."""
_GLOB = set("*?[")


@dataclass(frozen=True, kw_only=True, slots=True)
class FleetRun:
    """A fleet check: the merged report and how it was computed."""

    report: CheckReport
    """The merged report (``parts`` logs)."""
    parts: tuple[str, ...]
    """The parts, in the order merged."""
    rows: int
    """Samples checked over all parts and joints."""
    wall_time_s: float
    """Time of the whole check [s]."""
    merge_time_s: float
    """Time of the merge alone [s]."""
    workers: int
    """Dask workers used (0: in this process)."""


def is_fleet(spec: str | os.PathLike[str]) -> bool:
    """Whether ``spec`` names several logs: a folder that is not a bag, or a glob pattern."""
    text = str(spec)
    if _GLOB & set(text) and not Path(text).exists():
        return True
    return Path(text).is_dir() and not is_bag(text)


def _is_log(path: Path) -> bool:
    name = path.name.lower()
    if name.endswith(".gz"):
        name = name[:-3]
    return (
        path.is_file() and any(name.endswith(suffix) for suffix in LOG_SUFFIXES) and not name.startswith(".")
    )


def fleet_parts(spec: str | os.PathLike[str]) -> list[str]:
    """The logs of a folder, a glob pattern or a partitioned dataset, sorted by path.

    Raises:
        InputError: nothing matches, or the folder holds no log.
    """
    text = str(spec)
    if _GLOB & set(text) and not Path(text).exists():
        found = sorted(glob.glob(text, recursive=True))
        parts = [p for p in found if (is_bag(p) and Path(p).is_dir()) or _is_log(Path(p))]
        if not parts:
            raise InputError(
                f"{text}: the pattern matches no log (.csv, .parquet, ... or a ROS 2 bag folder)"
            )
        return parts
    root = Path(text)
    if not root.is_dir():
        if not root.exists():
            raise InputError(f"{text}: no such file or folder")
        return [text]
    if is_bag(root):
        return [text]
    parts = []
    for folder, subfolders, files in os.walk(root):
        here = Path(folder)
        bags = [name for name in subfolders if is_bag(here / name)]
        parts.extend(str(here / name) for name in bags)
        subfolders[:] = sorted(name for name in subfolders if name not in bags and not name.startswith("."))
        parts.extend(str(here / name) for name in files if _is_log(here / name))
    if not parts:
        raise InputError(
            f"{text}: the folder holds no log (.csv, .tsv, .txt, .gz, .parquet, .pq or a ROS 2 bag)"
        )
    return sorted(parts)


def _partition_joint(part: str, columns: LogColumns) -> str | None:
    """The ``joint=NAME`` folder of a hive-partitioned Parquet part, when its column is the joint."""
    key = f"{columns.joint}=" if columns.joint else None
    if key is None:
        return None
    for folder in reversed(Path(part).parent.parts):
        if folder.startswith(key):
            return folder[len(key) :]
    return None


def check_part(
    envelopes: PerformanceEnvelope | JointMapping,
    part: str,
    columns: LogColumns,
    options: CheckOptions,
) -> CheckReport:
    """Check one part of a fleet (runs on a Dask worker too: only picklable arguments)."""
    from drive_envelope._src.analysis.check import check_chunks
    from drive_envelope._src.analysis.logs import iter_log

    source: Any = part
    joint = _partition_joint(part, columns) if part.lower().endswith((".parquet", ".pq")) else None
    if joint is not None:
        import pyarrow.parquet as pq

        table = pq.read_table(part)
        if columns.joint not in table.column_names:
            import pyarrow as pa

            source = table.append_column(
                columns.joint, pa.array([joint] * table.num_rows).dictionary_encode()
            )
    chunks = iter_log(source, columns)
    return check_chunks(chunks, envelopes, options=options, source=part)


def _add(a: float | None, b: float | None) -> float | None:
    if a is None:
        return b
    return a if b is None else a + b


def _worst(a: Violation | None, b: Violation | None) -> Violation | None:
    if a is None:
        return b
    if b is None:
        return a
    return b if b.excess > a.excess else a


def _margins(a: MarginSummary, b: MarginSummary, samples: int) -> MarginSummary:
    if a.histogram is None or b.histogram is None:
        raise InputError("merge: a part report without its margin histogram (made by another version?)")
    histogram = a.histogram + b.histogram
    minimum = min(a.minimum, b.minimum)
    scale = margin_scale(a.cap)
    return replace(
        a,
        minimum=minimum,
        quantiles=tuple(
            (p, histogram_quantile(histogram, minimum, scale, p, samples)) for p in MARGIN_QUANTILES
        ),
        samples_outside=a.samples_outside + b.samples_outside,
        samples_on_limit=a.samples_on_limit + b.samples_on_limit,
        time_on_limit=_add(a.time_on_limit, b.time_on_limit),
        worst=_worst(a.worst, b.worst),
        histogram=histogram,
    )


def _merge_joint(a: JointCheck, b: JointCheck) -> JointCheck:
    if a.envelope != b.envelope:
        raise InputError(f"merge: joint {a.joint!r} has two envelopes in the parts; expected one per joint")
    samples = a.samples + b.samples
    velocity = None
    if a.velocity is not None and b.velocity is not None:
        velocity = _margins(a.velocity, b.velocity, samples)
    return replace(
        a,
        samples=samples,
        samples_outside=a.samples_outside + b.samples_outside,
        duration=_add(a.duration, b.duration),
        time_outside=_add(a.time_outside, b.time_outside),
        effort=_margins(a.effort, b.effort, samples),
        velocity=velocity,
        points=None,
        samples_released=a.samples_released + b.samples_released,
        time_released=_add(a.time_released, b.time_released),
        time_resets=a.time_resets + b.time_resets,
        first_time_reset=a.first_time_reset if a.first_time_reset is not None else b.first_time_reset,
    )


def _sourced(check: JointCheck, source: str) -> JointCheck:
    """The joint's worst violations named with the part they are in."""

    def named(summary: MarginSummary | None) -> MarginSummary | None:
        if summary is None or summary.worst is None or summary.worst.source is not None:
            return summary
        return replace(summary, worst=replace(summary.worst, source=source))

    effort = named(check.effort)
    assert effort is not None
    return replace(check, effort=effort, velocity=named(check.velocity))


def merge_reports(reports: Sequence[CheckReport], source: str) -> CheckReport:
    """One report of many parts' (joints by name, in order of first appearance).

    Raises:
        InputError: no report, different thresholds, or one joint with two envelopes.
    """
    if not reports:
        raise InputError(f"{source}: no part to merge")
    options = reports[0].options
    joints: dict[str, JointCheck] = {}
    unused = None
    parts = 0
    for report in reports:
        if report.options != options:
            raise InputError(f"{source}: the parts were checked with different thresholds")
        parts += report.parts
        for check in report.joints:
            check = _sourced(check, report.source)
            joints[check.joint] = _merge_joint(joints[check.joint], check) if check.joint in joints else check
        keys = {unused_key.key: unused_key for unused_key in report.unused_keys}
        unused = keys if unused is None else {key: value for key, value in unused.items() if key in keys}
    return CheckReport(
        source=source,
        joints=tuple(joints.values()),
        options=options,
        unused_keys=tuple((unused or {}).values()),
        parts=parts,
    )


def check_fleet(
    envelopes: PerformanceEnvelope | JointMapping,
    spec: str | os.PathLike[str],
    *,
    columns: LogColumns | None = None,
    options: CheckOptions | None = None,
    scheduler: str | None = None,
) -> FleetRun:
    """Check every part of a fleet and merge the reports.

    Args:
        envelopes: One envelope for every joint, or a joint mapping.
        spec: A folder, a glob pattern or a partitioned Parquet dataset (see :func:`fleet_parts`).
        columns: Column names (and bag topics), as for one log.
        options: Thresholds (``keep_points`` is not used: a fleet keeps no plot points).
        scheduler: Address of a running Dask distributed scheduler; None: in this process.

    Raises:
        InputError: no part, a bad part (naming it), a joint without envelope, dask missing or a
            scheduler that cannot be reached.
    """
    started = time.perf_counter()
    columns = columns or LogColumns()
    options = replace(options or CheckOptions(), keep_points=0)
    parts = fleet_parts(spec)
    workers = 0
    if scheduler is None:
        reports = [check_part(envelopes, part, columns, options) for part in parts]
    else:
        reports, workers = _on_cluster(scheduler, envelopes, parts, columns, options)
    merging = time.perf_counter()
    report = merge_reports(reports, str(spec))
    done = time.perf_counter()
    return FleetRun(
        report=report,
        parts=tuple(parts),
        rows=sum(joint.samples for joint in report.joints),
        wall_time_s=done - started,
        merge_time_s=done - merging,
        workers=workers,
    )


def _on_cluster(
    scheduler: str,
    envelopes: PerformanceEnvelope | JointMapping,
    parts: list[str],
    columns: LogColumns,
    options: CheckOptions,
) -> tuple[list[CheckReport], int]:
    try:
        from distributed import Client
    except ImportError:
        raise InputError("--scheduler needs dask distributed: pip install 'drive-envelope[fleet]'") from None
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise InputError(f"--scheduler {scheduler!r}: cannot connect: {' '.join(str(exc).split())}") from None
    except ValueError as exc:  # distributed's address parser: no port, a bad scheme ('nonsense')
        raise InputError(
            f"--scheduler {scheduler!r}: {' '.join(str(exc).split())}; expected an address such as "
            "tcp://HOST:8786"
        ) from None
    with client:
        workers = len(client.scheduler_info(n_workers=-1).get("workers", {}))
        futures = client.map(
            check_part,
            [envelopes] * len(parts),
            parts,
            [columns] * len(parts),
            [options] * len(parts),
            pure=False,
        )
        reports = client.gather(futures)
    return list(reports), workers

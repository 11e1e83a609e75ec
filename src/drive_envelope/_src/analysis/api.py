"""Entry points of the analysis: check a log against envelopes, fit an envelope to a log or a curve."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drive_envelope._src.analysis.check import CheckOptions, CheckReport, JointCheck, check_chunks
from drive_envelope._src.analysis.curve import read_curve
from drive_envelope._src.analysis.fit import FitOptions, FitResult, fit_samples
from drive_envelope._src.analysis.fit_evidence import WARNING
from drive_envelope._src.analysis.logs import (
    DEFAULT_CHUNK_ROWS,
    LogChunk,
    LogColumns,
    ReadEngine,
    iter_log,
    read_log,
    source_label,
)
from drive_envelope._src.analysis.mapping import JointMapping, is_mapping_file, load_joint_mapping
from drive_envelope._src.datasheet.resolve import resolve_envelope
from drive_envelope._src.envelope.model import PerformanceEnvelope, require_envelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.validation import check_numbers

EnvelopeSource = (
    PerformanceEnvelope | JointMapping | Mapping[str, PerformanceEnvelope] | str | os.PathLike[str]
)
"""One envelope for every joint, a per-joint mapping, or a spec: a joint mapping file, an envelope
file, a datasheet file or a catalog actuator name."""


def resolve_envelope_source(spec: EnvelopeSource) -> PerformanceEnvelope | JointMapping:
    """Turn an envelope source into one envelope or a :class:`JointMapping`.

    Raises:
        InputError: a file or name that cannot be resolved.
    """
    if isinstance(spec, (PerformanceEnvelope, JointMapping)):
        return spec
    if isinstance(spec, Mapping):
        return JointMapping.from_envelopes(spec)
    if is_mapping_file(spec):
        return load_joint_mapping(spec)
    return resolve_envelope(spec)


def check_log(
    envelopes: EnvelopeSource,
    log: Any,
    *,
    columns: LogColumns | None = None,
    options: CheckOptions | None = None,
    chunk_rows: int = DEFAULT_CHUNK_ROWS,
    engine: ReadEngine = "auto",
) -> CheckReport:
    """Check every sample of a log against its joint's envelope, streaming in bounded memory.

    Args:
        envelopes: One envelope for all joints, a mapping joint name (or glob) -> envelope, or a
            spec string (joint mapping file, envelope file, datasheet file, catalog name).
        log: CSV or Parquet path, or an in-memory table (mapping of arrays, DataFrame, pyarrow Table).
        columns: Column names; defaults ``time,velocity,effort`` (and ``joint`` when present). Units
            in the headers are read for the envelopes' joint type.
        options: Tolerance and thresholds.
        chunk_rows: Rows read at a time (the memory bound).
        engine: CSV reader: ``"auto"``, ``"pyarrow"`` or ``"python"``.

    Returns:
        The :class:`CheckReport`; ``report.passed`` applies ``options.tolerance``.

    Raises:
        InputError: unreadable envelope or log, missing column, bad cell (naming row and column),
            a joint without envelope.
    """
    resolved = resolve_envelope_source(envelopes)
    columns = columns or LogColumns()
    kinds = (
        {resolved.joint}
        if isinstance(resolved, PerformanceEnvelope)
        else {envelope.joint for _, envelope in resolved.entries}
    )
    if columns.joint_type is None and len(kinds) == 1:  # units in the header must be of that type
        columns = replace(columns, joint_type=kinds.pop())
    chunks = iter_log(log, columns, chunk_rows=chunk_rows, engine=engine)
    return check_chunks(chunks, resolved, options=options or CheckOptions(), source=source_label(log))


def check_samples(
    envelope: PerformanceEnvelope,
    velocity: npt.ArrayLike,
    effort: npt.ArrayLike,
    *,
    time: npt.ArrayLike | None = None,
    options: CheckOptions | None = None,
) -> JointCheck:
    """Check one joint's samples (NumPy arrays) against an envelope.

    Args:
        envelope: The envelope (joint side, SI).
        velocity: Joint velocity samples [rad/s or m/s].
        effort: Effort samples [N*m or N].
        time: Sample times [s], optional (needed for times on limits and of violations).
        options: Thresholds.
    """
    if isinstance(envelope, (np.ndarray, list, tuple, float, int)):  # the samples given first
        require_envelope(envelope, "check_samples")
    check_numbers(
        "check_samples", velocity=velocity, effort=effort, **({} if time is None else {"time": time})
    )
    table: dict[str, npt.ArrayLike] = {"velocity": velocity, "effort": effort}
    if time is not None:
        table["time"] = time
    report = check_log(envelope, table, options=options)
    return report.joints[0]


def _select_joint(chunk: LogChunk, select: str | None, label: str) -> tuple[np.ndarray, np.ndarray]:
    if chunk.joint is None:
        if select is not None:
            raise InputError(f"{label}: --select {select!r} needs a joint column in the log")
        return chunk.velocity, chunk.effort
    names = chunk.names
    if select is None:
        if len(names) > 1:
            raise InputError(f"{label}: the log holds joints {', '.join(names)}; pick one with --select")
        return chunk.velocity, chunk.effort
    if select not in names:
        raise InputError(f"{label}: --select {select!r}: no such joint (joints: {', '.join(names)})")
    mask = chunk.joint == names.index(select)
    return chunk.velocity[mask], chunk.effort[mask]


def fit_log(
    log: Any,
    *,
    columns: LogColumns | None = None,
    options: FitOptions | None = None,
    select: str | None = None,
    engine: ReadEngine = "auto",
) -> FitResult:
    """Fit an envelope to the (velocity, effort) samples of a log of saturated operation.

    Args:
        log: CSV or Parquet path, or an in-memory table.
        columns: Column names (defaults ``velocity``, ``effort``; ``joint`` when present).
        options: Joint type, outlier quantile, fixed parameters, bootstrap.
        select: Joint name to fit in a long-format log with several joints.
        engine: CSV reader.

    Units in the column headers (``velocity [rpm]``) are converted to SI for ``options.joint``;
    the time column is not read.

    Raises:
        InputError: unreadable log, a unit of the other joint type, several joints without
            ``select``, too few samples.
    """
    options = options or FitOptions()
    label = source_label(log)
    columns = columns or LogColumns()
    if columns.joint_type not in (None, options.joint):
        raise InputError(
            f"{label}: the columns are read for a {columns.joint_type} joint, the fit is for a "
            f"{options.joint} one; expected one joint type"
        )
    # the time is not read: a fit does not depend on the order of the samples
    chunk = read_log(log, replace(columns, time=None, joint_type=options.joint), engine=engine)
    velocity, effort = _select_joint(chunk, select, label)
    if select and not options.name:
        options = replace(options, name=select)
    where = f"{label}: joint {select!r}" if select else label
    return _fit_from(where, velocity, effort, options)


def _fit_from(where: str, velocity: Any, effort: Any, options: FitOptions) -> FitResult:
    """:func:`fit_samples`, its errors about the samples naming where they came from."""
    try:
        return fit_samples(velocity, effort, options)
    except InputError as exc:
        raise InputError(f"{where}: {str(exc).removeprefix('fit: ')}") from None


def fit_curve(
    path: str | os.PathLike[str], *, columns: LogColumns | None = None, options: FitOptions | None = None
) -> FitResult:
    """Fit an envelope to points digitized from a datasheet's torque-speed diagram.

    The points lie on the boundary by construction, so every point is kept (outlier quantile 0),
    two points suffice per line, and no bootstrap is run: the residuals show the digitizing scatter.

    Args:
        path: CSV of points; units in brackets after the column names (``speed [rpm]``).
        columns: Column names; ``speed``/``torque``/``force`` are accepted by default.
        options: Joint type, fixed parameters, name (the outlier quantile and bootstrap are ignored).
    """
    options = options or FitOptions()
    velocity, effort = read_curve(path, columns=columns, joint=options.joint)
    curve_options = replace(options, outlier_quantile=0.0, bootstrap=0, min_segment_samples=2)
    if not curve_options.name:
        curve_options = replace(curve_options, name=Path(path).stem)
    result = _fit_from(str(path), velocity, effort, curve_options)
    if result.samples_outside == 0:
        note = (
            "digitized curve: every point contained, no bootstrap; the residuals show the digitizing scatter"
        )
    else:
        # only a held parameter can leave a curve's point outside (the fit contains every point)
        held = ", ".join(f"{name} = {value:g}" for name, value in curve_options.fixed.items())
        note = (
            f"digitized curve: {result.samples_outside} point(s) outside, cut off by the fixed "
            f"{held or 'parameters'} (SI); no bootstrap; the residuals show how far"
        )
    # a curve's points lie on the boundary by construction: a line through one point (a stall point)
    # is how a datasheet draws it, not a spike, and the outlier allowance does not apply to curves
    notes = [kept for kept in result.notes if not kept.startswith(WARNING)]
    return replace(result, notes=(*notes, note))

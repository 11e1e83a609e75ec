"""Sim-to-real analysis: check logged operation against envelopes, fit envelopes to measurements.

``check_log(envelopes, "log.csv")`` streams a CSV or Parquet log (or an in-memory table) in chunks
and returns a :class:`CheckReport`: per joint the fraction of samples outside the envelope, by which
curve, the worst violation and where, the margin distribution and the time spent on each limit, and
the samples "released" (zero effort beyond the speed line: PhysX's drive let go), counted apart.
``fit_log("sweep.csv")`` / ``fit_samples(velocity, effort)`` / ``fit_curve("diagram.csv")`` return a
:class:`FitResult`: the tightest envelope of the spec's form containing the samples (up to an
outlier quantile), each parameter with a bootstrap uncertainty, and the residuals.

Everything is SI, joint side: velocity [rad/s or m/s], effort [N*m or N], time [s]. NumPy is the
only requirement; Parquet needs pyarrow (which, when installed, also reads CSV faster); pandas
DataFrames and pyarrow Tables are accepted as tables of columns.
"""

from __future__ import annotations

from drive_envelope._src.analysis.api import (
    EnvelopeSource,
    check_log,
    check_samples,
    fit_curve,
    fit_log,
)
from drive_envelope._src.analysis.check import (
    MARGIN_QUANTILES,
    CheckOptions,
    CheckReport,
    JointCheck,
    KeptPoints,
    MarginSummary,
    Violation,
)
from drive_envelope._src.analysis.curve import read_curve
from drive_envelope._src.analysis.fit import (
    FitOptions,
    FitResult,
    LineEvidence,
    ParameterEstimate,
    fit_samples,
)
from drive_envelope._src.analysis.logs import DEFAULT_CHUNK_ROWS, LogChunk, LogColumns, iter_log, read_log
from drive_envelope._src.analysis.mapping import JointMapping, load_joint_mapping
from drive_envelope._src.analysis.report import DEFAULT_MAX_JOINTS

__all__ = [
    "DEFAULT_CHUNK_ROWS",
    "DEFAULT_MAX_JOINTS",
    "MARGIN_QUANTILES",
    "CheckOptions",
    "CheckReport",
    "EnvelopeSource",
    "FitOptions",
    "FitResult",
    "JointCheck",
    "JointMapping",
    "KeptPoints",
    "LineEvidence",
    "LogChunk",
    "LogColumns",
    "MarginSummary",
    "ParameterEstimate",
    "Violation",
    "check_log",
    "check_samples",
    "fit_curve",
    "fit_log",
    "fit_samples",
    "iter_log",
    "load_joint_mapping",
    "read_curve",
    "read_log",
]

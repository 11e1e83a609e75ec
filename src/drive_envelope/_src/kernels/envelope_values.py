"""Reading and validating per-DOF envelope values for the batched backends (host side, NumPy).

``EnvelopeArrays.from_values`` (Warp) and ``EnvelopeTensors.from_values`` (torch) both come here:
every value is an SI number, an array of them, or a string read by
:func:`drive_envelope._src.values.read_envelope_value` (``"inf"``, ``"300 rpm"``, ``"2 N*m"``); no
other parser is involved. Both backends' implicit clamps check a ``response`` given on the host here too.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import numpy.typing as npt

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.values import read_envelope_value


def _read(value: object, field: str, where: str) -> npt.NDArray[np.float64]:
    """One field as float64: numbers as they are, strings (alone or in a sequence) through the reader."""
    items = np.asarray(value, dtype=object)
    if any(isinstance(item, (str, bytes)) for item in items.flat):
        read = [read_envelope_value(item, field, f"{where}: {field}") for item in items.flat]
        return np.array(read, dtype=np.float64).reshape(items.shape)
    # None would read as NaN and be reported as "nan", a value the caller never wrote
    if any(item is None or isinstance(item, (bool, np.bool_)) for item in items.flat):
        raise InputError(f"{where}: {field} = {value!r}; expected SI numbers or strings with units")
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{where}: {field} = {value!r}; expected SI numbers or strings with units") from None


def read_envelope_values(given: Mapping[str, object], where: str) -> dict[str, npt.NDArray[np.float64]]:
    """Read and validate the four envelope fields (each a scalar or an array, not broadcast here).

    Args:
        given: ``max_effort``, ``max_actuator_velocity``, ``velocity_dependent_resistance``,
            ``speed_effort_gradient``: SI numbers, arrays of them, or strings with units.
        where: The caller, e.g. ``"EnvelopeArrays.from_values"``; it starts every error.

    Returns:
        The SI values as float64 arrays, keyed and ordered as :data:`ENVELOPE_FIELDS`.

    Raises:
        InputError: a negative, NaN or (except ``max_actuator_velocity``) infinite value, or a
            string of the wrong unit.
    """
    values = {}
    for name in ENVELOPE_FIELDS:
        array = _read(given[name], name, where)
        bad = np.isnan(array) | (array < 0.0)
        if name != "max_actuator_velocity":
            bad |= np.isinf(array)
        if np.any(bad):
            expected = ">= 0" if name == "max_actuator_velocity" else ">= 0 and finite"
            raise InputError(f"{where}: {name} = {float(array[bad].flat[0])!r}; expected {expected}")
        values[name] = array
    return values


def envelope_columns(
    envelopes: PerformanceEnvelope | Sequence[PerformanceEnvelope], count: int | None, where: str
) -> dict[str, npt.NDArray[np.float64]]:
    """The four fields of validated envelopes as float64 columns: one per DOF, or one repeated.

    Args:
        envelopes: One envelope per DOF, or a single envelope.
        count: Number of DOFs for a single envelope, ``>= 0`` (``None``: a 0-d column each).
        where: The caller, for errors.
    """
    if isinstance(envelopes, PerformanceEnvelope):
        if count is not None and (isinstance(count, bool) or not isinstance(count, int) or count < 0):
            raise InputError(f"{where}: count: expected a number of DOFs >= 0, got {count!r}")
        return {
            name: np.full(() if count is None else (count,), getattr(envelopes, name), dtype=np.float64)
            for name in ENVELOPE_FIELDS
        }
    envelopes = list(envelopes)
    if not envelopes or not all(isinstance(env, PerformanceEnvelope) for env in envelopes):
        raise InputError(f"{where}: expected a PerformanceEnvelope or a non-empty list of them")
    if count is not None and count != len(envelopes):
        raise InputError(f"{where}: count = {count!r} but {len(envelopes)} envelopes were given")
    return {
        name: np.array([getattr(env, name) for env in envelopes], dtype=np.float64)
        for name in ENVELOPE_FIELDS
    }

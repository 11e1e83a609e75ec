"""Writing MJCF with every digit: MuJoCo's writer keeps 6 significant digits by default.

MuJoCo 4's XML writer formats numbers with a thread-local precision, 6 unless changed through
``_mjPRIVATE__set_xml_precision`` (exported by ``libmujoco``, used by MuJoCo's own tests; the Python
bindings do not wrap it). :func:`full_precision` sets it to 17 for the current thread meanwhile,
:func:`shortest_numbers` then writes each number as the shortest text that reads back as the same
double (``0.1``, not ``0.10000000000000001``), and :func:`precision_loss` compares a written model
with the one compiled in memory, for a MuJoCo without the entry point.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import mujoco

LOSS_TOLERANCE = 1e-9
"""Largest relative difference of a written number that is not reported as lost precision."""
_DIGITS = 17  # enough for every double to read back exactly
_NOISE = 1e-12  # differences below this fraction of a field's largest number are rounding

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_ATTRIBUTE = re.compile(r'="([^"<>]*)"')


@functools.lru_cache(maxsize=1)
def _setter() -> tuple[Any, Any] | None:
    """(get, set) of MuJoCo's XML writer precision, or None where ``libmujoco`` has no such entry."""
    import mujoco

    folder = Path(mujoco.__file__).parent
    for pattern in ("libmujoco.so*", "libmujoco*.dylib", "mujoco.dll"):
        for library in sorted(folder.glob(pattern)):
            try:
                handle = ctypes.CDLL(str(library))
                get = handle._mjPRIVATE__get_xml_precision
                put = handle._mjPRIVATE__set_xml_precision
            except (OSError, AttributeError):
                continue
            get.restype, get.argtypes = ctypes.c_int, []
            put.restype, put.argtypes = None, [ctypes.c_int]
            return get, put
    return None


@contextlib.contextmanager
def full_precision() -> Iterator[bool]:
    """MuJoCo's XML writer with 17 significant digits meanwhile, on this thread.

    Yields:
        Whether it could be set (False: the writer keeps its 6 digits).
    """
    functions = _setter()
    if functions is None:
        yield False
        return
    get, put = functions
    previous = int(get())
    put(_DIGITS)
    try:
        yield True
    finally:
        put(previous)


def _shortest(token: str) -> str:
    if not any(c in token for c in ".eE") or sum(c.isdigit() for c in token) < 16:
        return token  # integers (names, counts) and short numbers stay as written
    value = float(token)
    if not math.isfinite(value):
        return token
    text = repr(value)
    return text[:-2] if text.endswith(".0") else text


def shortest_numbers(xml: str) -> str:
    """Write every long number of an attribute made only of numbers as its shortest exact text."""

    def attribute(match: re.Match[str]) -> str:
        tokens = match.group(1).split()
        if not tokens or not all(_NUMBER.fullmatch(t) for t in tokens):
            return match.group(0)
        return '="' + " ".join(_shortest(t) for t in tokens) + '"'

    return _ATTRIBUTE.sub(attribute, xml)


def precision_loss(reference: mujoco.MjModel, written: mujoco.MjModel) -> tuple[float, str]:
    """The largest relative difference between two compiled models' real-valued arrays.

    Returns:
        ``(relative difference, "field[index] a -> b")``; ``(0.0, "")`` when they are equal.
    """
    import numpy as np

    worst, where = 0.0, ""
    for field in dir(reference):
        a = getattr(reference, field, None)
        if field.startswith("_") or not isinstance(a, np.ndarray) or a.dtype.kind != "f":
            continue
        b = getattr(written, field, None)
        if not isinstance(b, np.ndarray) or a.shape != b.shape or not a.size:
            continue
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            difference = np.abs(a - b)
            scale = np.maximum(np.abs(a), np.abs(b))
            relative = np.where(scale > 0, difference / np.where(scale > 0, scale, 1.0), 0.0)
            # rounding of numbers MuJoCo derives (a capsule's fromto written as pos/quat): noise
            # near zero, far below the field's own scale
            field_scale = float(np.nanmax(np.where(np.isfinite(scale), scale, 0.0)))
            relative = np.where(difference > _NOISE * field_scale, relative, 0.0)
        relative = np.where(np.isnan(relative), 0.0, relative)
        index = int(np.argmax(relative))
        if float(relative.flat[index]) > worst:
            worst = float(relative.flat[index])
            position = np.unravel_index(index, a.shape)
            at = ", ".join(str(int(p)) for p in position)
            where = f"{field}[{at}] {float(a[position])!r} -> {float(b[position])!r}"
    return worst, where

"""The one check of keys a user wrote: an unknown key is refused with the nearest valid one.

Every file, table and override that takes named keys (datasheets, scenarios, envelope tables,
bench-stand files, joint maps) refuses an unknown key here, so the message reads the same
everywhere: ``"file: unknown key 'servo.dutty'" (did you mean 'duty_per_rad'?); valid keys in
[servo]: ..."``. Arrays whose shapes do not broadcast are refused here too, in every backend.
"""

from __future__ import annotations

import difflib
from collections.abc import Collection, Iterable, Sequence
from typing import Any

import numpy as np

from drive_envelope._src.errors import InputError


def nearest_key(key: str, valid: Iterable[str], *, cutoff: float = 0.5) -> str:
    """Return ``" (did you mean 'x'?)"`` for the closest valid key, or ``""`` when none is close.

    Args:
        key: The key as written.
        valid: The keys that exist there.
        cutoff: Similarity in [0, 1] a suggestion needs (difflib's ratio); short names such as
            section names need a higher one, or every short word "looks like" one of them.
    """
    match = difflib.get_close_matches(key, list(valid), n=1, cutoff=cutoff)
    return f" (did you mean {match[0]!r}?)" if match else ""


def check_keys(
    given: Iterable[object],
    valid: Collection[str],
    source: str,
    section: str = "",
    *,
    aliases: Iterable[str] = (),
) -> None:
    """Refuse a key that is not in ``valid`` (or ``aliases``), suggesting the nearest one.

    Args:
        given: The keys as written (a mapping's keys).
        valid: The keys that exist there, listed in the message.
        source: The file (or argument) the keys come from; it starts the message.
        section: The table the keys sit in (``"servo"``), or ``""`` at the top level.
        aliases: Other accepted names: suggested, not listed.

    Raises:
        InputError: ``"source: unknown key 'section.key' (did you mean ...); valid keys in [section]: ..."``.
    """
    accepted = [*valid, *aliases]
    prefix = f"{section}." if section else ""
    for key in given:
        if key not in accepted:
            raise InputError(
                f"{source}: unknown key {prefix + str(key)!r}{nearest_key(str(key), accepted)}; "
                f"valid keys{' in [' + section + ']' if section else ''}: {', '.join(valid)}"
            )


def keyed_error(where: str, exc: InputError) -> InputError:
    """``exc`` with ``where`` (``"map.toml: key 'joints.<pattern>'"``) in front (the one "where: error" form).

    Engines call this on the error of applying a mapped joint, so that the message names the map
    file and key the joint came from; an empty ``where`` (no map) leaves the message as it is.
    """
    return InputError(f"{where}: {exc}" if where else str(exc))


def broadcast_shape(where: str, names: Sequence[str], shapes: Sequence[tuple[int, ...]]) -> tuple[int, ...]:
    """The broadcast shape of the arguments, or one InputError naming each argument's shape.

    Every backend's rule (NumPy, torch and Warp name a mismatch the same way): shapes that do not
    broadcast are a user mistake, not NumPy's ``ValueError`` or torch's ``RuntimeError``.
    """
    try:
        return tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        listed = ", ".join(f"{n}={tuple(s)}" for n, s in zip(names, shapes, strict=True))
        raise InputError(f"{where}: shapes do not broadcast ({listed})") from None


def check_numbers(where: str, **values: Any) -> None:
    """Refuse an argument that is not numbers: None, text, booleans, objects (one line naming it).

    NumPy reads ``None`` as NaN (which lets a drive go) and ``"3"`` as 3.0, so such a mistake would
    give a silent 0 or a number the user never meant. Arrays and Python numbers pass at once.
    """
    for name, value in values.items():
        if type(value) is np.ndarray and value.dtype.kind == "f":  # the hot path: a batch's own arrays
            continue
        if isinstance(value, bool):
            pass
        elif isinstance(value, (float, int, np.floating, np.integer)):
            continue
        elif isinstance(value, np.ndarray):
            if value.dtype.kind in "fiu":
                continue
        elif type(value).__module__.split(".")[0] in ("torch", "warp", "jax"):
            continue  # another backend's array: its own port reads it
        elif np.asarray(value).dtype.kind in "fiu":
            continue
        shown = repr(value) if np.ndim(value) == 0 else f"an array of {np.asarray(value).dtype}"
        expected = "numbers (a float, an int or an array of them)"
        raise InputError(f"{where}: {name}: expected {expected}, got {shown}")


def refuse_negative_response(response: object, *, device_array: type | None = None) -> None:
    """A negative ``response`` given on the host (number, list, NumPy array): a one-line InputError.

    A ``device_array`` (a torch tensor, a ``wp.array``) is not read: that would copy it back from the
    device (a negative value in it gives the guarded result). A NaN is not refused: it lets go.
    """
    if device_array is not None and isinstance(response, device_array):
        return
    values = np.asarray(response, dtype=np.float64)
    negative = values < 0.0
    if negative.any():
        bad = float(values[negative].flat[0])
        raise InputError(f"response: expected >= 0 [rad/s/(N*m*s) or m/s/(N*s)], got {bad!r}")

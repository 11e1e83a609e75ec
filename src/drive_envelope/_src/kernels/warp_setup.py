"""Initialising Warp quietly: no banner, no module-load lines, no "no CUDA driver" line on stderr.

Engines that run on Warp (the Newton stand, ovphysx's tensors) initialise it through
:func:`quiet_warp`, so a command's stdout (a CSV) and stderr (one status or error line) stay what
the command printed. Warp prints its banner and one line per module it loads at log level INFO,
and its native library writes a warning straight to the process's stderr when it finds no CUDA
driver (a CPU-only machine): that one is dropped during ``wp.init`` only.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
from collections.abc import Iterator


@contextlib.contextmanager
def _native_stderr_dropped() -> Iterator[None]:
    """Send file descriptor 2 to the null device for the block (C code writes there directly)."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no real stderr (an embedding host): nothing to silence
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


@contextlib.contextmanager
def quiet_warp() -> Iterator[None]:
    """Initialise Warp and hold its log level at WARNING or above for the block."""
    import warp as wp

    level = wp.config.log_level
    wp.config.log_level = max(level, logging.WARNING)
    try:
        with _native_stderr_dropped():
            wp.init()
        yield
    finally:
        wp.config.log_level = level

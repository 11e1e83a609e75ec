"""Keep Warp's banner and module-load lines off stdout while Newton runs (a CLI may write a CSV there)."""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator

__all__ = ["quiet_warp"]


@contextlib.contextmanager
def quiet_warp() -> Iterator[None]:
    """Initialise Warp and hold its log level at WARNING or above for the block.

    Warp prints its banner at ``wp.init`` and one line per module it loads or compiles (at the
    first launch of each kernel) at log level INFO, its default.
    """
    import warp as wp

    level = wp.config.log_level
    wp.config.log_level = max(level, logging.WARNING)
    try:
        wp.init()
        yield
    finally:
        wp.config.log_level = level

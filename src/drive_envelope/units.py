"""Units at the input edges: the one pint registry and conversion of user quantities to SI floats.

Use :func:`to_si` for a value from a file or a user (``"3000 rpm"`` -> 314.159 rad/s). Angles are
explicit: an angular quantity without an angle unit (``Hz``, ``1/s``) is an error, never a silent
factor 2*pi.
"""

from __future__ import annotations

from drive_envelope._src.units import format_si, get_registry, to_si

__all__ = ["format_si", "get_registry", "to_si"]

"""Units at the input edges: the one pint registry and conversion of user quantities to SI floats.

Use :func:`to_si` for a value from a file or a user (``"3000 rpm"`` -> 314.159 rad/s). Angles are
explicit: an angular quantity without an angle unit (``Hz``, ``1/s``) is an error, never a silent
factor 2*pi. A bare number is SI; a comma in a number is an error (``16,1`` or ``1,500``?).
"""

from __future__ import annotations

from drive_envelope._src.units import describe_unit, format_si, get_registry, to_si

__all__ = ["describe_unit", "format_si", "get_registry", "to_si"]

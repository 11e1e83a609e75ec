"""Generate ``docs/glossary.md`` from the parameter table: ``python -m drive_envelope._src.params.glossary``.

A test compares the committed file with :func:`render_glossary`, so the glossary cannot drift from
the names the adapters use.
"""

from __future__ import annotations

import sys
from pathlib import Path

from drive_envelope._src.params.table import PARAMETERS

__all__ = ["GLOSSARY_PATH", "render_glossary"]

GLOSSARY_PATH = Path(__file__).resolve().parents[4] / "docs" / "glossary.md"


def render_glossary() -> str:
    """The glossary as Markdown: one row per parameter, one column per engine."""
    lines = [
        "# Glossary: one envelope, many names",
        "",
        "Generated from `src/drive_envelope/_src/params/table.py` by",
        "`python -m drive_envelope._src.params.glossary`; do not edit by hand.",
        "",
        "All values are joint side and SI inside drive-envelope. USD stores angular instances per degree.",
        "",
        "| drive-envelope | spec | meaning | SI revolute | SI prismatic | PhysX C++ | USD attribute "
        "| USD angular unit | PhysX tensor index | MuJoCo plugin | Isaac Lab | Newton |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for p in PARAMETERS:
        index = "-" if p.physx_tensor_index is None else str(p.physx_tensor_index)
        cells = [
            f"`{p.name}`",
            p.symbol,
            p.meaning,
            p.unit_revolute,
            p.unit_prismatic,
            f"`{p.physx_cpp}`",
            f"`{p.usd_attribute}`",
            p.usd_unit_angular,
            index,
            f"`{p.mujoco_plugin}`",
            p.isaac_lab,
            p.newton,
        ]
        lines.append("| " + " | ".join(cells) + " |")
    lines += [
        "",
        "The PhysX tensor API orders the three envelope values (speedEffortGradient, maxActuatorVelocity,",
        "velocityDependentResistance); the C++ constructor orders (maxEffort, maxActuatorVelocity,",
        "velocityDependentResistance, speedEffortGradient).",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    GLOSSARY_PATH.write_text(render_glossary(), encoding="utf-8")
    sys.stdout.write(f"wrote {GLOSSARY_PATH}\n")

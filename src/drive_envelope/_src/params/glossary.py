"""Generate the glossary from the parameter table: ``python -m drive_envelope._src.params.glossary OUT``.

It writes only where it is told: ``OUT`` (``docs/glossary.md`` in a checkout; ``-`` for stdout), never
into the installation it runs from. A test compares the committed file with :func:`render_glossary`,
so the glossary cannot drift from the names the adapters use.
"""

from __future__ import annotations

import sys
from pathlib import Path

from drive_envelope._src.params.table import PARAMETERS

GLOSSARY_PATH = Path(__file__).resolve().parents[4] / "docs" / "glossary.md"
"""Where a source checkout keeps the glossary (the test reads it; the generator is told where to write)."""


def render_glossary() -> str:
    """The glossary as Markdown: one row per parameter, one column per engine."""
    lines = [
        "# Glossary: one envelope, many names",
        "",
        "Generated from `src/drive_envelope/_src/params/table.py` by",
        "`python -m drive_envelope._src.params.glossary docs/glossary.md`; do not edit by hand.",
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


def main(argv: list[str]) -> int:
    """Write the glossary to ``argv[0]`` (``-``: stdout); return the exit status (2: no output given)."""
    usage = "usage: python -m drive_envelope._src.params.glossary OUT.md (or - for stdout)"
    if len(argv) != 1 or not argv[0].strip():
        sys.stderr.write(f"{usage}\n")
        return 2
    if argv[0] == "-":
        sys.stdout.write(render_glossary())
        return 0
    try:  # a plain write: params/ sits below io/ in the layer stack, and this is a developer tool
        Path(argv[0]).write_text(render_glossary(), encoding="utf-8")
    except OSError as exc:
        sys.stderr.write(f"glossary: error: {argv[0]}: cannot write: {exc.strerror or exc}\n")
        return 2
    sys.stderr.write(f"wrote {argv[0]}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""USD builds its schema registry once per process: whichever of our registrations comes first must
bring every schema we read (PhysX's envelope API and our Newton-actuator clamping schema).

Each case runs in a fresh interpreter, since the registry cannot be rebuilt within one.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

pytestmark = pytest.mark.usd

pytest.importorskip("pxr")
pytest.importorskip("physx_usd_schemas")

READ_BOTH = """
from pxr import Usd
for name in ("PhysxDrivePerformanceEnvelopeAPI", "DriveEnvelopeClampingAPI"):
    assert Usd.SchemaRegistry().FindAppliedAPIPrimDefinition(name) is not None, name
print("ok")
"""


@pytest.mark.parametrize(
    "first",
    [
        "from drive_envelope._src.adapters.usd.newton_actuator import register_schema; register_schema()",
        "from drive_envelope.usd import register_schemas; register_schemas()",
    ],
    ids=["clamping-schema-first", "physx-schemas-first"],
)
def test_either_registration_first_knows_both_schemas(first: str) -> None:
    run = subprocess.run(
        [sys.executable, "-c", first + "\n" + READ_BOTH], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip().endswith("ok")

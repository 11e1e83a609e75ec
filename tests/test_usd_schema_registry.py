"""The PhysX schemas must be registered before USD builds its schema registry, or reading is refused."""

from __future__ import annotations

import subprocess
import sys

import pytest

pytestmark = pytest.mark.usd


def test_a_registry_built_too_early_is_refused_not_read_as_no_envelope() -> None:
    """Refuse with one line when pxr read schemas before physx_usd_schemas (Newton's add_usd does)."""
    code = (
        "from pxr import Usd\n"
        "Usd.SchemaRegistry()\n"  # what any earlier USD user of the process does
        "from drive_envelope._src.adapters.usd.stage import register_schemas\n"
        "from drive_envelope._src.errors import InputError\n"
        "try:\n    register_schemas()\nexcept InputError as exc:\n    print(exc)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "schema registry was built before the PhysX schemas" in out
    assert "register_schemas()" in out


def test_registering_first_works() -> None:
    """Know the envelope API when the schemas are registered before USD builds its registry."""
    code = (
        "from drive_envelope._src.adapters.usd.stage import register_schemas\n"
        "register_schemas()\n"
        "from pxr import Usd\n"
        "api = 'PhysxDrivePerformanceEnvelopeAPI'\n"
        "print(Usd.SchemaRegistry().FindAppliedAPIPrimDefinition(api) is not None)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "True"

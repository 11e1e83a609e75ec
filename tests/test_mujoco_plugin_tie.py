"""The Python side's slot table, bound, no-limit value and attributes are the plugin's (envelope.h/.cc)."""

from __future__ import annotations

import re
from pathlib import Path

from drive_envelope._src.adapters.mujoco import params

PLUGIN = Path(__file__).resolve().parents[1] / "plugin" / "mujoco"
# the enum's names, in the order of params.DYNPRM_SLOTS
_SLOT_ENUM = {
    "kSlotMaxEffort": "max_effort",
    "kSlotMaxActuatorVelocity": "max_actuator_velocity",
    "kSlotResistance": "velocity_dependent_resistance",
    "kSlotGradient": "speed_effort_gradient",
    "kSlotStiffness": "stiffness",
    "kSlotDamping": "damping",
}


def _header() -> str:
    return (PLUGIN / "envelope.h").read_text(encoding="utf-8")


def test_slot_order_matches_envelope_h() -> None:
    """Each slot's index in the plugin's Slot enum is its index in DYNPRM_SLOTS; kNumSlots is their count."""
    found = dict(re.findall(r"\b(kSlot\w+|kNumSlots)\s*=\s*(\d+)", _header()))
    assert int(found.pop("kNumSlots")) == len(params.DYNPRM_SLOTS)
    assert {_SLOT_ENUM[name]: int(index) for name, index in found.items()} == {
        slot: k for k, slot in enumerate(params.DYNPRM_SLOTS)
    }


def test_bound_and_no_limit_match_envelope_h() -> None:
    """PARAM_BOUND and NO_LIMIT are kParamBound and kNoLimit."""
    text = _header()
    bound = re.search(r"constexpr double kParamBound = ([^;]+);", text)
    no_limit = re.search(r"constexpr double kNoLimit = ([^;]+);", text)
    assert bound is not None and float(bound.group(1)) == params.PARAM_BOUND
    assert no_limit is not None and float(no_limit.group(1)) == params.NO_LIMIT


def test_inputs_match_envelope_h() -> None:
    """INPUTS are the Input enum's names in bit order (pos 1, vel 2, ff 4)."""
    bits = dict(re.findall(r"\bkInput(\w+)\s*=\s*(\d+)", _header()))
    assert sorted(bits, key=lambda name: int(bits[name])) == [i.capitalize() for i in params.INPUTS]
    assert [int(bits[i.capitalize()]) for i in params.INPUTS] == [1 << k for k in range(len(params.INPUTS))]


def test_attributes_match_the_registered_list() -> None:
    """_ATTRIBUTES is the plugin's declared attribute list, in order (how model.plugin_attr is laid out)."""
    source = (PLUGIN / "envelope.cc").read_text(encoding="utf-8")
    names = dict(re.findall(r'constexpr char (kAttr\w+)\[\] = "(\w+)";', source))
    declared = re.search(r"static const char\* attributes\[\] = \{([^}]*)\};", source)
    assert declared is not None
    order = [names[token.strip()] for token in declared.group(1).split(",") if token.strip()]
    assert tuple(order) == params._ATTRIBUTES

"""What a datasheet file says: motor, gear, controller, losses, output rating and screw, in SI.

Motor side and joint side are kept apart by type. :class:`MotorDatasheet` holds motor-side values
(before the gear), :class:`OutputRating` and direct ``velocity_dependent_resistance`` values hold
joint-side values, and :class:`Transmission` is the only place where one becomes the other.

Every field is an SI float or ``None`` when the datasheet does not give it. ``None`` is never
guessed: a candidate limit whose inputs are absent is reported as missing. Defaults (gear efficiency
1.0, controller modulation 0.9) are applied by :func:`~drive_envelope._src.datasheet.derive.derive`,
which records them as such. Each section field also carries its file key's rule (kind of quantity,
bound, side) in its metadata: the reader's ``SECTION_KEYS`` is derived from these fields.

Units depend on the motor: a rotary motor uses N*m, rad/s, N*m/A, rad/s/V; a linear motor (a
prismatic joint without ``[screw]``) uses N, m/s, N/A, (m/s)/V. The brackets below give both.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, get_args

if TYPE_CHECKING:  # a string annotation only: the CLI reads GRADIENT_METHODS without loading numpy
    from drive_envelope._src.envelope.model import JointType

GradientMethod = Literal["auto", "resistance", "nominal", "datasheet"]
GRADIENT_METHODS: tuple[GradientMethod, ...] = get_args(GradientMethod)
"""The speed-torque gradient methods, for the file's ``motor.gradient_method`` and ``--gradient-method``."""
"""How the motor's speed-torque gradient is formed when the voltage limit binds."""

ParamSource = Literal["datasheet", "derived", "default", "user"]
"""Where a value came from: the datasheet file, a formula, a documented default, or the user
(a command-line override)."""

Side = Literal["motor", "joint"]
"""Which units a file value takes: ``"motor"`` (linear for a linear motor) or ``"joint"``."""


def _rule(kind: str, bound: str, side: Side) -> dict[str, str]:
    """A section field's file rule, the one table the reader derives ``SECTION_KEYS`` from.

    Args:
        kind: The quantity (``"torque"``, ``"speed"``, ...; ``"enum"``, ``"points"`` and ``"lead"``
            have their own readers).
        bound: ``">0"``, ``">=0"``, ``"(0,1]"`` or ``""`` (not a number).
        side: Motor-side or joint-side units.

    Each field is read from the file key of its own name; a field that is not a file key would say
    so with ``metadata={"file_key": False}`` (none is, today).
    """
    return {"kind": kind, "bound": bound, "side": side}


def _key(kind: str, bound: str, side: Side) -> Any:
    """An optional section field, ``None`` when the file omits it, with its file rule."""
    # Any: the field's own annotation gives its type, as with dataclasses.field
    return field(default=None, metadata=_rule(kind, bound, side))


@dataclass(frozen=True, kw_only=True, slots=True)
class MotorDatasheet:
    """The motor, motor side (before the gear), as its datasheet prints it."""

    torque_constant: float | None = _key("torque_constant", ">0", "motor")
    """k_t [N*m/A or N/A]; taken as printed (no rms/peak or phase conversion)."""
    speed_constant: float | None = _key("speed_constant", ">0", "motor")
    """k_v [(rad/s)/V or (m/s)/V]."""
    back_emf_constant: float | None = _key("back_emf_constant", ">0", "motor")
    """k_e [V*s/rad or V*s/m]; gives k_v = 1/k_e. Exclusive with ``speed_constant``."""
    terminal_resistance: float | None = _key("ohm", ">0", "motor")
    """R_mot, terminal (phase-to-phase) resistance [ohm]."""
    max_torque: float | None = _key("torque", ">0", "motor")
    """tau_M,max for peak duty [N*m or N]."""
    continuous_torque: float | None = _key("torque", ">0", "motor")
    """tau_M,max for continuous duty [N*m or N]."""
    max_speed: float | None = _key("speed", ">0", "motor")
    """n_M,max, mechanical speed limit [rad/s or m/s]."""
    no_load_speed: float | None = _key("speed", ">0", "motor")
    """n_0 [rad/s or m/s]."""
    nominal_speed: float | None = _key("speed", ">0", "motor")
    """n_N [rad/s or m/s]; below ``no_load_speed``."""
    nominal_torque: float | None = _key("torque", ">0", "motor")
    """tau_N [N*m or N]."""
    speed_torque_gradient: float | None = _key("gradient", ">0", "motor")
    """Speed-torque gradient as printed [(rad/s)/(N*m) or (m/s)/N]."""
    gradient_method: GradientMethod = field(default="auto", metadata=_rule("enum", "", "motor"))
    """Which motor gradient to use: ``auto`` takes the first of datasheet, resistance, nominal whose
    inputs exist."""


@dataclass(frozen=True, kw_only=True, slots=True)
class GearboxSpec:
    """The gear between motor and joint (or screw)."""

    ratio: float = field(metadata=_rule("ratio", ">0", "motor"))
    """i_G = motor speed / gear output speed [1]; > 1 for a reducer."""
    efficiency: float | None = _key("fraction", "(0,1]", "motor")
    """eta_G in (0, 1] [1]; ``None``: 1.0 is used, with a note."""
    max_torque: float | None = _key("torque", ">0", "motor")
    """tau_G,max at the gear output [N*m or N]."""
    max_input_speed: float | None = _key("speed", ">0", "motor")
    """n_G,in,max at the gear input [rad/s or m/s]."""


@dataclass(frozen=True, kw_only=True, slots=True)
class ControllerSpec:
    """The motor controller (drive electronics)."""

    max_current: float | None = _key("current", ">0", "motor")
    """I_C,max [A]."""
    max_voltage: float | None = _key("voltage", ">0", "motor")
    """V_max, supply voltage [V]."""
    modulation: float | None = _key("fraction", "(0,1]", "motor")
    """mu_C in (0, 1] [1]; ``None``: 0.9 is used, with a note."""


@dataclass(frozen=True, kw_only=True, slots=True)
class LossesSpec:
    """Speed-dependent losses."""

    velocity_dependent_resistance: float | None = _key("resistance_joint", ">=0", "joint")
    """k_tau_v at the joint, when known directly [N*m*s/rad or N*s/m]."""
    operating_points: tuple[tuple[float, float], ...] | None = _key("points", "", "motor")
    """Motor-side ``(speed [rad/s or m/s], max torque [N*m or N])`` points from an operating
    diagram, or None; fitted by least squares when no direct value is given."""


@dataclass(frozen=True, kw_only=True, slots=True)
class OutputRating:
    """Ratings of the whole actuator at its output (joint side), not scaled by the gear.

    Two kinds of numbers live here. ``max_effort`` and ``max_velocity`` are plain caps (a peak
    torque, a firmware speed limit): alone they give a rectangle, speed_effort_gradient 0.
    ``stall_effort`` and ``no_load_velocity`` are the two ends of the actuator's speed-effort line,
    as servo and gearmotor datasheets print them: together they give the gradient
    ``no_load_velocity / stall_effort``. A point on that line, ``nominal_velocity`` at
    ``nominal_effort`` (a rated speed at the rated torque), gives it as
    ``(no_load_velocity - nominal_velocity) / nominal_effort`` (the spec's nominal method).
    """

    max_effort: float | None = _key("torque", ">0", "joint")
    """Peak output effort, a cap [N*m or N]."""
    max_velocity: float | None = _key("speed", ">0", "joint")
    """Output velocity cap [rad/s or m/s]."""
    velocity_at_max_effort: float | None = _key("speed", ">=0", "joint")
    """Output velocity at ``max_effort`` [rad/s or m/s]; gives the gradient
    ``(max_velocity - velocity_at_max_effort) / max_effort``."""
    speed_effort_gradient: float | None = _key("gradient", ">0", "joint")
    """Output speed-effort gradient as printed [(rad/s)/(N*m) or (m/s)/N]."""
    velocity_dependent_resistance: float | None = _key("resistance_joint", ">=0", "joint")
    """k_tau_v at the output [N*m*s/rad or N*s/m]."""
    stall_effort: float | None = _key("torque", ">0", "joint")
    """Stall torque or force: the effort at zero speed, the line's effort end [N*m or N]. Read from
    ``stall_effort``, ``stall_torque`` or ``stall_force``."""
    no_load_velocity: float | None = _key("speed", ">0", "joint")
    """No-load output velocity: the speed at zero effort, the line's speed end [rad/s or m/s]. Read
    from ``no_load_velocity`` or ``no_load_speed``."""
    nominal_effort: float | None = _key("torque", ">0", "joint")
    """Rated (continuous) output effort [N*m or N]; the effort cap for ``--duty continuous``."""
    nominal_velocity: float | None = _key("speed", ">0", "joint")
    """Output velocity at ``nominal_effort`` on the speed-effort line [rad/s or m/s]."""

    def rating_gradient(self) -> tuple[float, str] | None:
        """The gradient of the ``max_velocity`` cap, or None.

        Returns:
            ``(value [(rad/s)/(N*m) or (m/s)/N], formula)`` or None.
        """
        if self.speed_effort_gradient is not None:
            return self.speed_effort_gradient, "output speed_effort_gradient"
        if self.velocity_at_max_effort is not None and self.max_velocity is not None and self.max_effort:
            value = (self.max_velocity - self.velocity_at_max_effort) / self.max_effort
            return value, "(max_velocity - velocity_at_max_effort) / max_effort"
        return None

    def line_gradient(self) -> tuple[float, str] | None:
        """The gradient of the no-load line ``(value [(rad/s)/(N*m) or (m/s)/N], formula)``, or None.

        The order: a printed ``speed_effort_gradient``, then the two ends (stall), then the nominal
        point.
        """
        v0 = self.no_load_velocity
        if self.speed_effort_gradient is not None:
            return self.speed_effort_gradient, "output speed_effort_gradient"
        if v0 is not None and self.stall_effort:
            return v0 / self.stall_effort, "no_load_velocity / stall_effort"
        if v0 is not None and self.nominal_velocity is not None and self.nominal_effort:
            value = (v0 - self.nominal_velocity) / self.nominal_effort
            return value, "(no_load_velocity - nominal_velocity) / nominal_effort"
        return None


@dataclass(frozen=True, kw_only=True, slots=True)
class ScrewSpec:
    """A lead screw or ball screw turning the gear output into linear travel (prismatic joints)."""

    lead: float = field(metadata=_rule("lead", ">0", "motor"))
    """Travel per revolution [m]."""
    efficiency: float | None = _key("fraction", "(0,1]", "motor")
    """eta_S in (0, 1] [1]; ``None``: 1.0."""


@dataclass(frozen=True, kw_only=True, slots=True)
class Datasheet:
    """A whole actuator datasheet, SI, as read from a datasheet file."""

    name: str
    """Actuator name."""
    joint: JointType = "revolute"
    """``"revolute"`` or ``"prismatic"``; fixes the joint-side units."""
    motor: MotorDatasheet | None = None
    """``[motor]``, or None when absent."""
    gear: GearboxSpec | None = None
    """``[gear]``, or None: direct drive (ratio 1, efficiency 1)."""
    controller: ControllerSpec | None = None
    """``[controller]``, or None."""
    losses: LossesSpec | None = None
    """``[losses]``, or None."""
    output: OutputRating | None = None
    """``[output]``, or None."""
    screw: ScrewSpec | None = None
    """``[screw]`` (prismatic joints only), or None."""
    description: str = ""
    """Free text (catalog entries describe the actuator here)."""
    sources: tuple[str, ...] = ()
    """Document URLs the numbers come from (catalog entries)."""
    source: str = "datasheet"
    """File (or catalog name) it was read from; starts every error message."""
    provenance: Mapping[str, ParamSource] = field(default_factory=dict)
    """``"section.key"`` -> ``"datasheet"`` or ``"user"`` (set with an override) for each value given."""
    notes: tuple[str, ...] = ()
    """How the file was read where it could be read two ways (e.g. a ratio written ``"1:50"``)."""
    current_conventions: Mapping[str, str] = field(default_factory=dict)
    """``"motor.torque_constant"`` or ``"controller.max_current"`` -> ``"rms"`` or ``"peak"``, as the
    value's text marked it (``"1.22 N.m/Arms"``, ``"23Apk"``); the units layer reads both as plain
    amperes, so a derivation checks that they match."""
    bare_numbers: frozenset[str] = frozenset()
    """``"section.key"`` of each value written as a bare number, without a unit (``torque_constant =
    91``): read as SI, it may be a vendor's ``mNm/A`` typed without its unit, which a derivation
    checks for."""

    @property
    def linear_motor(self) -> bool:
        """Whether motor and gear data are linear (N, m/s): a prismatic joint without a screw."""
        return self.joint == "prismatic" and self.screw is None


@dataclass(frozen=True, kw_only=True, slots=True)
class Transmission:
    """Motor side -> joint side: the gear ratio is defined here, once, with every reflection rule.

    ``i_G = motor speed / gear output speed`` (> 1 for a reducer). A screw of lead ``L`` (travel per
    revolution) adds ``T = 2*pi / L`` [rad/m] between gear output and joint. With gear efficiency
    ``eta_G`` and screw efficiency ``eta_S`` (``T = eta_S = 1`` without a screw):

    * effort: motor effort ``x i_G * eta_G * T * eta_S``; gear output effort ``x T * eta_S``;
    * speed: motor (or gear input) speed ``/ (i_G * T)``;
    * speed-effort gradient: ``/ (i_G**2 * T**2)``; efficiency does not enter (the spec's rule);
    * velocity-dependent resistance: ``x i_G**2 * eta_G * T**2 * eta_S``.

    Joint-side values (``[output]``, a direct resistance) are never converted.
    """

    ratio: float = 1.0
    """i_G [1]."""
    efficiency: float = 1.0
    """eta_G [1]."""
    screw_factor: float = 1.0
    """T = 2*pi/lead [rad/m], 1.0 without a screw."""
    screw_efficiency: float = 1.0
    """eta_S [1]."""

    def motor_effort(self, effort: float) -> float:
        """Joint effort [N*m or N] of a motor effort [N*m or N]."""
        return effort * self.ratio * self.efficiency * self.screw_factor * self.screw_efficiency

    def gear_output_effort(self, effort: float) -> float:
        """Joint effort [N*m or N] of a gear output effort [N*m or N]."""
        return effort * self.screw_factor * self.screw_efficiency

    def motor_speed(self, speed: float) -> float:
        """Joint speed [rad/s or m/s] of a motor (or gear input) speed [rad/s or m/s]."""
        return speed / (self.ratio * self.screw_factor)

    def motor_gradient(self, gradient: float) -> float:
        """Joint speed-effort gradient of a motor gradient [(rad/s)/(N*m) or (m/s)/N]."""
        reduction = self.ratio * self.screw_factor
        return gradient / reduction / reduction  # not **2: an extreme ratio gives 0 or inf, not an error

"""The test stand in Newton: one revolute or prismatic joint on a fixed base, Featherstone, implicit.

The scenario's rigid inertia becomes one link whose inertia about the joint axis (X) is
``joint.inertia``, with ``joint.armature`` as Newton's joint armature, so the DOF's unit response is
``1/(inertia + armature)``. A ``[pendulum]`` point mass is folded into the same link (mass, centre
of mass off the axis, inertia about it) under gravity along -Z, so gravity's effort is
``-m*g*d*sin(q + angle_offset)``; without one the stand has no gravity.
The drive runs as the scenario's PhysX solver iterates it (``drive="physx"``, the default and what
``simulate --engine newton`` runs): :mod:`~drive_envelope._src.adapters.newton.physx_drive`'s Warp
kernel computes the step's drive effort, PGS's sweeps or TGS's substeps with their iteration
counts, with the joint's response from Newton's mass matrix (``JointSpaceResponse``) and the loads
from :class:`~drive_envelope._src.adapters.newton.bias.BiasForce` (gravity, minus the external
effort); Newton gets it as joint effort (``joint_f``, with the external effort), and after the step
the joint's position is moved to the one PhysX integrates (as the MuJoCo plugin does). On every
shipped scenario, PGS and TGS, that is the reference to float32 rounding (``docs/parity.md``).

``drive="actuator"`` runs Newton's own actuator stack instead: ``DrivePD`` (stiffness, damping, the
scenario's applied effort as its feed-forward ``joint_act``, which PhysX counts as actuator
effort) clamped by :class:`ClampingPerformanceEnvelope`, in Newton's implicit effort mode: the PD
law and the clamp are solved at the end-of-step velocity and position, as PhysX's implicit drive
and ``clampDriveImpulse`` are. The external effort is not actuator effort: it is added to
``joint_f`` after the actuator. The implicit solve gets the forces from outside the actuator as
``bias_force`` (gravity from :class:`BiasForce`, minus the external effort), so it predicts the
end-of-step velocity the solver will reach. That is one solve per step, what PhysX's PGS does for
an isolated DOF; on a TGS scenario it warns with the measured size of the difference.

PhysX's joint friction has no Newton counterpart in Featherstone: a scenario with ``[friction]``
is refused. ``SolverFeatherstone`` integrates semi-implicitly (``v1 = v0 + a*dt``, ``q1 = q0 +
v1*dt``). Newton computes in float32 (the drive kernel and the implicit solve in float64).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any, Literal

import numpy as np

from drive_envelope._src.envelope.model import ENVELOPE_FIELDS, PerformanceEnvelope
from drive_envelope._src.errors import EngineWarning, InputError
from drive_envelope._src.scenario.checks import one_solve_tgs_note
from drive_envelope._src.scenario.spec import Scenario
from drive_envelope._src.scenario.trajectory import Trajectory, stand_run

DRIVES = ("physx", "actuator")
"""How the stand's drive runs: PhysX's PGS/TGS iteration (a Warp kernel), or Newton's actuator stack."""
MIN_INERTIA = 1e-12
"""Smallest inertia [kg*m^2 or kg] the stand accepts: Newton inverts the float32 mass matrix."""
MAX_VALUE = 1e30
"""Largest gain, effort or envelope slope (SI) the stand accepts: Newton stores them in float32."""
_SOLVE_TOLERANCE = 1e-10
"""Absolute residual and update tolerance of Newton's implicit solve [N*m*s or N*s]: Newton's 1e-5
default halts the approach to the speed limit short of it; this converges to float precision."""
_SOLVE_ITERATIONS = 32
"""Most iterations of the implicit solve per step (Newton's default 8)."""


def _where(scenario: Scenario) -> str:
    return f"scenario {scenario.name!r}" if scenario.name else "scenario"


def _check(scenario: Scenario) -> None:
    """Refuse what Newton's float32 model cannot hold, naming the scenario key (before building)."""
    where = _where(scenario)
    if scenario.friction.active:
        raise InputError(
            f"{where}: [friction]: the newton engine has no PhysX joint friction model (Featherstone "
            "ignores joint_friction); run it on the reference, mujoco or physx engine"
        )
    if scenario.joint.inertia < MIN_INERTIA:
        raise InputError(
            f"{where}: key 'joint.inertia' = {scenario.joint.inertia!r}: the newton engine needs at "
            f"least {MIN_INERTIA:g} (Newton inverts its float32 mass matrix)"
        )
    values = {
        "drive.stiffness": scenario.drive.stiffness,
        "drive.damping": scenario.drive.damping,
        "load.applied_effort": abs(scenario.load.applied_effort),
        "load.external_effort": abs(scenario.load.external_effort),
    }
    envelope = scenario.effective_envelope()
    if envelope is not None:
        for field in ENVELOPE_FIELDS:
            values[f"envelope.{field}"] = getattr(envelope, field)
    for key, value in values.items():
        if math.isfinite(value) and value > MAX_VALUE:
            raise InputError(
                f"{where}: key {key!r} = {value!r}: the newton engine takes at most {MAX_VALUE:g} (SI, "
                "Newton stores it in float32)"
            )


def _gains(scenario: Scenario) -> tuple[float, float]:
    """``(kp, kd)`` of Newton's force-type PD: PhysX's acceleration drive scales by the inertia."""
    drive = scenario.drive
    if drive.max_effort == 0.0:
        return 0.0, 0.0  # PhysX: maxForce = 0 turns the drive off
    scale = scenario.joint.inertia if drive.type == "acceleration" else 1.0
    return drive.stiffness * scale, drive.damping * scale


def _clamping(scenario: Scenario, clamp_class: type) -> list[tuple[type, dict[str, float]]]:
    """The envelope clamp of the stand's drive; none for a drive that is off or unlimited."""
    envelope = scenario.effective_envelope()
    if scenario.drive.max_effort == 0.0 or envelope is None:
        return []  # off: the applied effort passes unlimited; unlimited: PhysX skips the clamp
    return [(clamp_class, {field: float(getattr(envelope, field)) for field in ENVELOPE_FIELDS})]


def _build(scenario: Scenario, *, actuator: bool) -> Any:
    """The stand as a finalized ``newton.Model``, with Newton's actuator on DOF 0 when ``actuator``."""
    import newton
    import warp as wp
    from newton.actuators import DrivePD

    from drive_envelope._src.adapters.newton.clamp_stage import ClampingPerformanceEnvelope

    pendulum = scenario.pendulum
    gravity = scenario.simulation.gravity if pendulum is not None else 0.0
    builder = newton.ModelBuilder(gravity=(0.0, 0.0, -gravity))
    inertia, armature = scenario.joint.inertia, scenario.joint.armature
    if scenario.joint.type == "revolute":
        mass, com, about_com = _link(inertia, pendulum)
        link = builder.add_link(mass=mass, com=wp.vec3(*com), inertia=wp.mat33(np.eye(3) * about_com))
        add_joint: Callable[..., int] = builder.add_joint_revolute
    else:
        link = builder.add_link(mass=inertia, inertia=wp.mat33(np.eye(3)))
        add_joint = builder.add_joint_prismatic
    joint = add_joint(
        parent=-1, child=link, axis=newton.Axis.X, target_ke=0.0, target_kd=0.0, armature=armature
    )
    builder.add_articulation([joint])
    if actuator:
        kp, kd = _gains(scenario)
        clamping = _clamping(scenario, ClampingPerformanceEnvelope)
        builder.add_actuator(DrivePD, index=0, kp=kp, kd=kd, clamping=clamping)
    return builder.finalize(device="cpu")


def _link(inertia: float, pendulum: Any) -> tuple[float, tuple[float, float, float], float]:
    """Mass, centre of mass (joint frame, q = 0) and inertia about it of the revolute stand's link.

    The link is the scenario's rigid inertia (1 kg on the axis) plus the pendulum's point mass m at
    d, hanging straight down (-Z) at ``q = -angle_offset``: total mass M = 1 + m, centre of mass at
    ``c = m*d/M``, inertia about it ``inertia + m*d^2 - M*c^2`` so that the inertia about the axis
    is ``inertia + m*d^2``, and gravity's effort about X is ``-m*g*d*sin(q + angle_offset)``.
    """
    if pendulum is None:
        return 1.0, (0.0, 0.0, 0.0), inertia
    mass = 1.0 + pendulum.mass
    reach = pendulum.mass * pendulum.distance / mass
    offset = pendulum.angle_offset
    com = (0.0, reach * math.sin(offset), -reach * math.cos(offset))
    return mass, com, inertia + pendulum.inertia - mass * reach**2


def _array(value: float) -> Any:
    import warp as wp

    return wp.array(np.array([value], dtype=np.float32), dtype=wp.float32, device="cpu")


def simulate(
    scenario: Scenario,
    progress: Callable[[int, int], None] | None = None,
    *,
    drive: Literal["physx", "actuator"] = "physx",
) -> Trajectory:
    """Run ``scenario`` on Newton (Featherstone); ``steps + 1`` rows, row 0 the start.

    Args:
        scenario: The validated scenario.
        progress: Called as ``progress(done, total)`` every 1000 steps and at the end.
        drive: ``"physx"``: the scenario's PhysX solver (PGS or TGS, its iteration counts) computes
            the drive effort; ``"actuator"``: Newton's ``DrivePD`` + ``ClampingPerformanceEnvelope``
            in implicit mode, one solve per step.

    Raises:
        InputError: a value Newton's float32 model cannot hold, a state that diverged, or an
            unknown ``drive``.
    """
    from drive_envelope._src.kernels.warp_setup import quiet_warp

    if drive not in DRIVES:
        raise InputError(f"newton stand: argument 'drive' = {drive!r}: expected 'physx' or 'actuator'")
    _check(scenario)
    if drive == "actuator":
        note = one_solve_tgs_note("newton", scenario.simulation.solver)
        if note is not None:
            warnings.warn(note, EngineWarning, stacklevel=2)
    with quiet_warp():
        return _run(scenario, progress, drive)


def _run(scenario: Scenario, progress: Callable[[int, int], None] | None, drive: str) -> Trajectory:
    """Build the stand and step it (inside :func:`quiet_warp`)."""
    import newton
    from newton.actuators import JointSpaceResponse

    from drive_envelope._src.adapters.newton.bias import BiasForce

    model = _build(scenario, actuator=drive == "actuator")
    response = JointSpaceResponse(model)
    solver = newton.solvers.SolverFeatherstone(model)
    state_in, state_out, control = model.state(), model.state(), model.control()
    state_in.joint_q.assign(np.array([scenario.joint.initial_position], dtype=np.float32))
    state_in.joint_qd.assign(np.array([scenario.joint.initial_velocity], dtype=np.float32))
    newton.eval_fk(model, state_in.joint_q, state_in.joint_qd, state_in)
    control.joint_target_q.assign(np.array([scenario.drive.target_position], dtype=np.float32))
    control.joint_target_qd.assign(np.array([scenario.drive.target_velocity], dtype=np.float32))
    control.joint_act.assign(np.array([scenario.load.applied_effort], dtype=np.float32))
    load = _array(scenario.load.external_effort)
    bias = BiasForce(model, coriolis=False)  # one DOF on a fixed base: no Coriolis force
    # the manipulator equation's bias (tau = M qdd + b): gravity, minus the load from outside
    if drive == "physx":
        effort_of = _physx_drive(scenario, model, response, bias, load)
    else:
        effort_of = _actuator_drive(scenario, model, response, bias, load)
    count = scenario.simulation.steps
    dt = scenario.simulation.dt
    position, velocity, effort = np.empty(count + 1), np.empty(count + 1), np.zeros(count + 1)
    position[0], velocity[0] = scenario.joint.initial_position, scenario.joint.initial_velocity
    let_go = _LetGo(scenario) if drive == "actuator" else None
    for i in range(1, count + 1):
        effort[i], after = effort_of(state_in, control)
        solver.step(state_in, state_out, control, None, dt)  # type: ignore[arg-type]  # no contacts
        state_in, state_out = state_out, state_in
        if after is not None:
            after(state_in)
        position[i] = float(state_in.joint_q.numpy()[0])
        velocity[i] = float(state_in.joint_qd.numpy()[0])
        if not (math.isfinite(position[i]) and math.isfinite(velocity[i])):
            raise InputError(
                f"{_where(scenario)}: Newton's state diverged at step {i} (t = {i * dt:.6g} s): "
                "check dt, inertia, gains and loads"
            )
        if let_go is not None:
            let_go.see(i, position[i], velocity[i], effort[i])
        if progress is not None and (i % 1000 == 0 or i == count):
            progress(i, count)
    if let_go is not None:
        let_go.report(dt)
    return stand_run(scenario, "newton", position, velocity, effort, **_metadata(scenario, drive))


_StepEffort = Callable[[Any, Any], tuple[float, Callable[[Any], None] | None]]
"""Per step: writes ``control.joint_f`` from the start state, returns the actuator effort [N*m or
N] and what to do to the state after the solver step (or None)."""


def _physx_drive(scenario: Scenario, model: Any, response: Any, bias: Any, load: Any) -> _StepEffort:
    """The drive as the scenario's PhysX solver iterates it (:mod:`physx_drive`'s kernel)."""
    import newton
    import warp as wp

    from drive_envelope._src.adapters.newton import physx_drive

    sim, drive = scenario.simulation, scenario.drive
    envelope = scenario.effective_envelope()
    on = drive.max_effort != 0.0  # PhysX: maxForce = 0 turns the drive off
    row = [drive.stiffness, drive.damping, 0.0, math.inf, 0.0, 0.0]
    if envelope is not None:
        row[2:] = [getattr(envelope, field) for field in physx_drive.PARAMS[2:]]
    flags = [int(sim.solver == "tgs"), sim.position_iterations, sim.velocity_iterations,
             int(drive.type == "acceleration"), int(on), int(envelope is not None)]  # fmt: skip
    params: Any = wp.array(np.array([row], dtype=np.float64), dtype=wp.float64, device="cpu")
    flag_array: Any = wp.array(np.array([flags], dtype=np.int32), dtype=wp.int32, device="cpu")
    effort = wp.zeros(1, dtype=wp.float64, device="cpu")
    shift = wp.zeros(1, dtype=wp.float64, device="cpu")
    dt = sim.dt

    def after(state: Any) -> None:
        physx_drive.shift_positions(state, shift)
        newton.eval_fk(model, state.joint_q, state.joint_qd, state)  # the bodies at the moved position

    def step(state: Any, control: Any) -> tuple[float, Callable[[Any], None] | None]:
        response.refresh(state)
        physx_drive.launch_drive(state, control, response.inverse_blocks, bias.compute(state, external=load),
                                 load, params, flag_array, dt, effort, shift)  # fmt: skip
        return float(effort.numpy()[0]), after

    return step


def _actuator_drive(scenario: Scenario, model: Any, response: Any, bias: Any, load: Any) -> _StepEffort:
    """Newton's ``DrivePD`` + ``ClampingPerformanceEnvelope``, implicit: one solve per step."""
    from newton.actuators import Actuator

    actuator = model.actuators[0]
    actuator.set_effort_mode_implicit(
        response=response,
        options=Actuator.ImplicitOptions(
            max_iters=_SOLVE_ITERATIONS, residual_tol=_SOLVE_TOLERANCE, update_tol=_SOLVE_TOLERANCE
        ),
    )
    dt, external = scenario.simulation.dt, scenario.load.external_effort

    def step(state: Any, control: Any) -> tuple[float, Callable[[Any], None] | None]:
        control.joint_f.zero_()
        response.refresh(state)
        actuator.step(state, control, dt=dt, bias_force=bias.compute(state, external=load))
        effort = float(control.joint_f.numpy()[0])
        control.joint_f.assign(np.array([effort + external], dtype=np.float32))
        return effort, None

    return step


class _LetGo:
    """Counts the steps where Newton's implicit solve let the drive go beyond the speed line.

    Newton solves ``p = dt * clip(drive(v(p)), -L(v(p)), L(v(p)))``: when the step without drive
    effort would end beyond the speed line, ``p = 0`` solves it and the solve stops there, where
    PhysX's ``clampDriveImpulse`` brakes whenever braking makes the step feasible
    (docs/newton.md). A step counts when the effort is 0, the joint ends with no feasible effort,
    and a braking effort the drive law asks for would have been feasible (:func:`_can_brake`); one
    :class:`EngineWarning` says how many. Where PhysX lets go too (a load that no braking within
    the envelope can hold), nothing is counted.
    """

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.envelope = scenario.effective_envelope()
        self.response = scenario.simulation.dt / scenario.effective_inertia  # [rad/s per N*m]
        self.steps = 0
        self.first = 0

    def see(self, step: int, position: float, velocity: float, effort: float) -> None:
        envelope = self.envelope
        if envelope is None or effort != 0.0 or float(envelope.effort_limit(velocity)) != 0.0:
            return
        drive = self.scenario.drive
        request = drive.stiffness * (drive.target_position - position)
        request += drive.damping * (drive.target_velocity - velocity)
        if request * velocity < 0.0 and _can_brake(envelope, abs(velocity), self.response, abs(request)):
            self.steps += 1
            self.first = self.first or step

    def report(self, dt: float) -> None:
        if self.steps:
            import warnings

            warnings.warn(
                f"{_where(self.scenario)}: Newton's implicit solve let the drive go in {self.steps} "
                f"step(s), first at t = {self.first * dt:.6g} s, with the joint beyond its speed line "
                "and the drive asking to brake; PhysX brakes there when braking makes the step "
                "feasible (a limit of Newton 1.8's implicit effort mode, see docs/newton.md): compare "
                "with --engine reference",
                EngineWarning,
                stacklevel=3,
            )


def _can_brake(envelope: PerformanceEnvelope, speed: float, response: float, request: float) -> bool:
    """Whether some braking effort ``0 < e <= request`` is feasible at the speed it leaves, ``speed - r*e``.

    Each line of the envelope is ``e <= a - b*s`` at speed ``s`` (eq. 1: ``a = max_effort``,
    ``b = R``; eq. 2: ``a = v_max/G``, ``b = 1/G``); at ``s = speed - r*e`` it reads
    ``(b*r - 1)*e >= b*speed - a``. ``speed`` [rad/s or m/s], ``response`` ``r`` [(rad/s)/(N*m)].
    """
    low, high = 0.0, request
    lines = [(envelope.max_effort, envelope.velocity_dependent_resistance)]
    if envelope.speed_effort_gradient > 0.0 and math.isfinite(envelope.max_actuator_velocity):
        gradient = envelope.speed_effort_gradient
        lines.append((envelope.max_actuator_velocity / gradient, 1.0 / gradient))
    elif math.isfinite(envelope.max_actuator_velocity) and speed > envelope.max_actuator_velocity:
        low = max(low, (speed - envelope.max_actuator_velocity) / response)  # back on the speed limit
    for a, b in lines:
        slope, need = b * response - 1.0, b * speed - a
        if slope > 0.0:
            low = max(low, need / slope)
        elif slope < 0.0:
            high = min(high, need / slope)
        elif need > 0.0:
            return False
    return 0.0 < high and low <= high


def _metadata(scenario: Scenario, drive: str) -> dict[str, object]:
    """What a run's metadata adds to the solver settings (:func:`stand_run` puts them first)."""
    import newton

    data: dict[str, object] = {
        "newton_version": str(newton.__version__),
        "newton_solver": "SolverFeatherstone",
        "drive": drive,
    }
    if drive == "physx":
        data["drive_solver"] = scenario.simulation.solver
        data["effort_source"] = "PhysX's drive iteration (Warp kernel), applied as joint_f"
    else:
        data["effort_mode"] = "implicit"
        data["clamp"] = "ClampingPerformanceEnvelope"
        data["note"] = "one implicit drive solve per step (PhysX PGS for an isolated DOF)"
    data["unlimited_effort"] = math.isinf(scenario.drive.max_effort)
    return data

"""Replaying bench logs through the reference test stand for many candidate parameter sets at once.

A :class:`Replay` packs ``L`` logs (same sampling step) into arrays padded to the longest; one call
of :meth:`Replay.run` simulates ``S`` candidate parameter sets on every log together, ``S*L`` stands
in one :func:`~drive_envelope._src.teststand.batch.simulate_batch` pass (element ``s*L + l`` is
candidate ``s`` on log ``l``). Each log starts from its first sample's position and velocity (0
when the log has no velocity) and follows its targets and ``torque_enable``; the simulated row
``i`` is compared with the measured row ``i``, as BAM compares its rollouts, so the mean absolute
error of a log covers all its rows (row 0 is the initial state).

A log's stiffness is ``duty_per_rad * duty_effort`` (``duty_effort`` is ``max_effort`` unless the
stand or the fit separates them) when the log (sidecar) or the stand gives a duty
gain (a voltage-driven servo), else the candidate's ``stiffness``. ``dynamic_friction`` above
``static_friction`` is clipped to it (PhysX's schema asks for ``dynamic <= static``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.logs import BenchLog
from drive_envelope._src.identify.stand import IdentifyStand
from drive_envelope._src.teststand.batch import BatchResult, BatchStand, simulate_batch
from drive_envelope._src.teststand.engines.reference import batch_solver

FloatArray = npt.NDArray[np.float64]
_DIVERGED = 1e3  # error given to a diverged candidate [rad]: worse than any real fit


@dataclass(frozen=True, slots=True)
class ReplayErrors:
    """Errors of ``S`` candidates on ``L`` logs."""

    position: FloatArray
    """Mean absolute position error, shape ``(S, L)`` [rad or m]."""
    velocity: FloatArray | None
    """Mean absolute velocity error ``(S, L)`` [rad/s or m/s], None when a log has no velocity."""
    residuals: FloatArray | None
    """Per-sample position errors ``(S, N)`` (every log's rows, each log weighted by 1/rows), or None."""


class Replay:
    """Bench logs packed for batched replay on one stand."""

    def __init__(self, stand: IdentifyStand, logs: Sequence[BenchLog]) -> None:
        """Pack ``logs`` for replay on ``stand``.

        Raises:
            InputError: no logs, or logs with different sampling steps.
        """
        if not logs:
            raise InputError("identify: no logs to replay")
        dts = [log.dt for log in logs]
        if max(dts) - min(dts) > 1e-6 * max(dts):
            detail = ", ".join(f"{log.name} {log.dt:.6g} s" for log in logs)
            raise InputError(f"identify: the logs have different sampling steps ({detail}); expected one dt")
        self.stand = stand
        self.logs = tuple(logs)
        self.dt = float(np.mean(dts))
        self.solver = batch_solver(stand.scenario, self.dt)
        rows = max(log.rows for log in logs)
        count = len(logs)
        self.rows = np.array([log.rows for log in logs])
        self.measured = np.full((rows, count), np.nan)
        self.measured_velocity: FloatArray | None = np.full((rows, count), np.nan)
        self.target_position = np.empty((rows - 1, count))
        self.target_velocity = np.empty((rows - 1, count))
        self.enabled = np.empty((rows - 1, count))
        for i, log in enumerate(logs):
            n = log.rows
            self.measured[:n, i] = log.position
            if log.velocity is None:
                self.measured_velocity = None
            elif self.measured_velocity is not None:
                self.measured_velocity[:n, i] = log.velocity
            # padding past a log's end repeats its last command; those rows are never scored
            self.target_position[:, i] = _padded(log.target_position[:-1], rows - 1)
            self.target_velocity[:, i] = _padded(log.target_velocity[:-1], rows - 1)
            self.enabled[:, i] = _padded(log.enabled[:-1].astype(np.float64), rows - 1)
        self.mask = np.isfinite(self.measured)
        self.initial_position = np.array([log.position[0] for log in logs])
        self.initial_velocity = np.array([0.0 if log.velocity is None else log.velocity[0] for log in logs])
        duty = [log.duty_per_rad if log.duty_per_rad is not None else stand.duty_per_rad for log in logs]
        self.duty = np.array([np.nan if value is None else value for value in duty])
        self.speed_scale = float(
            max(
                np.nanmax(np.abs(self.measured_velocity)) if self.measured_velocity is not None else 0.0,
                np.nanmax(np.abs(np.diff(self.measured, axis=0))) / self.dt,
                1e-9,
            )
        )

    @property
    def uses_duty(self) -> bool:
        """Whether any log's stiffness follows ``max_effort`` through a duty gain."""
        return bool(np.isfinite(self.duty).any())

    def stands(self, values: Mapping[str, FloatArray]) -> BatchStand:
        """The ``S*L`` stands of ``S`` candidates (name -> array ``(S,)``) on every log."""
        count = len(self.logs)
        scenario = self.stand.scenario

        def each(name: str) -> FloatArray:
            return np.repeat(np.asarray(values[name], dtype=np.float64), count)

        size = int(np.asarray(values["max_effort"]).shape[0])
        duty = np.tile(self.duty, size)
        max_effort = each("max_effort")
        stiffness = np.where(np.isfinite(duty), duty * each("duty_effort"), each("stiffness"))
        static = each("static_friction")
        pendulum = scenario.pendulum
        base = scenario.joint.inertia + (pendulum.inertia if pendulum is not None else 0.0)
        gravity = 0.0 if pendulum is None else pendulum.mass * scenario.simulation.gravity * pendulum.distance
        load = scenario.load
        return BatchStand(
            inertia=base + each("armature"),
            stiffness=stiffness,
            damping=each("damping"),
            max_effort=max_effort,
            max_actuator_velocity=each("max_actuator_velocity"),
            velocity_dependent_resistance=each("velocity_dependent_resistance"),
            speed_effort_gradient=each("speed_effort_gradient"),
            static_friction=static,
            dynamic_friction=np.minimum(each("dynamic_friction"), static),
            viscous_friction=each("viscous_friction"),
            gravity_torque=np.full(size * count, gravity),
            angle_offset=each("angle_offset"),
            applied_effort=np.full(size * count, load.applied_effort),
            external_effort=np.full(size * count, load.external_effort),
        )

    def simulate(self, values: Mapping[str, FloatArray]) -> BatchResult:
        """Simulate ``S`` candidates on every log; arrays ``(rows, S*L)``."""
        size = int(np.asarray(values["max_effort"]).shape[0])
        return simulate_batch(
            self.solver,
            self.stands(values),
            initial_position=np.tile(self.initial_position, size),
            initial_velocity=np.tile(self.initial_velocity, size),
            target_position=np.tile(self.target_position, (1, size)),
            target_velocity=np.tile(self.target_velocity, (1, size)),
            enabled=np.tile(self.enabled, (1, size)),
        )

    def errors(self, values: Mapping[str, FloatArray], *, residuals: bool = False) -> ReplayErrors:
        """Mean absolute errors of ``S`` candidates on every log (diverged ones get a large error)."""
        size = int(np.asarray(values["max_effort"]).shape[0])
        count = len(self.logs)
        result = self.simulate(values)
        position = result.position.reshape(-1, size, count)
        error = np.abs(position - self.measured[:, None, :])
        mae = np.nansum(np.where(self.mask[:, None, :], error, 0.0), axis=0) / self.rows
        diverged = result.diverged.reshape(size, count)
        mae = np.where(diverged | ~np.isfinite(mae), _DIVERGED, mae)
        velocity_mae = None
        if self.measured_velocity is not None:
            velocity = result.velocity.reshape(-1, size, count)
            verror = np.abs(velocity - self.measured_velocity[:, None, :])
            velocity_mae = np.nansum(np.where(self.mask[:, None, :], verror, 0.0), axis=0) / self.rows
            velocity_mae = np.where(diverged | ~np.isfinite(velocity_mae), _DIVERGED, velocity_mae)
        flat = None
        if residuals:
            signed = np.where(self.mask[:, None, :], position - self.measured[:, None, :], 0.0)
            signed = np.where(np.isfinite(signed), signed, _DIVERGED) / np.sqrt(self.rows)
            flat = signed.transpose(1, 2, 0).reshape(size, -1)
        return ReplayErrors(position=mae, velocity=velocity_mae, residuals=flat)


def _padded(values: FloatArray, length: int) -> FloatArray:
    if values.shape[0] >= length:
        return values[:length]
    return np.concatenate([values, np.full(length - values.shape[0], values[-1])])

# mypy: disable-error-code="index"
# (Warp kernel bodies index wp.array values, which Warp's type stubs do not declare indexable)
"""``ClampingPerformanceEnvelope`` itself: imports Newton and Warp at the top, so it is imported lazily.

:mod:`~drive_envelope._src.adapters.newton.clamp` explains the stage and validates its arguments;
``drive_envelope.newton`` loads this module on the first access to the class, the stand and the USD
import when they run. The class is defined here at module level (once per process, as Warp's
kernels must be); its ``__module__`` names the public facade, whose ``__getattr__`` returns this
same class, so reprs, docs and pickles use the one public path.
"""

import math
from typing import Any

import warp as wp
from newton.actuators import ClampingBase

from drive_envelope._src.adapters.newton.clamp import resolve_envelope_arguments
from drive_envelope._src.envelope.model import ENVELOPE_FIELDS
from drive_envelope._src.errors import InputError
from drive_envelope._src.kernels.warp_funcs import clamp_effort_func


@wp.func
def _evaluate_envelope_clamp(
    value: wp.float64,
    q: wp.float64,
    qd: wp.float64,
    params: wp.array2d[wp.float32],
    i: int,
    base: int,
) -> wp.float64:
    """Implicit-solve entry point; params row is ``[max_effort, v_max, R, G]``.

    ``qd`` is the predicted end-of-step velocity, so ``|effort| <= L(qd)`` holds at the end of
    the step: clip(value, -L(qd), L(qd)), L(v) = max(min(max_effort - R|v|, (v_max - |v|)/G), 0).
    The float32 parameters are widened to float64 (exactly) so that one generic function serves
    both stages: Warp's generic functions need one type per call, it does not promote.
    """
    return clamp_effort_func(
        wp.float64(params[i, base]),
        wp.float64(params[i, base + 1]),
        wp.float64(params[i, base + 2]),
        wp.float64(params[i, base + 3]),
        value,
        qd,
    )


@wp.kernel(enable_backward=False)
def _clamp_envelope_kernel(
    current_vel: wp.array[wp.float32],
    state_indices: wp.array[wp.uint32],
    max_effort: wp.array[wp.float32],
    max_actuator_velocity: wp.array[wp.float32],
    velocity_dependent_resistance: wp.array[wp.float32],
    speed_effort_gradient: wp.array[wp.float32],
    src: wp.array[wp.float32],
    dst: wp.array[wp.float32],
):
    """dst[i] = clip(src[i], -L_i(v), L_i(v)) at the measured velocity v of DOF i."""
    i = wp.tid()
    dst[i] = clamp_effort_func(
        max_effort[i],
        max_actuator_velocity[i],
        velocity_dependent_resistance[i],
        speed_effort_gradient[i],
        src[i],
        current_vel[state_indices[i]],
    )


class ClampingPerformanceEnvelope(ClampingBase):  # type: ignore[misc,valid-type]
    """PhysX drive performance envelope as a Newton clamping stage (explicit and implicit modes).

    Bounds the drive's effort to ``L(v) = max(min(max_effort - R|v|, (v_max - |v|)/G), 0)``
    at the measured velocity (explicit mode) or at the predicted end-of-step velocity (implicit
    mode, PhysX's semantics). Usage with a model builder::

        builder.add_actuator(DrivePD, index=dof, kp=50.0, kd=2.0,
                             clamping=[(ClampingPerformanceEnvelope, {"max_effort": 12.0,
                                        "max_actuator_velocity": 8.0, "speed_effort_gradient": 0.5})])
    """

    # the per-DOF float32 arrays of ENVELOPE_FIELDS (columns of the packed block once bound)
    max_effort: Any
    max_actuator_velocity: Any
    velocity_dependent_resistance: Any
    speed_effort_gradient: Any

    @classmethod
    def resolve_arguments(cls, args: dict[str, Any]) -> dict[str, Any]:
        """Validate scalar arguments (SI numbers or strings with units) and fill defaults."""
        return resolve_envelope_arguments(args)

    def __init__(
        self,
        max_effort: Any,
        max_actuator_velocity: Any = None,
        velocity_dependent_resistance: Any = None,
        speed_effort_gradient: Any = None,
    ) -> None:
        """Initialize from per-DOF float32 arrays of shape ``(N,)`` (shapes are checked, values not).

        Args:
            max_effort: Effort cap at zero velocity [N*m or N]. Shape ``(N,)``.
            max_actuator_velocity: Speed cap at zero effort [rad/s or m/s]; ``None``: inf.
            velocity_dependent_resistance: R [N*m*s/rad or N*s/m]; ``None``: 0.
            speed_effort_gradient: G [(rad/s)/(N*m) or (m/s)/N]; ``None``: 0.
        """
        given = (max_effort, max_actuator_velocity, velocity_dependent_resistance, speed_effort_gradient)
        for name, array in zip(ENVELOPE_FIELDS, given, strict=True):
            if array is not None and not isinstance(array, wp.array):
                raise InputError(
                    f"ClampingPerformanceEnvelope: {name}: expected a float32 wp.array of shape (N,) "
                    f"(pass scalars through builder.add_actuator), got {type(array).__name__}"
                )
        n, device = max_effort.shape, max_effort.device
        for name, array, default in zip(ENVELOPE_FIELDS, given, (None, math.inf, 0.0, 0.0), strict=True):
            if array is None:
                array = wp.full(n, default, dtype=wp.float32, device=device)
            elif array.shape != n:
                raise InputError(f"{name} shape {array.shape} must match max_effort shape {n}")
            setattr(self, name, array)

    evaluate_clamp = _evaluate_envelope_clamp  # type: ignore[assignment]  # a wp.Function at runtime

    def finalize(self, device: Any, num_actuators: int) -> None:
        """Check that the parameter arrays cover the actuator's DOFs."""
        if self.max_effort.shape[0] != num_actuators:
            count = self.max_effort.shape[0]
            raise InputError(f"ClampingPerformanceEnvelope: {count} DOFs, its actuator {num_actuators}")

    def param_width(self) -> int:
        """Columns in the packed parameter array: max_effort, v_max, R, G."""
        return 4

    def bind_params(self, block: Any) -> None:
        """Copy the parameters into the packed block and re-point the attributes at its columns."""
        for column, name in enumerate(ENVELOPE_FIELDS):
            block[:, column].assign(getattr(self, name))
            setattr(self, name, block[:, column])

    def modify_forces(
        self,
        src_forces: Any,
        dst_forces: Any,
        positions: Any,
        velocities: Any,
        pos_indices: Any,
        vel_indices: Any,
        device: Any = None,
    ) -> None:
        """Read effort from ``src_forces``, clamp it at the current velocity, write ``dst_forces``.

        Args:
            src_forces: Drive effort [N*m or N]. Shape ``(N,)``.
            dst_forces: Output effort [N*m or N] (may be ``src_forces``). Shape ``(N,)``.
            positions: Joint positions [rad or m] (unused).
            velocities: Joint velocities [rad/s or m/s], indexed by ``vel_indices``.
            pos_indices: Indices into ``positions`` (unused).
            vel_indices: Index of each DOF into ``velocities``.
            device: Warp device for the launch.
        """
        wp.launch(
            kernel=_clamp_envelope_kernel,
            dim=len(src_forces),
            inputs=[
                velocities,
                vel_indices,
                self.max_effort,
                self.max_actuator_velocity,
                self.velocity_dependent_resistance,
                self.speed_effort_gradient,
                src_forces,
            ],
            outputs=[dst_forces],
            device=device,
        )


# the public path (drive_envelope.newton resolves it to this class, so pickling by reference works)
ClampingPerformanceEnvelope.__module__ = "drive_envelope.newton"

"""How the plugin solves a model's drives each step: exactly, or as PhysX's PGS or TGS iterate.

The setting lives in the model as the custom numeric :data:`SOLVER_NUMERIC`::

    <custom><numeric name="drive_envelope_solver" size="4" data="2 4 1 0"/></custom>
    data[0]  solver               0 exact, 1 pgs, 2 tgs
    data[1]  position_iterations  [1, 255]: PGS's position sweeps, TGS's substeps
    data[2]  velocity_iterations  [0, 255] (PGS runs at least one, as PhysX does)
    data[3]  constraints          0 (reserved: the drives are solved before MuJoCo's constraints)

Why a custom numeric: the setting belongs to the model as a whole (PhysX's solver type is the
scene's, and one MuJoCo model is one scene), MuJoCo's writer keeps it through ``mj_saveLastXML``,
``MjSpec.to_xml`` and ``MjSpec.from_file``, it is one line a reader of the MJCF can see, and the
plugin reads its numbers at every step as it reads the drives' ``dynprm``: a model compiled with it
can switch solver or iteration counts between steps (``set_solver`` on the ``MjModel``), and
``mujoco.rollout`` over several models uses each model's own. A model without it gets the exact
coupled solve. Plugin instance attributes would be per instance and fixed when an ``MjData`` is
made; the drives' ``dynprm`` are per drive.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, TypeAlias

from drive_envelope._src.errors import InputError

if TYPE_CHECKING:
    import mujoco

__all__ = [
    "MAX_ITERATIONS",
    "SOLVERS",
    "SOLVER_NUMERIC",
    "MjSolver",
    "SolverName",
    "get_solver",
    "set_solver",
]

SolverName: TypeAlias = Literal["exact", "pgs", "tgs"]
SOLVERS: tuple[SolverName, ...] = ("exact", "pgs", "tgs")
"""The plugin's solvers, in the order of their code in ``data[0]`` of :data:`SOLVER_NUMERIC`."""
SOLVER_NUMERIC = "drive_envelope_solver"
"""Name of the model's custom numeric that holds the solver setting."""
MAX_ITERATIONS = 255
"""PhysX's bound on an articulation's position and velocity iteration counts."""
_SIZE = 4


@dataclass(frozen=True, kw_only=True, slots=True)
class MjSolver:
    """A model's drive solver (:func:`get_solver`)."""

    solver: SolverName
    """``"exact"`` (the coupled solve, the default), ``"pgs"`` or ``"tgs"`` (PhysX's iteration)."""
    position_iterations: int
    """PGS: position sweeps over the drives; TGS: substeps of ``dt/position_iterations`` [-]."""
    velocity_iterations: int
    """Velocity sweeps after them; PGS runs at least one whatever is set, as PhysX does [-]."""


def _iterations(value: object, name: str, low: int, where: str) -> int:
    if (
        isinstance(value, bool)
        or not isinstance(value, numbers.Integral)
        or not low <= int(value) <= MAX_ITERATIONS
    ):
        raise InputError(
            f"{where}: argument {name!r} = {value!r}: expected an integer in [{low}, {MAX_ITERATIONS}]"
        )
    return int(value)


def _wrong_type(where: str, target: object) -> InputError:
    kind = type(target).__name__
    return InputError(f"{where}: argument 'spec_or_model' is a {kind}: expected a mujoco.MjSpec or MjModel")


def _is_spec(target: object) -> bool:
    import mujoco

    return isinstance(target, mujoco.MjSpec)


def set_solver(
    spec_or_model: mujoco.MjSpec | mujoco.MjModel,
    solver: SolverName,
    *,
    position_iterations: int = 4,
    velocity_iterations: int = 1,
) -> None:
    """Choose how the plugin solves the drives of a model: exactly, or as PhysX's PGS or TGS iterate.

    ``"exact"`` solves every drive of the model together to 1e-12 each step (the envelope held at
    the velocity MuJoCo integrates). ``"pgs"`` and ``"tgs"`` run PhysX's articulation iteration
    instead, what Isaac Lab trains with: the drives as velocity rows in Gauss-Seidel sweeps from the
    root to the leaves, each clamped on its own with the others held (``plugin/mujoco/README.md``,
    "Solvers"). The iteration counts are the articulation's (Isaac Lab's
    ``solver_position_iteration_count`` / ``solver_velocity_iteration_count``; PhysX's defaults 4
    and 1); ``"exact"`` ignores them.

    On an ``MjSpec`` this adds (or updates) the custom numeric :data:`SOLVER_NUMERIC`; on an
    ``MjModel`` compiled with it, it changes the numbers in place, effective at the next step of
    every ``MjData`` of that model.

    Args:
        spec_or_model: The ``mujoco.MjSpec`` to compile, or an ``mujoco.MjModel`` that has the numeric.
        solver: ``"exact"``, ``"pgs"`` or ``"tgs"``.
        position_iterations: Position iterations, in [1, 255] [-].
        velocity_iterations: Velocity iterations, in [0, 255] [-].

    Raises:
        InputError: an unknown solver, an iteration count out of range, an ``MjModel`` compiled
            without the numeric, or an object that is neither.
    """
    where = "set_solver"
    if solver not in SOLVERS:
        raise InputError(f"{where}: argument 'solver' = {solver!r}: expected one of 'exact', 'pgs', 'tgs'")
    position = _iterations(position_iterations, "position_iterations", 1, where)
    velocity = _iterations(velocity_iterations, "velocity_iterations", 0, where)
    values = [float(SOLVERS.index(solver)), float(position), float(velocity), 0.0]
    import mujoco

    if _is_spec(spec_or_model):
        spec = spec_or_model
        assert isinstance(spec, mujoco.MjSpec)
        existing = spec.numeric(SOLVER_NUMERIC)
        if existing is not None:
            existing.data = values
            existing.size = _SIZE
        else:
            spec.add_numeric(name=SOLVER_NUMERIC, data=values, size=_SIZE)
        return
    if not isinstance(spec_or_model, mujoco.MjModel):
        raise _wrong_type(where, spec_or_model)
    model = spec_or_model
    index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, SOLVER_NUMERIC)
    if index < 0:
        raise InputError(
            f"{where}: the model has no custom numeric {SOLVER_NUMERIC!r}: call set_solver on its MjSpec "
            "before compiling (the plugin finds the setting when an MjData is made), then change it here"
        )
    adr, size = int(model.numeric_adr[index]), int(model.numeric_size[index])
    if size not in (3, _SIZE):
        raise InputError(f"{where}: custom numeric {SOLVER_NUMERIC!r} has {size} number(s): expected {_SIZE}")
    model.numeric_data[adr : adr + size] = values[:size]


def get_solver(spec_or_model: mujoco.MjSpec | mujoco.MjModel) -> MjSolver:
    """The drive solver of an ``MjSpec`` or ``MjModel`` (``"exact"`` without :data:`SOLVER_NUMERIC`).

    Raises:
        InputError: the numeric holds values the plugin refuses, or an object that is neither.
    """
    import mujoco

    where = "get_solver"
    if _is_spec(spec_or_model):
        assert isinstance(spec_or_model, mujoco.MjSpec)
        numeric = spec_or_model.numeric(SOLVER_NUMERIC)
        values = None if numeric is None else [float(v) for v in numeric.data]
    elif isinstance(spec_or_model, mujoco.MjModel):
        model = spec_or_model
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, SOLVER_NUMERIC)
        if index < 0:
            values = None
        else:
            adr, size = int(model.numeric_adr[index]), int(model.numeric_size[index])
            values = [float(v) for v in model.numeric_data[adr : adr + size]]
    else:
        raise _wrong_type(where, spec_or_model)
    if values is None:
        return MjSolver(solver="exact", position_iterations=1, velocity_iterations=0)
    code = values[0] if values else math.nan
    if len(values) not in (3, 4) or code not in (0.0, 1.0, 2.0):
        raise InputError(
            f"{where}: custom numeric {SOLVER_NUMERIC!r} = {values}: expected "
            "'solver position_iterations velocity_iterations constraints' with solver 0, 1 or 2"
        )
    return MjSolver(
        solver=SOLVERS[int(code)],
        position_iterations=int(values[1]),
        velocity_iterations=int(values[2]),
    )

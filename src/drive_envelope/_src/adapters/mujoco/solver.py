"""How the plugin solves a model's drives each step: exactly, or as PhysX's PGS or TGS iterate.

The setting lives in the model as the custom numeric :data:`SOLVER_NUMERIC`::

    <custom><numeric name="drive_envelope_solver" size="4" data="2 4 1 0"/></custom>
    data[0]  solver               0 exact, 1 pgs, 2 tgs
    data[1]  position_iterations  [1, 255]: PGS's position sweeps, TGS's substeps
    data[2]  velocity_iterations  [0, 255] (PGS runs at least one, as PhysX does)
    data[3]  constraints          0: drives solved before MuJoCo's constraints; 1 (exact only): with them

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
    constraints: bool = False
    """``"exact"`` only: each step's efforts re-solved with MuJoCo's constraint solve in the loop
    until every drive is inside its envelope at the velocity MuJoCo integrates (``set_solver``)."""


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
    constraints: bool = False,
) -> None:
    """Choose how the plugin solves the drives of a model: exactly, or as PhysX's PGS or TGS iterate.

    ``"exact"`` solves every drive of the model together to 1e-12 each step (the envelope held at
    the velocity MuJoCo integrates). ``"pgs"`` and ``"tgs"`` run PhysX's articulation iteration
    instead, what Isaac Lab trains with: the drives as velocity rows in Gauss-Seidel sweeps from the
    root to the leaves, each clamped on its own with the others held (``plugin/mujoco/README.md``,
    "Solvers"). The iteration counts are the articulation's (Isaac Lab's
    ``solver_position_iteration_count`` / ``solver_velocity_iteration_count``; PhysX's defaults 4
    and 1); ``"exact"`` ignores them.

    ``constraints=True`` (``"exact"`` only) puts MuJoCo's constraint solve (contacts, joint limits,
    equalities, friction loss) into the drives' solve: inside the plugin's step, each candidate set
    of efforts runs through ``mj_fwdConstraint`` (warm-started from the last one) and the
    integrator's velocity update, and is re-solved by Newton steps on the constrained Hessian
    ``M + h*D' + J'*D*J`` until MuJoCo's own solve shows every drive inside its envelope (or letting
    go) at the velocity it integrates, at most 4 re-solves per step (then the checked set closest to
    inside). Every step costs one constraint solve more, each re-solve one more again
    (``docs/mujoco.md``, "Constraints solved with the drives"). Without constraint rows in a step,
    and under RK4, it is the default solve; the default (``False``) is unchanged.

    On an ``MjSpec`` this adds (or updates) the custom numeric :data:`SOLVER_NUMERIC`; on an
    ``MjModel`` compiled with it, it changes the numbers in place, effective at the next step of
    every ``MjData`` of that model.

    Args:
        spec_or_model: The ``mujoco.MjSpec`` to compile, or an ``mujoco.MjModel`` that has the numeric.
        solver: ``"exact"``, ``"pgs"`` or ``"tgs"``.
        position_iterations: Position iterations, in [1, 255] [-].
        velocity_iterations: Velocity iterations, in [0, 255] [-].
        constraints: Solve the drives with MuJoCo's constraints (``"exact"`` only) [-].

    Raises:
        InputError: an unknown solver, an iteration count out of range, ``constraints`` not a bool
            or set with ``"pgs"``/``"tgs"``, an ``MjModel`` compiled without the numeric, or an
            object that is neither.
    """
    where = "set_solver"
    if solver not in SOLVERS:
        raise InputError(f"{where}: argument 'solver' = {solver!r}: expected one of 'exact', 'pgs', 'tgs'")
    position = _iterations(position_iterations, "position_iterations", 1, where)
    velocity = _iterations(velocity_iterations, "velocity_iterations", 0, where)
    if not isinstance(constraints, bool):
        raise InputError(f"{where}: argument 'constraints' = {constraints!r}: expected True or False")
    if constraints and solver != "exact":
        raise InputError(
            f"{where}: argument 'constraints' = True with solver {solver!r}: expected solver 'exact' "
            "(PhysX's PGS and TGS solve the drives before the constraints)"
        )
    values = [float(SOLVERS.index(solver)), float(position), float(velocity), float(constraints)]
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
    if size not in (3, _SIZE) or (size == 3 and constraints):
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
    flag = values[3] if len(values) == 4 else 0.0
    if len(values) not in (3, 4) or code not in (0.0, 1.0, 2.0) or flag not in (0.0, 1.0) or (flag and code):
        raise InputError(
            f"{where}: custom numeric {SOLVER_NUMERIC!r} = {values}: expected "
            "'solver position_iterations velocity_iterations constraints' with solver 0, 1 or 2 "
            "and constraints 0, or 1 with solver 0"
        )
    return MjSolver(
        solver=SOLVERS[int(code)],
        position_iterations=int(values[1]),
        velocity_iterations=int(values[2]),
        constraints=bool(flag),
    )

"""Golden values of the envelope geometry and the explicit clamp, computed by hand from the spec.

The envelope used throughout: max_effort 10, max_actuator_velocity 5, R = 1, G = 0.25::

    effort_limit(v) = min(10 - |v|, (5 - |v|) / 0.25) = min(10 - |v|, 20 - 4|v|), clipped at 0

           tau
            10 +  stall (0, 10)
               |\\__
               |    \\__  eq. 1: tau = 10 - v
               |        \\__
          20/3 +            * corner (10/3, 20/3): both lines bind
               |             \\
               |              \\  eq. 2: v = 5 - 0.25 tau
               |               \\
           ----+----------------+------> v
               0                5  no-load (5, 0)

    quadrants: I drive (+v, +tau)   II brake (-v, +tau)   III drive (-v, -tau)   IV brake (+v, -tau)
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import drive_envelope as de
from drive_envelope import InputError, PerformanceEnvelope, clamp_effort

ENV = PerformanceEnvelope(
    max_effort=10.0, max_actuator_velocity=5.0, velocity_dependent_resistance=1.0, speed_effort_gradient=0.25
)

# (velocity, requested effort, clamped effort, what binds)
FOUR_QUADRANT_TABLE = [
    (0.0, 30.0, 10.0, "stall: max_effort"),
    (0.0, -30.0, -10.0, "stall, negative"),
    (2.0, 12.0, 8.0, "I drive: eq. 1"),
    (2.0, 5.0, 5.0, "I inside: unchanged"),
    (-2.0, 12.0, 8.0, "II brake: eq. 1, same curve as driving"),
    (-2.0, -12.0, -8.0, "III drive: eq. 1"),
    (2.0, -12.0, -8.0, "IV brake: eq. 1"),
    (10.0 / 3.0, 100.0, 20.0 / 3.0, "I corner: both curves"),
    (-10.0 / 3.0, 100.0, 20.0 / 3.0, "II corner"),
    (4.0, -100.0, -4.0, "IV brake: eq. 2 binds (20 - 4*4)"),
    (-4.0, -100.0, -4.0, "III drive: eq. 2"),
    (5.0, 3.0, 0.0, "no-load speed: nothing left"),
    (6.0, 3.0, 0.0, "beyond max_actuator_velocity: 0"),
    (-6.0, -3.0, 0.0, "beyond, negative"),
]


@pytest.mark.parametrize(("velocity", "request_", "expected", "case"), FOUR_QUADRANT_TABLE)
def test_clamp_effort_four_quadrants(velocity: float, request_: float, expected: float, case: str) -> None:
    """Clamp each quadrant's request to the hand-computed limit."""
    assert clamp_effort(ENV, request_, velocity) == pytest.approx(expected, abs=1e-12), case


def test_clamp_effort_vectorized_matches_table() -> None:
    """Clamp the whole table in one broadcast call."""
    v, req, expected, _ = map(np.array, zip(*FOUR_QUADRANT_TABLE, strict=True))
    np.testing.assert_allclose(clamp_effort(ENV, req, v), expected.astype(float), atol=1e-12)


def test_effort_limit_values() -> None:
    """Evaluate eq. 1 and eq. 2 combined at hand-picked speeds."""
    v = np.array([0.0, 2.0, 10.0 / 3.0, 4.0, 5.0, 6.0, -2.0])
    np.testing.assert_allclose(ENV.effort_limit(v), [10.0, 8.0, 20.0 / 3.0, 4.0, 0.0, 0.0, 8.0], atol=1e-12)


def test_velocity_limit_values() -> None:
    """Evaluate the velocity limit at hand-picked efforts."""
    tau = np.array([0.0, 8.0, 10.0, 12.0, -8.0])
    np.testing.assert_allclose(ENV.velocity_at_effort(tau), [5.0, 2.0, 0.0, 0.0, 2.0], atol=1e-12)


def test_corners() -> None:
    """Find the stall, corner and no-load points."""
    corners = ENV.corners()
    assert corners.stall == pytest.approx((0.0, 10.0))
    assert corners.corner == pytest.approx((10.0 / 3.0, 20.0 / 3.0))
    assert corners.no_load == pytest.approx((5.0, 0.0))


def test_boundary_polygon_all_quadrants() -> None:
    """List the polygon counter-clockwise with every corner of the four quadrants."""
    c = (10.0 / 3.0, 20.0 / 3.0)
    expected = [
        (5.0, 0.0),
        c,
        (0.0, 10.0),
        (-c[0], c[1]),
        (-5.0, 0.0),
        (-c[0], -c[1]),
        (0.0, -10.0),
        (c[0], -c[1]),
    ]
    np.testing.assert_allclose(ENV.boundary(), expected, atol=1e-12)


def test_boundary_points_are_on_the_envelope() -> None:
    """Keep every boundary vertex inside the region and on at least one limit."""
    polygon = ENV.boundary()
    assert ENV.contains(polygon[:, 0], polygon[:, 1], atol=1e-12).all()
    effort_margin, velocity_margin = ENV.margins(polygon[:, 0], polygon[:, 1])
    on_a_limit = (np.abs(effort_margin) < 1e-12) | (np.abs(velocity_margin) < 1e-12)
    assert on_a_limit.all()


def test_boundary_shoelace_area() -> None:
    """Compute the region's area: four quadrants of the hand-computed quadrilateral."""
    polygon = ENV.boundary()
    x, y = polygon[:, 0], polygon[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    # first quadrant: triangle (0,0),(5,0),c plus triangle (0,0),c,(0,10)
    quadrant = 0.5 * 5.0 * (20.0 / 3.0) + 0.5 * 10.0 * (10.0 / 3.0)
    assert area == pytest.approx(4 * quadrant)


def test_rectangle_when_no_slopes() -> None:
    """Make a rectangle when R = G = 0, with the corner where both caps meet."""
    env = PerformanceEnvelope(max_effort=3.0, max_actuator_velocity=2.0)
    assert env.corners().corner == (2.0, 3.0)
    np.testing.assert_allclose(
        env.boundary(), [(2, 0), (2, 3), (0, 3), (-2, 3), (-2, 0), (-2, -3), (0, -3), (2, -3)], atol=0
    )


def test_gradient_only_triangle() -> None:
    """Cut the stall effort at max_actuator_velocity / G when that is below max_effort."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=2.0, speed_effort_gradient=0.5)
    corners = env.corners()
    assert corners.stall == (0.0, 4.0)
    assert corners.corner is None
    assert env.effort_limit(1.0) == pytest.approx(2.0)


def test_resistance_with_vertical_speed_cap() -> None:
    """Put the corner on v = max_actuator_velocity when G = 0 and R > 0."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=4.0, velocity_dependent_resistance=1.0)
    assert env.corners().corner == pytest.approx((4.0, 6.0))
    assert env.effort_limit([3.9, 4.0, 4.1]) == pytest.approx([6.1, 6.0, 0.0])


def test_unbounded_needs_extent() -> None:
    """Refuse an unbounded polygon unless a velocity extent is given."""
    env = PerformanceEnvelope(max_effort=2.0)
    with pytest.raises(InputError, match="velocity_extent"):
        env.boundary()
    assert env.boundary(velocity_extent=3.0).max(axis=0) == pytest.approx([3.0, 2.0])


def test_unbounded_in_effort_has_no_polygon() -> None:
    """max_effort = inf without a speed-effort slope: refused (it returned the point [[3, 0]])."""
    env = PerformanceEnvelope(max_effort=math.inf, max_actuator_velocity=3.0)
    for call in (env.boundary, env.corners, env.quadrant_path):
        with pytest.raises(InputError, match="unbounded in effort"):
            call()
    sloped = PerformanceEnvelope(max_effort=math.inf, max_actuator_velocity=3.0, speed_effort_gradient=0.1)
    assert sloped.boundary().max(axis=0) == pytest.approx([3.0, 30.0])  # the speed line bounds it


def test_infinite_speed_with_resistance_is_bounded() -> None:
    """Bound the region by max_effort / R when max_actuator_velocity is inf."""
    env = PerformanceEnvelope(max_effort=6.0, velocity_dependent_resistance=2.0)
    assert env.no_load_velocity() == pytest.approx(3.0)
    assert env.corners().corner is None


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("max_effort", -1.0, "max_effort must be >= 0, got -1.0"),
        ("max_effort", math.nan, "max_effort must be >= 0"),
        ("velocity_dependent_resistance", math.inf, "velocity_dependent_resistance must be finite"),
        ("velocity_dependent_resistance", -0.1, "velocity_dependent_resistance must be >= 0"),
        ("speed_effort_gradient", math.inf, "speed_effort_gradient must be finite"),
        ("max_actuator_velocity", -2.0, "max_actuator_velocity must be >= 0"),
        ("max_actuator_velocity", math.nan, "max_actuator_velocity must be >= 0"),
    ],
)
def test_validation_names_field_and_value(field: str, value: float, message: str) -> None:
    """Reject invalid parameters with the field and the value in the message."""
    kwargs = {"max_effort": 1.0, field: value}
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        PerformanceEnvelope(**kwargs)


def test_rejects_bad_joint_and_positional_use() -> None:
    """Refuse an unknown joint type and positional construction."""
    with pytest.raises(ValueError, match="joint must be"):
        PerformanceEnvelope(max_effort=1.0, joint="ball")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        PerformanceEnvelope(1.0)  # type: ignore[misc]


def test_frozen() -> None:
    """Forbid mutation of an envelope."""
    with pytest.raises(AttributeError):
        ENV.max_effort = 3.0  # type: ignore[misc]


def test_dict_round_trip_and_units() -> None:
    """Round-trip through a dict and read strings with units."""
    assert PerformanceEnvelope.from_dict(ENV.to_dict()) == ENV
    env = PerformanceEnvelope.from_dict(
        {"max_effort": "1200 mNm", "max_actuator_velocity": "60 rpm", "speed_effort_gradient": "1 rpm/(N*m)"}
    )
    assert env.max_effort == pytest.approx(1.2)
    assert env.max_actuator_velocity == pytest.approx(2 * math.pi)
    assert env.speed_effort_gradient == pytest.approx(2 * math.pi / 60)


def test_from_dict_prismatic_units() -> None:
    """Read prismatic values in N and m/s."""
    env = PerformanceEnvelope.from_dict(
        {"joint": "prismatic", "max_effort": "0.2 kN", "max_actuator_velocity": "50 mm/s"}
    )
    assert (env.max_effort, env.max_actuator_velocity) == pytest.approx((200.0, 0.05))


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"max_efort": 1.0}, "unknown key 'max_efort' (did you mean 'max_effort'?)"),
        ({"max_actuator_velocity": 1.0}, "missing required key 'max_effort'"),
        ({"max_effort": "3 rpm"}, "key 'max_effort'"),
        ({"max_effort": 1.0, "max_actuator_velocity": "10 Hz"}, "angle unit"),
        ({"max_effort": 1.0, "max_actuator_velocity": "10 blorps"}, "unknown unit"),
        ({"max_effort": -1.0}, "max_effort must be >= 0"),
        ({"max_effort": 1.0, "joint": "ball"}, "key 'joint'"),
    ],
)
def test_from_dict_errors(data: dict[str, object], message: str) -> None:
    """Name the source, the key and the reason in every error."""
    with pytest.raises(InputError) as info:
        PerformanceEnvelope.from_dict(data, source="robot.toml")
    text = str(info.value)
    assert text.startswith("robot.toml: ")
    assert message in text
    assert "\n" not in text


def test_subnormal_slopes_give_no_nan_and_no_warning() -> None:
    """Treat a subnormal slope as no limit from its line: no NaN on the line's own end point."""
    import warnings

    env = PerformanceEnvelope(
        max_effort=2.0,
        max_actuator_velocity=3.0,
        velocity_dependent_resistance=5e-324,
        speed_effort_gradient=5e-324,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert env.effort_limit([0.0, 3.0, 4.0]).tolist() == [2.0, 0.0, 0.0]
        assert env.velocity_at_effort([0.0, 1.0, 3.0]).tolist() == [3.0, 3.0, 0.0]


# the sign of a let-go zero: +0.0 in every backend (a new user's API finding)

LET_GO_LINE = de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0, speed_effort_gradient=0.5)
LET_GO_BOX = de.PerformanceEnvelope(max_effort=12.0, max_actuator_velocity=10.0)  # R = G = 0: 0 past 10
SIGN_EFFORTS = (5.0, -5.0, 0.0, -0.0, 30.0, -30.0, math.inf, -math.inf, math.nan)
SIGN_VELOCITIES = (0.0, 3.0, -3.0, 20.0, -20.0, math.nan, math.inf, -math.inf)


def _sign_grid(repeat: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Every effort at every velocity, repeated so that SIMD lanes and scalar tails both see each."""
    effort, velocity = (a.ravel() for a in np.meshgrid(SIGN_EFFORTS, SIGN_VELOCITIES))
    return np.tile(effort, repeat), np.tile(velocity, repeat)


@pytest.mark.parametrize("envelope", [LET_GO_LINE, LET_GO_BOX], ids=["line", "box"])
def test_numpy_let_go_is_positive_zero(envelope: de.PerformanceEnvelope) -> None:
    for velocity in (math.nan, math.inf, -math.inf, 20.0):
        for effort in (5.0, -5.0, math.inf, -math.inf, math.nan):
            got = de.clamp_effort(envelope, effort, velocity)  # L = 0: NaN, infinite or beyond v_max
            assert got == 0.0 and not np.signbit(got), (effort, velocity, got)
    assert np.signbit(de.clamp_effort(envelope, -0.0, 1.0))  # inside the limit an effort is kept as is


@pytest.mark.parametrize("envelope", [LET_GO_LINE, LET_GO_BOX], ids=["line", "box"])
def test_backends_agree_on_every_zero_sign(envelope: de.PerformanceEnvelope) -> None:
    effort, velocity = _sign_grid()
    reference = de.clamp_effort(envelope, effort, velocity)
    let_go = envelope.effort_limit(velocity) == 0.0
    assert not np.signbit(reference[let_go]).any()
    torch = pytest.importorskip("torch")
    from drive_envelope.torch import EnvelopeTensors, clamp_effort

    params = EnvelopeTensors.from_envelopes(envelope, dtype=torch.float64)
    eager = clamp_effort(params, torch.tensor(effort), torch.tensor(velocity)).numpy()
    tracked_effort = torch.tensor(effort, requires_grad=True)
    tracked = clamp_effort(params, tracked_effort, torch.tensor(velocity)).detach().numpy()
    for got in (eager, tracked):
        np.testing.assert_array_equal(got, reference)
        np.testing.assert_array_equal(np.signbit(got), np.signbit(reference))
    pytest.importorskip("warp")
    import drive_envelope.warp as dw

    arrays = dw.EnvelopeArrays.from_envelopes(envelope, count=effort.size, device="cpu")
    warp = dw.clamp_effort(arrays, effort.astype(np.float32), velocity.astype(np.float32)).numpy()
    np.testing.assert_array_equal(warp, reference.astype(np.float32))
    np.testing.assert_array_equal(np.signbit(warp), np.signbit(reference))


def test_a_string_with_units_in_the_constructor_points_to_from_dict() -> None:
    """The constructor takes SI numbers; a string with units is named and sent to ``from_dict``."""
    with pytest.raises(InputError, match=r"^max_effort must be a number, got '12 N\*m'; a string with units: "
                       r"PerformanceEnvelope\.from_dict\(\{'max_effort': \.\.\.\}\)$"):  # fmt: skip
        PerformanceEnvelope(max_effort="12 N*m")  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"^max_effort must be a number, got None$"):
        PerformanceEnvelope(max_effort=None)  # type: ignore[arg-type]
    assert PerformanceEnvelope.from_dict({"max_effort": "12 N*m"}).max_effort == 12.0


@pytest.mark.parametrize(
    ("value", "shown"),
    [
        (None, "None"),
        ("3", "'3'"),
        (True, "True"),
        ([None, 1.0], "an array of object"),
        (["1"], "an array of <U1"),
    ],
)
def test_not_numbers_are_refused_naming_the_argument(value: object, shown: str) -> None:
    """NumPy reads None as NaN (a silent 0: the drive lets go) and "3" as 3.0: each is one line instead."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=5.0, velocity_dependent_resistance=0.1)
    calls = {
        "effort_limit: velocity": lambda: env.effort_limit(value),
        "clamp_effort: effort": lambda: clamp_effort(env, value, 1.0),
        "clamp_effort_implicit: velocity": lambda: de.clamp_effort_implicit(env, 1.0, value, 2.0, 0.01),
        "clamp_drive_impulse: max_impulse": lambda: de.clamp_drive_impulse(
            0.0, 0.0, 1.0, 2.0, 5.0, value, 0, 0
        ),
    }
    for where, call in calls.items():
        with pytest.raises(
            InputError, match=f"^{where}: expected numbers .*, got {shown}$".replace("(", r"\(")
        ):
            call()


def test_numbers_of_every_kind_pass() -> None:
    """Python and NumPy scalars of any width, lists and integer arrays are numbers."""
    env = PerformanceEnvelope(max_effort=10.0, max_actuator_velocity=5.0, velocity_dependent_resistance=0.1)
    for speed in (1, 1.0, np.float32(1.0), np.int64(1), [1.0], np.array([1], dtype=np.int32)):
        assert np.all(env.effort_limit(speed) == pytest.approx(9.9))

"""Every catalog actuator's derivation against a value computed by hand from its datasheet's text.

Each row below quotes the numbers its catalog file cites (the file's comments name the document,
table and page) and writes the arithmetic out in SI: revolutions per minute are 2*pi/60 rad/s, a
kilogram-force is 9.80665 N, an ounce-force inch is 0.028349523125 kg * 9.80665 m/s^2 * 0.0254 m,
a servo's "0.14 s/60°" is 60 degrees in 0.14 s. The test then derives the catalog file and compares.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import pytest

import drive_envelope.datasheet as public
from drive_envelope._src.datasheet.catalog import load_catalog_datasheet
from drive_envelope._src.datasheet.derive import derive

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm
KGF = 9.80665  # N per kgf
KGF_CM = KGF * 0.01  # N*m per kgf*cm
OZF_IN = 0.028349523125 * KGF * 0.0254  # N*m per ozf*in
SIXTY_DEG = math.pi / 3.0  # rad
MM = 1e-3  # m per mm


class Expected(NamedTuple):
    """The hand-computed envelope (SI, joint side) and the binding limits."""

    max_effort: float
    max_actuator_velocity: float
    speed_effort_gradient: float
    effort_by: str
    velocity_by: str
    velocity_dependent_resistance: float = 0.0


def servo(stall: float, no_load: float) -> Expected:
    """Stall effort and no-load speed, the two ends of the speed-torque line: gradient v0 / tau_stall."""
    return Expected(stall, no_load, no_load / stall, "output_stall", "output_no_load")


def rated_line(peak: float, no_load: float, rated_speed: float, rated: float) -> Expected:
    """Peak cap, no-load speed and the rated point on the line: gradient (v0 - vN) / tau_N."""
    return Expected(peak, no_load, (no_load - rated_speed) / rated, "output_rating", "output_no_load")


def caps(effort: float, velocity: float) -> Expected:
    """Joint limits only (a rectangle): gradient 0."""
    return Expected(effort, velocity, 0.0, "output_rating", "output_rating")


EXPECTED: dict[str, Expected] = {
    # ROBOTIS e-Manual, _data/dxl_x_info.yml: stalltorque / noloadspeed at the recommended voltage
    "dynamixel-xl330-m077": servo(
        0.215, 383 * RPM
    ),  # "0.215 [N.m] (at 5.0 [V]...)", "383 [rev/min] (at 5.0 [V])"
    "dynamixel-xl330-m288": servo(0.52, 103 * RPM),  # "0.52 [N.m] (at 5.0 [V], 1.47 [A])", "103 [rev/min]"
    "dynamixel-xc330-m288": servo(0.93, 81 * RPM),  # "0.93 [N.m] (at 5.0 [V], 1.80 [A])", "81 [rev/min]"
    "dynamixel-xl430-w250": servo(1.4, 57 * RPM),  # "1.4 [N.m] (at 11.1 [V], 1.3 [A])", "57 [rev/min]"
    "dynamixel-xc430-w240": servo(1.9, 70 * RPM),  # "1.9 [N.m] (at 12.0 [V], 1.4 [A])", "70 [rev/min]"
    "dynamixel-xm430-w210": servo(3.0, 77 * RPM),  # "3.0 [N.m] (at 12.0 [V], 2.3 [A])", "77 [rev/min]"
    "dynamixel-xm430-w350": servo(4.1, 46 * RPM),  # "4.1 [N.m] (at 12.0 [V], 2.3 [A])", "46 [rev/min]"
    "dynamixel-xh430-w350": servo(3.4, 30 * RPM),  # "3.4 [N.m] (at 12.0 [V], 1.3 [A])", "30 [rev/min]"
    "dynamixel-xh540-w150": servo(7.1, 70 * RPM),  # "7.1 [N.m] (at 12.0 [V], 4.9 [A])", "70 [rev/min]"
    "dynamixel-xh540-w270": servo(9.9, 39 * RPM),  # "9.9 [N.m] (at 12.0 [V], 4.9 [A])", "39 [rev/min]"
    "dynamixel-xw540-t260": servo(9.5, 40 * RPM),  # "9.5 [N.m] (at 12.0 [V], 4.9 [A])", "40 [rev/min]"
    "dynamixel-xm540-w150": servo(7.3, 53 * RPM),  # "7.3 [N.m] (at 12.0 [V], 4.4 [A])", "53 [rev/min]"
    "dynamixel-xm540-w270": servo(10.6, 30 * RPM),  # "10.6 [N.m] (at 12.0 [V], 4.4 [A])", "30 [rev/min]"
    # ROBOTIS e-Manual, _data/dxl_p_info.yml: noloadspeed, contspeed, conttorque
    # (no peak torque printed: the continuous one caps the peak)
    "dynamixel-ph54-200-s500-r": Expected(
        44.7, 33.1 * RPM, (33.1 - 29.0) * RPM / 44.7, "output_rating", "output_no_load"
    ),  # "33.1 [rev/min]", "29.0 [rev/min]", "44.7 [N.m]"
    "dynamixel-ph42-020-s300-r": Expected(
        5.1, 32.7 * RPM, (32.7 - 29.2) * RPM / 5.1, "output_rating", "output_no_load"
    ),  # "32.7 [rev/min]", "29.2 [rev/min]", "5.1 [N.m]"
    # RobStride user manuals, 1.3: "Peak load", "No load speed" (no line slope printed: gradient 0)
    "robstride-rs00": Expected(14, 315 * RPM, 0.0, "output_rating", "output_no_load"),  # "Peak load: 14 N.m"
    "robstride-rs01": Expected(
        17, 315 * RPM, 0.0, "output_rating", "output_no_load"
    ),  # "No load speed: 315 rpm"
    "robstride-rs02": Expected(
        17, 410 * RPM, 0.0, "output_rating", "output_no_load"
    ),  # "No load speed: 410 rpm"
    "robstride-rs03": Expected(60, 200 * RPM, 0.0, "output_rating", "output_no_load"),  # "Peak load: 60 N.m"
    "robstride-rs04": Expected(
        120, 200 * RPM, 0.0, "output_rating", "output_no_load"
    ),  # "Peak load: 120 N.m"
    "robstride-rs05": Expected(
        5.5, 480 * RPM, 0.0, "output_rating", "output_no_load"
    ),  # "Peak load: 5.5 N.m"
    "robstride-rs06": Expected(36, 480 * RPM, 0.0, "output_rating", "output_no_load"),  # "Peak load: 36 N.m"
    "robstride-el05": Expected(6, 430 * RPM, 0.0, "output_rating", "output_no_load"),  # "Peak load: 6 N.m"
    # Unitree unitree_ros descriptions: <limit effort=... velocity=...>
    "unitree-go-m8010-6": caps(23.7, 30.1),  # go2 FL_hip_joint effort="23.7" velocity="30.1"
    "unitree-go2-calf": caps(45.43, 15.70),  # go2 FL_calf_joint effort="45.43" velocity="15.70" (79f054ec on)
    "unitree-go1-joint": caps(23.7, 30.1),  # go1 hip_torque_max 23.7, hip_velocity_max 30.1
    "unitree-a1-motor": caps(33.5, 21.0),  # a1 hip_torque_max 33.5, hip_velocity_max 21
    "unitree-g1-7520-14": caps(88, 32),  # g1_29dof left_hip_pitch_joint effort="88" velocity="32"
    "unitree-g1-7520-22": caps(139, 20),  # left_knee_joint effort="139" velocity="20"
    "unitree-g1-5020": caps(25, 37),  # left_shoulder_pitch_joint effort="25" velocity="37"
    "unitree-g1-4010": caps(5, 22),  # left_wrist_pitch_joint effort="5" velocity="22"
    "unitree-g1-ankle": caps(35, 30),  # left_ankle_pitch_joint effort="35" velocity="30"
    "unitree-h1-hip": caps(200, 23),  # h1 left_hip_pitch_joint effort="200" velocity="23"
    "unitree-h1-knee": caps(300, 14),  # left_knee_joint effort="300" velocity="14"
    "unitree-h1-ankle": caps(40, 9),  # left_ankle_joint effort="40" velocity="9"
    "unitree-h1-arm": caps(18, 20),  # left_elbow_joint effort="18" velocity="20"
    # Kinova ros_kortex gen3_macro.xacro (7dof): <limit effort=... velocity=...>
    "kinova-gen3-large": caps(39, 1.3963),  # joint_1..4 effort="39" velocity="1.3963"
    "kinova-gen3-small": caps(9, 1.2218),  # joint_5..7 effort="9" velocity="1.2218"
    # Isaac Lab anymal.py ANYDRIVE_3 DCMotorCfg: cap effort_limit=80.0 on the line from
    # saturation_effort=120.0 at rest to velocity_limit=7.5 at zero effort: gradient 7.5 / 120
    "anybotics-anydrive-3": Expected(80, 7.5, 7.5 / 120, "output_rating", "output_no_load"),
    # FEETECH model pages: "Peak stall torque", "No load speed" (time per 60 degrees)
    "feetech-sts3215-c001": servo(19.5 * KGF_CM, SIXTY_DEG / 0.238),  # "19.5kg.cm@6V", "0.238sec/60°@6V"
    "feetech-st3215-c018": servo(30 * KGF_CM, SIXTY_DEG / 0.222),  # "30kg.cm@12V", "0.222sec/60°@12V"
    "feetech-sts3250": servo(50 * KGF_CM, SIXTY_DEG / 0.133),  # "50kg.cm@12V", "0.133sec/60°@12V"
    # Franka FCI "Joint space limits": tau_j,max and qdot_max
    "franka-panda-joint1-4": caps(87, 2.1750),  # "87, 87, 87, 87, 12, 12, 12"; "2.1750 ... 2.6100"
    "franka-panda-joint5-7": caps(12, 2.6100),
    "franka-fr3-joint1-4": caps(87, 2.62),  # FR3: "2.62, 2.62, 2.62, 2.62, 5.26, 4.18, 5.26"
    "franka-fr3-joint5-7": caps(12, 5.26),
    "franka-fr3-joint6": caps(12, 4.18),
    # MyActuator (Seeed table): Peak Torque, No Load Speed, Rated Speed, Rated Torque
    "myactuator-rmd-x8-120": rated_line(120, 158 * RPM, 127 * RPM, 43),  # X8-120: 120, 158, 127, 43
    "myactuator-rmd-x12-320": rated_line(320, 125 * RPM, 100 * RPM, 85),  # X12-320: 320, 125, 100, 85
    # CubeMars product pages (48 V): Peak Torque, No-Load Speed, Rated Speed, Rated Torque
    "cubemars-ak70-10": rated_line(24.8, 480 * RPM, 310 * RPM, 8.3),
    "cubemars-ak80-9-v3": rated_line(22, 570 * RPM, 390 * RPM, 9),
    "cubemars-ak60-6-v3": rated_line(9, 640 * RPM, 490 * RPM, 3),
    # Damiao (Seeed table, 24 V): Peak Torque, No-load Speed (the rated speed is not a line point: gradient 0)
    "damiao-dm-j4310-2ec": Expected(7, 200 * RPM, 0.0, "output_rating", "output_no_load"),
    "damiao-dm-j4340-2ec": Expected(27, 52.5 * RPM, 0.0, "output_rating", "output_no_load"),
    # Actuonix: Max Force (lifted), Max Speed (no load), gradient through the peak power point
    "actuonix-l16-35-6-r": Expected(50, 32 * MM, (32 - 16) * MM / 50, "output_rating", "output_rating"),
    "actuonix-l16-63-6-r": Expected(100, 20 * MM, (20 - 10) * MM / 75, "output_rating", "output_rating"),
    "actuonix-l16-150-6-r": Expected(200, 8 * MM, (8 - 4) * MM / 175, "output_rating", "output_rating"),
    "actuonix-l12-50-210-12-s": Expected(
        80, 6.5 * MM, (6.5 - 3.2) * MM / 62, "output_rating", "output_rating"
    ),
    # Pololu 4845: "stall extrapolation 15 kg*cm", "no-load performance 220 RPM"
    "pololu-25d-47-hp-12v": servo(15 * KGF_CM, 220 * RPM),
    # MG996R: "11 kgf*cm (6 V)", "0.14 s/60° (6 V)"
    "towerpro-mg996r": servo(11 * KGF_CM, SIXTY_DEG / 0.14),
    # T-Motor AK80-6 (DFKI): output 12 N*m caps; voltage 100 rpm/V * 24 V * 0.9 / 6 = 360 rpm < 38.2 rad/s;
    # gradient R / k_t^2 / i_G^2 = 0.170 / 0.091^2 / 36
    "tmotor-ak80-6": Expected(
        12.0, 100 * RPM * 24 * 0.9 / 6, 0.170 / 0.091**2 / 36, "output_rating", "voltage"
    ),
    # Harmonic Drive FHA-8C-50 (output shaft values): effort min(I 3.3 A * k_t 1.3, tau_max 3.3) = 3.3 N*m;
    # speed min(k_v 1/0.16 rpm/V * 24 V * 0.9 = 135 rpm, n_max 116 r/min) = 116 r/min (mechanical: gradient 0)
    "harmonic-drive-fha-8c-50": Expected(3.3, 116 * RPM, 0.0, "motor_torque", "motor_speed"),
    # Magmotor S28-F2-300: stall 1166 oz-in; voltage 1000/11.5 rpm/V * 24 V * 0.9;
    # R / k_t^2 = 0.32 / (15.6 oz-in/A)^2
    "magmotor-s28-f2-300": Expected(
        1166 * OZF_IN, 1000 * RPM / 11.5 * 24 * 0.9, 0.32 / (15.6 * OZF_IN) ** 2, "motor_torque", "voltage"
    ),
    # Magmotor C21-H-175 FX: stall 145 oz-in; voltage 1000/13.70 rpm/V * 36 V * 0.9;
    # R / k_t^2 = 4.60 / (18.5 oz-in/A)^2;
    # its calculation table falls to 0 oz-in at 2628 RPM: the speed-torque line, so no k_tau_v
    "magmotor-c21-h-175": Expected(
        145 * OZF_IN, 1000 * RPM / 13.70 * 36 * 0.9, 4.60 / (18.5 * OZF_IN) ** 2, "motor_torque", "voltage"
    ),
}

CATALOG = Path(public.__file__).parent / "catalog"
KEYS = sorted(p.stem for p in CATALOG.glob("*.toml"))


def test_every_catalog_file_has_a_hand_computed_row() -> None:
    """Check the table above covers exactly the shipped catalog (a new file needs its row)."""
    assert sorted(EXPECTED) == KEYS


@pytest.mark.parametrize("key", sorted(EXPECTED))
def test_derivation_matches_the_hand_computation(key: str) -> None:
    """Derive the catalog file (peak duty) and compare with the arithmetic of its printed numbers."""
    expected = EXPECTED[key]
    d = derive(load_catalog_datasheet(key))
    env = d.envelope
    assert env.max_effort == pytest.approx(expected.max_effort, rel=1e-9)
    assert env.max_actuator_velocity == pytest.approx(expected.max_actuator_velocity, rel=1e-9)
    assert env.speed_effort_gradient == pytest.approx(expected.speed_effort_gradient, rel=1e-9, abs=0.0)
    assert env.velocity_dependent_resistance == pytest.approx(expected.velocity_dependent_resistance)
    assert d.max_effort_limited_by == expected.effort_by
    assert d.max_actuator_velocity_limited_by == expected.velocity_by


@pytest.mark.parametrize(
    ("key", "continuous"),
    [
        ("robstride-rs01", 6.0),  # RS01 1.3: "Rated load: 6 N.m(Tested at 100 rpm)"
        ("robstride-rs04", 40.0),  # RS04 1.3: "Rated load: 40 N.m"
        ("feetech-sts3215-c001", 6.5 * KGF_CM),  # "Rated torque | 6.5kg.cm@6V"
        ("cubemars-ak70-10", 8.3),  # "Rated Torque (N·m): 8.3"
        ("damiao-dm-j4310-2ec", 3.0),  # "Rated Torque (Nm) | 3"
        ("dynamixel-ph54-200-s500-r", 44.7),  # conttorque: "44.7 [N.m]"
        ("harmonic-drive-fha-8c-50", 1.5),  # "Allowable continuous torque N*m 0.75 | 1.5 | 2"
    ],
)
def test_continuous_duty_uses_the_rated_effort(key: str, continuous: float) -> None:
    """Cap effort at the continuous (rated, nominal) rating for --duty continuous."""
    d = derive(load_catalog_datasheet(key), duty="continuous")
    assert d.envelope.max_effort == pytest.approx(continuous, rel=1e-12)


def test_the_stored_torque_speed_table_gives_no_resistance() -> None:
    """Store Magmotor C21's calculation table: it is the speed-torque line, so k_tau_v = 0 with the reason."""
    d = derive(load_catalog_datasheet("magmotor-c21-h-175"))
    assert d.datasheet.losses is not None
    points = d.datasheet.losses.operating_points
    assert points is not None and len(points) == 4
    # the table's rows "36 0 2628 | 36 26 2157 | 36 40 1903 | 36 145 0" (volts, oz-in, RPM)
    assert points[0] == pytest.approx((2628 * RPM, 0.0))
    assert points[1] == pytest.approx((2157 * RPM, 26 * OZF_IN))
    assert d.velocity_dependent_resistance_method == "speed_torque_line"
    assert any("speed-torque line of eq. 2" in note for note in d.notes)
    # the table is one straight line: its slope is the motor's own gradient at 100 % voltage, within 0.5 %
    slope = (2628 - 0) * RPM / (145 * OZF_IN)
    assert slope == pytest.approx(d.envelope.speed_effort_gradient, rel=0.005)

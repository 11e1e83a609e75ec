"""ROS 2 bags as logs: bags written here with rosbags (MCAP and sqlite3) read back to the CSV numbers.

The bags are real rosbag2 folders written by the library users record with (``rosbags``): from
BAM's XL330 logs (states as ``sensor_msgs/JointState``, targets as JointState, JointTrajectory or
Float64MultiArray, a NaN target where the servo was unpowered) and from ``simulate``'s output. The
check, fit, identify and replay of a bag must give the numbers of the CSV it was written from.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from drive_envelope._src.analysis.api import check_log, fit_log
from drive_envelope._src.analysis.log_bag import BagOptions, read_bag
from drive_envelope._src.analysis.logs import LogColumns
from drive_envelope._src.envelope.model import PerformanceEnvelope
from drive_envelope._src.errors import InputError
from drive_envelope._src.identify.logs import read_bench_log

pytest.importorskip("rosbags")

REPO = Path(__file__).resolve().parents[1]
BAM = REPO.parent / "shared" / "data" / "bam" / "logs"
STAND = REPO / "examples" / "bam" / "xl330_pendulum.toml"
EPOCH_NS = 1_768_470_490_123_456_789  # a 2026 wall-clock stamp: times must come out relative, exact
CLI = [sys.executable, "-m", "drive_envelope"]


def _typestore():  # type: ignore[no-untyped-def]
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def _stamp(store, ns: int):  # type: ignore[no-untyped-def]
    Time = store.types["builtin_interfaces/msg/Time"]
    Header = store.types["std_msgs/msg/Header"]
    return Header(stamp=Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id="")


def write_bag(
    folder: Path,
    joints: dict[str, dict[str, np.ndarray]],
    *,
    storage: str = "mcap",
    command: str | None = None,
    state_topic: str = "/joint_states",
) -> Path:
    """A rosbag2 folder: one JointState per sample (every joint), commands on ``/command``.

    ``joints[name]`` holds ``time`` [s] and any of position, velocity, effort, target_position
    (NaN: drive off); ``command`` is ``"state"``, ``"trajectory"`` or ``"array"``.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = _typestore()
    JointState = store.types["sensor_msgs/msg/JointState"]
    names = list(joints)
    first = joints[names[0]]
    rows = len(first["time"])
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(folder, version=8, storage_plugin=plugin) as writer:
        states = writer.add_connection(state_topic, JointState.__msgtype__, typestore=store)
        kinds = {
            "state": "sensor_msgs/msg/JointState",
            "trajectory": "trajectory_msgs/msg/JointTrajectory",
            "array": "std_msgs/msg/Float64MultiArray",
        }
        commands = (
            None if command is None else writer.add_connection("/command", kinds[command], typestore=store)
        )
        for i in range(rows):
            ns = EPOCH_NS + round(float(first["time"][i]) * 1e9)

            def values(key: str, i: int = i) -> np.ndarray:
                if key not in first:
                    return np.zeros(0)
                return np.array([joints[name][key][i] for name in names], dtype=np.float64)

            header = _stamp(store, ns)
            message = JointState(
                header=header, name=names, position=values("position"), velocity=values("velocity"),
                effort=values("effort"),
            )  # fmt: skip
            writer.write(states, ns, store.serialize_cdr(message, JointState.__msgtype__))
            if commands is None:
                continue
            targets = values("target_position")
            if command == "state":
                out = JointState(
                    header=header, name=names, position=targets, velocity=np.zeros(0), effort=np.zeros(0)
                )
            elif command == "trajectory":
                Point = store.types["trajectory_msgs/msg/JointTrajectoryPoint"]
                Duration = store.types["builtin_interfaces/msg/Duration"]
                point = Point(positions=targets, velocities=np.zeros(0), accelerations=np.zeros(0),
                              effort=np.zeros(0), time_from_start=Duration(sec=0, nanosec=0))  # fmt: skip
                Trajectory = store.types["trajectory_msgs/msg/JointTrajectory"]
                out = Trajectory(header=header, joint_names=names, points=[point])
            else:
                Array = store.types["std_msgs/msg/Float64MultiArray"]
                Layout = store.types["std_msgs/msg/MultiArrayLayout"]
                out = Array(layout=Layout(dim=[], data_offset=0), data=targets)
            writer.write(commands, ns, store.serialize_cdr(out, commands.msgtype))
    return folder


def _bam_logs() -> list[Path]:
    if not BAM.is_dir():
        pytest.skip(f"{BAM} is absent (the shared BAM logs)")
    return sorted(BAM.glob("*.csv"))


def _bam_bag(tmp_path: Path, csv: Path, *, storage: str = "mcap", command: str = "state") -> Path:
    """A bag of one BAM log (its sidecar copied beside it, as a user keeps it with the recording)."""
    log = read_bench_log(csv)
    target = np.where(log.enabled, log.target_position, np.nan)  # unpowered: no command
    columns = {"time": log.time, "position": log.position, "target_position": target}
    if log.velocity is not None:
        columns["velocity"] = log.velocity
    folder = write_bag(tmp_path / csv.stem, {"xl330": columns}, storage=storage, command=command)
    shutil.copy(csv.with_suffix(".json"), folder.with_suffix(".json"))
    return folder


@pytest.mark.parametrize(
    ("storage", "command"), [("mcap", "state"), ("sqlite3", "trajectory"), ("mcap", "array")]
)
def test_a_bam_log_as_a_bag_reads_as_its_csv(tmp_path: Path, storage: str, command: str) -> None:
    """Positions, velocities, targets, torque_enable and the duty gain of the bag equal the CSV's."""
    csv = next(path for path in _bam_logs() if "10h28m49" in path.name)  # lift_and_drop: unpowered span
    bag = _bam_bag(tmp_path, csv, storage=storage, command=command)
    ours = read_bench_log(bag, bag=BagOptions(command_topic="/command"))
    theirs = read_bench_log(csv)
    assert ours.rows == theirs.rows == 1200
    np.testing.assert_allclose(ours.time, theirs.time, rtol=0, atol=1e-9)  # ns stamps, from the first
    assert ours.dt == pytest.approx(theirs.dt, rel=1e-9)
    np.testing.assert_array_equal(ours.position, theirs.position)
    assert ours.velocity is not None and theirs.velocity is not None
    np.testing.assert_array_equal(ours.velocity, theirs.velocity)
    np.testing.assert_array_equal(ours.enabled, theirs.enabled)
    assert 0 < int((~ours.enabled).sum()) < ours.rows  # the free fall is there
    np.testing.assert_array_equal(ours.target_position[ours.enabled], theirs.target_position[theirs.enabled])
    assert ours.duty_per_rad == theirs.duty_per_rad == pytest.approx(0.5754755004452713)


def test_a_bags_storage_file_reads_the_bag_folders_sidecar(tmp_path: Path) -> None:
    """The .mcap inside a bag is the same log as its folder: the same sidecar gain (kp 800 log), not none.

    A new user's replay of ``bags/one/one.mcap`` ran on the stand's own gain, 130 mrad against the
    folder's 29 mrad, silently. Two sidecars for one log are refused rather than one picked.
    """
    csv = next(path for path in _bam_logs() if "10h28m49" in path.name)
    bag = _bam_bag(tmp_path, csv)
    (storage,) = bag.glob("*.mcap")
    options = BagOptions(command_topic="/command")
    by_folder = read_bench_log(bag, bag=options).duty_per_rad
    assert read_bench_log(storage, bag=options).duty_per_rad == by_folder == pytest.approx(0.5754755004452713)
    shutil.copy(bag.with_suffix(".json"), storage.with_suffix(".json"))
    with pytest.raises(InputError, match=r"two sidecars \(.*10h28m49\.json, .*10h28m49\.json\): keep one"):
        read_bench_log(storage, bag=options)


def test_a_sidecar_named_after_the_whole_log_file_is_read(tmp_path: Path) -> None:
    """``run.csv.json`` and ``run.csv.gz.json`` are the log's sidecar as ``run.json`` is."""
    csv = next(path for path in _bam_logs() if "10h28m49" in path.name)
    for name in ("run.csv", "run.csv.gz"):
        folder = tmp_path / name.replace(".", "_")
        folder.mkdir()
        log = folder / name
        data = csv.read_bytes()
        if name.endswith(".gz"):
            import gzip

            data = gzip.compress(data)
        log.write_bytes(data)
        shutil.copy(csv.with_suffix(".json"), folder / f"{name}.json")
        assert read_bench_log(log).duty_per_rad == pytest.approx(0.5754755004452713)


def test_identify_and_replay_of_bags_give_the_csv_numbers(tmp_path: Path) -> None:
    """identify on bags written from BAM logs gives the CSVs' parameters and errors; replay too."""
    pytest.importorskip("scipy")
    from drive_envelope._src.identify.optimize import SearchOptions
    from drive_envelope._src.identify.playback import replay_logs
    from drive_envelope._src.identify.run import identify

    csvs = [path for path in _bam_logs() if any(key in path.name for key in ("10h28m17", "10h28m49"))]
    bags = [
        _bam_bag(tmp_path, csv, storage=storage)
        for csv, storage in zip(csvs, ("mcap", "sqlite3"), strict=True)
    ]
    options = SearchOptions(generations=3, population=4, restarts=1, polish_evaluations=2)
    fit = ["max_effort", "damping", "static_friction"]
    topics = BagOptions(command_topic="/command")
    ours = identify(bags[:1], STAND, validate=bags[1:], fit=fit, options=options, bag=topics)
    theirs = identify(csvs[:1], STAND, validate=csvs[1:], fit=fit, options=options)
    for name, estimate in theirs.parameters.items():
        assert ours.parameters[name].value == pytest.approx(estimate.value, rel=1e-9, nan_ok=True), name
    assert ours.validation[0].mae_position == pytest.approx(theirs.validation[0].mae_position, rel=1e-9)
    assert ours.train[0].mae_position == pytest.approx(theirs.train[0].mae_position, rel=1e-9)
    out = tmp_path / "stand.toml"
    from drive_envelope._src.identify.stand_file import save_stand

    assert ours.stand is not None
    save_stand(ours.stand, out)
    played = replay_logs(bags[1:], out, bag=topics)
    assert played.errors[bags[1].name][0] == pytest.approx(ours.validation[0].mae_position, abs=1e-12)


def _simulated(tmp_path: Path) -> Path:
    out = tmp_path / "sim.csv"
    scenario = REPO / "examples" / "scenarios" / "velocity_saturation_pgs.toml"
    run = subprocess.run([*CLI, "simulate", str(scenario), "-o", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return out


def _columns(csv: Path) -> dict[str, np.ndarray]:
    data = np.genfromtxt(csv, delimiter=",", names=True)
    return {name: np.asarray(data[name], dtype=np.float64) for name in data.dtype.names or ()}


def test_check_and_fit_of_a_bag_from_simulate_give_the_csv_numbers(tmp_path: Path) -> None:
    """A bag of simulate's run (two joints in each message) checks and fits as its CSV does."""
    csv = _simulated(tmp_path)
    columns = _columns(csv)
    doubled = {name: np.asarray(values) for name, values in columns.items()}
    bag = write_bag(tmp_path / "run", {"shoulder": columns, "elbow": doubled}, storage="sqlite3")
    envelope = PerformanceEnvelope(
        max_effort=10.0,
        max_actuator_velocity=3.0,
        velocity_dependent_resistance=0.5,
        speed_effort_gradient=0.1,
    )
    tight = PerformanceEnvelope(max_effort=8.0, max_actuator_velocity=2.5)  # so there are violations
    for spec in (envelope, tight):
        ours = check_log(spec, bag).to_dict()
        theirs = check_log(spec, csv).to_dict()
        assert sorted(joint["joint"] for joint in ours["joints"]) == ["elbow", "shoulder"]
        for joint in ours["joints"]:
            expected = dict(theirs["joints"][0], joint=joint["joint"])
            # the long table holds the shoulder's rows first: the elbow's rows are counted after them
            _same(joint, expected, ignore=("row",) if joint["joint"] == "elbow" else ())
    fitted = fit_log(bag, select="elbow")
    reference = fit_log(csv)
    assert fitted.envelope.max_effort == pytest.approx(reference.envelope.max_effort, rel=1e-12)
    assert fitted.envelope.max_actuator_velocity == pytest.approx(
        reference.envelope.max_actuator_velocity, rel=1e-12
    )


def _same(ours: dict[str, object], theirs: dict[str, object], ignore: tuple[str, ...] = ()) -> None:
    """Equal reports, times compared to the bag's nanosecond stamps (to 1e-9 s)."""
    assert set(ours) == set(theirs)
    for key, value in theirs.items():
        other = ours[key]
        if key in ignore:
            continue
        if isinstance(value, float):
            assert other == pytest.approx(value, rel=1e-9, abs=1e-9), key
        elif isinstance(value, dict):
            _same(other, value, ignore)  # type: ignore[arg-type]
        else:
            assert other == value, key


def test_cli_check_reads_a_bag_and_names_its_topics(tmp_path: Path) -> None:
    """check BAG prints the CSV's verdict; a bag with two JointState topics asks for --topic."""
    csv = _simulated(tmp_path)
    bag = write_bag(tmp_path / "run", {"j1": _columns(csv)}, storage="mcap")
    envelope = tmp_path / "env.toml"
    envelope.write_text(
        "joint = 'revolute'\nmax_effort = 8.0\nmax_actuator_velocity = 2.5\n", encoding="utf-8"
    )
    runs = [subprocess.run([*CLI, "check", str(envelope), str(log), "--json"], capture_output=True,
                           text=True) for log in (bag, csv)]  # fmt: skip
    assert runs[0].returncode == runs[1].returncode == 1, runs[0].stderr  # violations in both
    ours, theirs = (json.loads(run.stdout) for run in runs)
    assert ours["joints"][0]["samples"] == theirs["joints"][0]["samples"] == 121
    assert ours["joints"][0]["samples_outside"] == theirs["joints"][0]["samples_outside"] == 14
    wrong = subprocess.run([*CLI, "check", str(envelope), str(bag), "--topic", "/other"],
                           capture_output=True, text=True)  # fmt: skip
    assert wrong.returncode == 2
    assert (
        "--topic '/other': no such topic; the bag has /joint_states (sensor_msgs/msg/JointState)"
        in wrong.stderr
    )


def test_bag_mistakes_are_one_line(tmp_path: Path) -> None:
    """Missing command topic, unknown joint, a storage file without metadata: one InputError each."""
    t = np.arange(5) * 0.01
    joints = {name: {"time": t, "position": t, "target_position": t} for name in ("a", "b")}
    bag = write_bag(tmp_path / "bag", joints, command="state")
    with pytest.raises(InputError, match="a ROS 2 bag needs --command-topic"):
        read_bench_log(bag)
    with pytest.raises(InputError, match="the bag has joints a, b; name one with --joint"):
        read_bench_log(bag, bag=BagOptions(command_topic="/command"))
    with pytest.raises(InputError, match=r"--joint 'c': not in the bag's joints \(a, b\)"):
        read_bench_log(bag, bag=BagOptions(command_topic="/command"), joint="c")
    with pytest.raises(InputError, match=r"2 sensor_msgs/msg/JointState topics \(/command, /joint_states\)"):
        read_bag(bag)  # the command topic is a JointState too: which one is measured?
    other = write_bag(tmp_path / "trajectory", joints, command="trajectory")
    with pytest.raises(InputError, match=r"--topic '/command' is trajectory_msgs/msg/JointTrajectory"):
        read_bag(other, BagOptions(topic="/command"))
    log = read_bench_log(bag, bag=BagOptions(command_topic="/command"), joint="b")
    np.testing.assert_allclose(log.time, t, atol=1e-12)
    np.testing.assert_array_equal(log.target_position, t)
    loose = tmp_path / "loose.mcap"
    shutil.copy(next(bag.glob("*.mcap")), loose)
    with pytest.raises(InputError, match=r"needs the bag's metadata\.yaml beside it"):
        read_bag(loose)
    with pytest.raises(InputError, match="no column 'velocity'"):  # the states carry position only
        columns = LogColumns(bag=BagOptions(topic="/joint_states"))
        check_log(PerformanceEnvelope(max_effort=1.0), bag, columns=columns)

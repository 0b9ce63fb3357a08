"""Joint logs from ROS bags, written here with the rosbags package's own writers (ROS 2 SQLite3
and MCAP, ROS 1) and compared with the same log read from CSV; identification from a bag equals
identification from the CSV."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from mindyn import cli
from mindyn.identification.data import DataError, DataFileNotFoundError, read_csv, write_csv
from mindyn.identification.rosbag import is_rosbag, read_rosbag

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

TS = get_typestore(Stores.ROS2_HUMBLE)
JS, HEADER, TIME = (
    TS.types[k]
    for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header", "builtin_interfaces/msg/Time")
)


def joint_state(t, names, q, dq=None, tau=None):
    sec = int(np.floor(t))
    empty = np.zeros(0)
    return JS(
        header=HEADER(stamp=TIME(sec=sec, nanosec=int(round((t - sec) * 1e9))), frame_id=""),
        name=list(names),
        position=np.asarray(q, dtype=float),
        velocity=empty if dq is None else np.asarray(dq, dtype=float),
        effort=empty if tau is None else np.asarray(tau, dtype=float),
    )


def write_bag(path, messages, topic="/joint_states", storage="sqlite3", extra_topics=()):
    """ROS 2 bag with the JointState `messages`; `extra_topics` get the same messages."""
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns = [
            w.add_connection(tp, JS.__msgtype__, typestore=TS) for tp in (topic, *extra_topics)
        ]
        for i, msg in enumerate(messages):
            for c in conns:
                w.write(c, 1000 + i, TS.serialize_cdr(msg, JS.__msgtype__))
    return path


def robot_log(robot, m=1500, rate=250.0, seed=0):
    """Torques of the robot's own parameters along sums of sines (rad, rad/s, rad/s^2)."""
    rng = np.random.default_rng(seed)
    n = robot.n
    t = 12.5 + np.arange(m) / rate  # a clock that does not start at 0
    w = rng.uniform(0.5, 2.0, (3, n))
    a = rng.uniform(0.2, 0.6, (3, n))
    ph = rng.uniform(0, 2 * np.pi, (3, n))
    arg = t[:, None, None] * w + ph
    q = np.sum(a * np.sin(arg), axis=1)
    dq = np.sum(a * w * np.cos(arg), axis=1)
    ddq = -np.sum(a * w**2 * np.sin(arg), axis=1)
    tau = robot.inverse_dynamics(q, dq, ddq)
    return t, q, dq, tau


@pytest.fixture(scope="module")
def planar():
    robot = mindyn.load("planar3")
    return robot, robot_log(robot)


def messages(robot, log, shuffle=True, velocity=True, effort=True):
    """The robot's joints in a shuffled order plus a joint it does not have."""
    t, q, dq, tau = log
    names = list(robot.joint_names) + ["gripper"]
    order = np.random.default_rng(1).permutation(len(names)) if shuffle else np.arange(len(names))
    out = []
    for i in range(t.size):

        def row(x, i=i):
            return np.append(x[i], 0.5)[order]

        out.append(
            joint_state(
                t[i],
                [names[k] for k in order],
                row(q),
                row(dq) if velocity else None,
                row(tau) if effort else None,
            )
        )
    return out


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_bag_equals_the_csv_log(planar, tmp_path, storage):
    robot, log = planar
    t, q, dq, tau = log
    bag = write_bag(tmp_path / "run", messages(robot, log), storage=storage)
    assert is_rosbag(bag) and not is_rosbag(tmp_path / "run.csv")
    d = read_rosbag(bag, robot)
    c = read_csv(write_csv(tmp_path / "run.csv", t - t[0], q, tau, dq=dq), robot=robot)
    # the accelerations are derived: the filter's start-up at each end is dropped, as the CSV's
    k = d.processing["derivative_edges"]["samples"]
    assert k == c.processing["derivative_edges"]["samples"] > 0
    keep = slice(k, t.size - k)
    assert d.m == c.m == t.size - 2 * k and d.n == robot.n
    np.testing.assert_allclose(d.t, (t - t[0])[keep], rtol=0, atol=1e-9)  # nanosecond stamps
    np.testing.assert_array_equal(d.q, q[keep])
    np.testing.assert_array_equal(d.dq, dq[keep])
    np.testing.assert_array_equal(d.tau, tau[keep])
    # accelerations are filtered differences: the same up to the stamps' nanosecond rounding
    np.testing.assert_allclose(d.ddq, c.ddq, rtol=0, atol=1e-4 * np.abs(c.ddq).max())
    assert d.processing["topic"] == "/joint_states"
    assert d.processing["velocity"]["source"] == "logged"


def test_velocities_missing_from_the_messages_are_derived(planar, tmp_path):
    robot, log = planar
    bag = write_bag(tmp_path / "nov", messages(robot, log, velocity=False))
    d = read_rosbag(bag, robot, filter="butter", cutoff=20.0)
    assert d.processing["velocity"]["source"] == "differentiated positions"
    k = d.processing["derivative_edges"]["samples"]  # the filter's start-up, dropped
    np.testing.assert_allclose(d.dq, log[2][k : log[0].size - k], atol=2e-3)


def test_a_drive_gain_for_efforts_in_newton_metres_is_refused_not_ignored(planar, tmp_path):
    """read_rosbag took drive_gain= for efforts in N m and ignored it; in A the gain is used."""
    robot, log = planar
    t, q, dq, tau = log
    bag = write_bag(tmp_path / "run", messages(robot, log))
    with pytest.raises(DataError, match=r"^drive_gain=: .* holds torques in N m, not motor curr"):
        read_rosbag(bag, robot, drive_gain=[2.0] * robot.n)
    gain = np.array([2.0, -0.5, 4.0])  # tau = K i, the currents the bag holds
    amps = write_bag(tmp_path / "amps", messages(robot, (t, q, dq, tau / gain)))
    d = read_rosbag(amps, robot, torque_unit="current", drive_gain=gain)
    k = d.processing["derivative_edges"]["samples"]
    np.testing.assert_allclose(d.tau, tau[k : t.size - k], rtol=1e-9, atol=1e-9)


def test_ros1_bag(planar, tmp_path):
    robot, log = planar
    ts1 = get_typestore(Stores.ROS1_NOETIC)
    js1 = ts1.types["sensor_msgs/msg/JointState"]
    h1, t1 = ts1.types["std_msgs/msg/Header"], ts1.types["builtin_interfaces/msg/Time"]
    path = tmp_path / "run.bag"
    with Writer1(path) as w:
        conn = w.add_connection("/joint_states", js1.__msgtype__, typestore=ts1)
        for i, m in enumerate(messages(robot, log)):
            s = m.header.stamp
            msg = js1(
                header=h1(seq=i, stamp=t1(sec=s.sec, nanosec=s.nanosec), frame_id=""),
                name=m.name,
                position=m.position,
                velocity=m.velocity,
                effort=m.effort,
            )
            w.write(conn, 1000 + i, ts1.serialize_ros1(msg, js1.__msgtype__))
    d = read_rosbag(path, robot, filter="none")  # every sample kept
    np.testing.assert_array_equal(d.q, log[1])
    np.testing.assert_array_equal(d.tau, log[3])


def test_identification_from_a_bag_equals_the_csv(planar, tmp_path, capsys):
    robot, log = planar
    t, q, dq, tau = log
    bag = write_bag(tmp_path / "run", messages(robot, log), storage="mcap")
    csv = write_csv(tmp_path / "run.csv", t - t[0], q, tau, dq=dq)
    out = {}
    for name, src in (("bag", bag), ("csv", csv)):
        js = tmp_path / f"{name}.json"
        assert cli.main(["identify", "planar3", str(src), "--json", str(js)]) == 0
        out[name] = json.loads(js.read_text())
    capsys.readouterr()
    b, c = out["bag"], out["csv"]
    assert b["names"] == c["names"] and b["data"]["samples"] == t.size
    np.testing.assert_allclose(b["values"], c["values"], rtol=1e-5)  # stamps in ns
    # noise-free torques of the robot's own parameters: the fit recovers them
    bp = mindyn.base_parameters(robot)
    truth = bp.values(robot.parameters())
    est = np.array(b["base_values"])
    assert b["base_names"] == bp.names
    np.testing.assert_allclose(est, truth, rtol=1e-3, atol=1e-3 * np.abs(truth).max())


def test_bag_errors_are_precise(planar, tmp_path, capsys):
    robot, log = planar
    short = (log[0][:30], log[1][:30], log[2][:30], log[3][:30])
    two = write_bag(tmp_path / "two", messages(robot, short), extra_topics=["/other/joint_states"])
    with pytest.raises(DataError, match="several JointState topics .*/joint_states.*/other"):
        read_rosbag(two, robot)
    assert read_rosbag(two, robot, topic="/other/joint_states", filter="none").m == 30
    with pytest.raises(DataError, match="no JointState topic '/nope'"):
        read_rosbag(two, robot, topic="/nope")

    msgs = messages(robot, short)
    two_joints = robot.joint_names[:2]
    msgs[7] = joint_state(short[0][7], two_joints, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0])
    bag = write_bag(tmp_path / "missing", msgs)
    with pytest.raises(
        DataError,
        match=rf"message 7: no joint\(s\) {robot.joint_names[2]} \(the message names "
        rf"{two_joints[0]}, {two_joints[1]}\)",
    ):
        read_rosbag(bag, robot)

    bag = write_bag(tmp_path / "noeffort", messages(robot, short, effort=False))
    with pytest.raises(DataError, match="carry no efforts"):
        read_rosbag(bag, robot)
    assert read_rosbag(bag, robot, require_torque=False, filter="none").tau is None

    msgs = messages(robot, short)
    msgs[4], msgs[5] = msgs[5], msgs[4]
    bag = write_bag(tmp_path / "order", msgs)
    with pytest.raises(DataError, match="message 5: time stamp not increasing"):
        read_rosbag(bag, robot)

    msgs = messages(robot, short)
    msgs[3].position[0] = np.nan
    bag = write_bag(tmp_path / "nan", msgs)
    with pytest.raises(DataError, match="message 3: position is NaN or infinite"):
        read_rosbag(bag, robot)

    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not a bag")
    with pytest.raises(DataError, match="not a readable ROS bag"):
        read_rosbag(junk, robot)
    with pytest.raises(DataFileNotFoundError):
        read_rosbag(tmp_path / "absent.mcap", robot)

    rc = cli.main(["identify", "planar3", str(tmp_path)])
    err = capsys.readouterr().err
    assert rc == 2 and "is a folder but not a ROS 2 bag (it has no metadata.yaml)" in err

    rc = cli.main(["identify", "planar3", str(two)])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("mindyn: error: ") and err.count("\n") == 1
    assert "--topic" in err


def test_a_bag_in_degrees_or_with_velocities_in_degrees_is_refused(planar, tmp_path, capsys):
    """A bag's JointState in degrees (or its velocities alone in deg/s) was identified without
    a word, as a CSV was; both are refused in one line naming the bag and the unit."""
    robot, log = planar
    t, q, dq, tau = log
    deg = 180 / np.pi
    for name, log_, said in (
        ("deg", (t, q * deg, dq * deg, tau), "seem to be in degrees"),
        ("degps", (t, q, dq * deg, tau), "velocity dq1 is 57.3 times"),
    ):
        bag = write_bag(tmp_path / name, messages(robot, log_))
        assert cli.main(["identify", "planar3", str(bag)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(bag) in err and said in err, err

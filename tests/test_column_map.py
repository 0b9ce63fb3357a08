"""Column maps: a log under a controller's own column names (Universal Robots RTDE style, extra
columns, time in ms, positions in degrees) read through ``columns=`` / ``--columns``.

Reference: the same log the test simulates, written in mindyn's own names by ``write_csv`` and
rewritten by the test under other names (the cells copied as text, the time stamps as whole
milliseconds): read through the map it must give the same arrays, the same estimates and the
same predicted torques as in mindyn's names; positions in degrees converted by pi / 180 must
give the radians within rounding. Every malformed map or log is a one-line error naming
it."""

from __future__ import annotations

import json

import mindyn
import numpy as np
import pytest
from mindyn import cli
from mindyn.control import SensorNoise, simulate_inverse
from mindyn.identification import identify
from mindyn.identification.data import DataError, read_csv, write_csv
from mindyn.identification.excitation import random_trajectory

RATE = 500.0
RTDE = {
    "t[ms]": "timestamp",
    "q": "actual_q_{j0}",
    "dq": "actual_qd_{j0}",
    "tau": "target_moment_{j0}",
}
RTDE_INLINE = "t[ms]=timestamp,q=actual_q_{j0},dq=actual_qd_{j0},tau=target_moment_{j0}"


def _simulated(name: str, path, duration: float = 6.0):
    robot = mindyn.load(name)
    traj = random_trajectory(robot, seed=3, freq=0.2)
    log = simulate_inverse(
        robot, traj, rate=RATE, duration=duration, friction=True, seed=3,
        noise=SensorNoise(torque=0.01),
    )  # fmt: skip
    return robot, log, write_csv(path, log.t, log.q, log.tau, dq=log.dq)


def _cells(path):
    """The header and the rows (lists of cell texts) of a CSV."""
    lines = path.read_text().splitlines()
    return lines[0].split(","), [line.split(",") for line in lines[1:]]


def _rewritten(src, dst, names: dict, *, extra=True, deg=()):
    """The log ``src`` (mindyn's names) written to ``dst`` under ``names`` (mindyn's name ->
    the file's), time in whole ms (the logs are at 500 Hz), with a temperature and a mode
    column between the others when ``extra``; the columns of ``deg`` in degrees."""
    header, rows = _cells(src)
    out_header, columns = [], []
    for k, h in enumerate(header):
        out_header.append(names[h])
        columns.append(k)
        if extra and h == "q1":
            out_header += ["temperature_0", "robot_mode", "safety_status"]
            columns += ["temp", "mode", "safety"]
    lines = [",".join(out_header)]
    for i, row in enumerate(rows):
        cells = []
        for c in columns:
            if c == 0:
                cells.append(str(2 * i))  # ms at 500 Hz: t = i / 500 s
            elif c == "temp":
                cells.append(f"{31.5 + 0.01 * i:.2f}")
            elif c in ("mode", "safety"):
                cells.append("RUNNING" if c == "mode" else "NORMAL")
            elif header[c] in deg:
                cells.append(repr(float(np.rad2deg(float(row[c])))))
            else:
                cells.append(row[c])
        lines.append(",".join(cells))
    dst.write_text("\n".join(lines) + "\n")
    return dst


def _rtde_names(n: int) -> dict:
    names = {"t": "timestamp"}
    for j in range(n):
        names |= {
            f"q{j + 1}": f"actual_q_{j}",
            f"dq{j + 1}": f"actual_qd_{j}",
            f"tau{j + 1}": f"target_moment_{j}",
        }
    return names


@pytest.fixture(scope="module")
def zcr(tmp_path_factory):
    d = tmp_path_factory.mktemp("rtde")
    robot, log, own = _simulated("zcr07s", d / "own.csv")
    rtde = _rewritten(own, d / "rtde.csv", _rtde_names(robot.n))
    return robot, own, rtde


def test_a_log_under_rtde_names_reads_and_identifies_as_under_mindyn_names(zcr):
    robot, own, rtde = zcr
    a = read_csv(own, robot)
    b = read_csv(rtde, robot, columns=RTDE)
    for x, y in ((a.t, b.t), (a.q, b.q), (a.dq, b.dq), (a.ddq, b.ddq), (a.tau, b.tau)):
        np.testing.assert_array_equal(x, y)  # ms / 1000 rounds as the decimal seconds do
    info = b.processing["columns"]
    assert info["ignored"] == 3, info
    assert info["ignored_first"] == ["temperature_0", "robot_mode", "safety_status"], info
    assert info["map"] == RTDE and "ms" in info["units"]["t"], info
    ra, rb = identify(robot, a), identify(robot, b)
    np.testing.assert_allclose(rb.values, ra.values, rtol=1e-12, atol=0)


def test_the_cli_identifies_an_rtde_log_with_columns_and_records_the_map(zcr, tmp_path, capsys):
    robot, own, rtde = zcr
    ja, jb = tmp_path / "a.json", tmp_path / "b.json"
    assert cli.main(["identify", "zcr07s", str(own), "--json", str(ja)]) == 0
    capsys.readouterr()
    assert (
        cli.main(["identify", "zcr07s", str(rtde), "--columns", RTDE_INLINE, "--json", str(jb)])
        == 0
    )
    out = capsys.readouterr().out
    assert "3 other column(s) ignored (temperature_0, robot_mode, safety_status)" in out, out
    da, db = json.loads(ja.read_text()), json.loads(jb.read_text())
    np.testing.assert_allclose(db["base_values"], da["base_values"], rtol=1e-12, atol=0)
    assert db["reading"]["columns"] == RTDE and da["reading"]["columns"] is None
    assert db["data"]["processing"]["columns"]["ignored"] == 3
    # the same map as a YAML file
    spec = tmp_path / "rtde.yaml"
    spec.write_text("".join(f"{k}: '{v}'\n" for k, v in RTDE.items()))
    jc = tmp_path / "c.json"
    assert (
        cli.main(["identify", "zcr07s", str(rtde), "--columns", str(spec), "--json", str(jc)]) == 0
    )
    assert json.loads(jc.read_text())["base_values"] == db["base_values"]
    # predict reads a log as the JSON records: its map applies without --columns
    pa, pb = tmp_path / "pa.csv", tmp_path / "pb.csv"
    assert cli.main(["predict", "zcr07s", str(ja), str(own), "-o", str(pa)]) == 0
    capsys.readouterr()
    assert cli.main(["predict", "zcr07s", str(jb), str(rtde), "-o", str(pb)]) == 0
    assert "columns mapped: t[ms]=timestamp" in capsys.readouterr().out
    assert pa.read_text() == pb.read_text()
    # a log without torques: the recorded map's torque columns are optional for predict
    header, rows = _cells(rtde)
    keep = [k for k, h in enumerate(header) if not h.startswith("target_moment")]
    notau = tmp_path / "notau.csv"
    notau.write_text("\n".join(",".join(r[k] for k in keep) for r in [header, *rows]) + "\n")
    pc = tmp_path / "pc.csv"
    assert cli.main(["predict", "zcr07s", str(jb), str(notau), "-o", str(pc)]) == 0
    capsys.readouterr()
    a, c = (np.genfromtxt(p, delimiter=",", names=True) for p in (pa, pc))
    assert "tau_hat1" in c.dtype.names and "tau1" not in c.dtype.names, c.dtype.names
    for name in c.dtype.names:
        np.testing.assert_array_equal(c[name], a[name])
    # and detect: the thresholds calibrated on the log through the recorded map, or through
    # the map given, are those of the log under mindyn's names
    thr = {}
    for key, doc, log, extra in (
        ("a", ja, own, []),
        ("b", jb, rtde, []),
        ("c", ja, rtde, ["--columns", str(spec)]),
    ):
        thr[key] = tmp_path / f"thr_{key}.json"
        argv = ["detect", "zcr07s", str(doc), str(log), "--calibrate", str(thr[key]), *extra]
        assert cli.main(argv) == 0
        out = capsys.readouterr().out
        assert ("3 other column(s) ignored" in out) == (key != "a"), out
    ta, tb, tc = (json.loads(thr[k].read_text()) for k in "abc")
    assert ta["thresholds"] == tb["thresholds"] == tc["thresholds"], (ta, tb)


def test_name_patterns_and_lists_of_names(tmp_path):
    robot, log, own = _simulated("planar2", tmp_path / "own.csv", duration=3.0)
    names = {"t": "time"}
    for j, joint in enumerate(robot.joint_names):
        names |= {f"q{j + 1}": f"{joint}.pos", f"dq{j + 1}": f"vel {j + 1}", f"tau{j + 1}": f"T{j}"}
    other = _rewritten(own, tmp_path / "named.csv", names, extra=False)
    a = read_csv(own, robot)
    cmap = {"t[ms]": "time", "q": "{name}.pos", "dq": "vel {j}", "tau": ["T0", "T1"]}
    b = read_csv(other, robot, columns=cmap)
    for x, y in ((a.t, b.t), (a.q, b.q), (a.dq, b.dq), (a.tau, b.tau)):
        np.testing.assert_array_equal(x, y)
    assert b.processing["columns"]["ignored"] == 0


def test_positions_and_velocities_in_degrees_on_revolute_joints_only(tmp_path):
    robot, log, own = _simulated("stanford", tmp_path / "own.csv", duration=3.0)
    prismatic = [j for j, t in enumerate(robot.joint_types) if t == "prismatic"]
    assert prismatic, robot.joint_types  # the Stanford arm's third joint
    deg = {
        f"{k}{j + 1}"
        for k in ("q", "dq")
        for j in range(robot.n)
        if robot.joint_types[j] == "revolute"
    }
    other = _rewritten(own, tmp_path / "deg.csv", _rtde_names(robot.n), deg=deg)
    a = read_csv(own, robot)
    cmap = {
        "t[ms]": "timestamp",
        "q[deg]": "actual_q_{j0}",
        "dq[deg/s]": "actual_qd_{j0}",
        "tau": "target_moment_{j0}",
    }
    b = read_csv(other, robot, columns=cmap)
    np.testing.assert_array_equal(b.q[:, prismatic], a.q[:, prismatic])
    np.testing.assert_allclose(b.q, a.q, rtol=1e-15, atol=1e-300)  # one rounding each way
    np.testing.assert_allclose(b.dq, a.dq, rtol=1e-15, atol=1e-300)
    units = b.processing["columns"]["units"]
    revolute = [str(j + 1) for j in range(robot.n) if j not in prismatic]
    assert f"revolute joint(s) {', '.join(revolute)}" in units["q"], units
    ra, rb = identify(robot, a), identify(robot, b)
    scale = np.maximum(np.abs(ra.values), ra.std)
    assert np.max(np.abs(rb.values - ra.values) / scale) < 1e-8


def _current_logs(own, tmp_path, gain):
    """The torques of the log ``own`` as motor currents (torque / gain): in mindyn's names
    (``t, q, i``) and under RTDE names (``timestamp`` in ms, ``actual_q_*``,
    ``actual_current_*``), each in one file and split into a position log and a currents
    file."""
    header, rows = _cells(own)
    n = 6
    cur = [[repr(float(x) / g) for x, g in zip(row[1 + 2 * n :], gain)] for row in rows]
    mine = [
        ["t", *[f"q{j + 1}" for j in range(n)]],
        [f"i{j + 1}" for j in range(n)],
        [row[: 1 + n] for row in rows],
    ]
    theirs = [
        ["timestamp", *[f"actual_q_{j}" for j in range(n)]],
        [f"actual_current_{j}" for j in range(n)],
        [[str(2 * i), *row[1 : 1 + n]] for i, row in enumerate(rows)],
    ]
    out = {}
    for key, (head, ihead, pos) in (("mine", mine), ("theirs", theirs)):
        both = [",".join(head + ihead)] + [",".join(p + c) for p, c in zip(pos, cur)]
        only_q = [",".join(head)] + [",".join(p) for p in pos]
        only_i = [",".join([head[0], "mode"] + ihead)]
        only_i += [",".join([p[0], "7"] + c) for p, c in zip(pos, cur)]
        for name, lines in (("both", both), ("q", only_q), ("i", only_i)):
            out[key, name] = tmp_path / f"{key}_{name}.csv"
            out[key, name].write_text("\n".join(lines) + "\n")
    return out


def test_motor_currents_through_the_map_in_the_log_and_in_a_currents_file(zcr, tmp_path):
    from mindyn.identification.options import ReadingOptions
    from mindyn.identification.reading import read_log

    robot, own, rtde = zcr
    gain = [150.0, 150.0, 120.0, 40.0, 40.0, 30.0]
    f = _current_logs(own, tmp_path, gain)
    cmap = {"t[ms]": "timestamp", "q": "actual_q_{j0}", "i": "actual_current_{j0}"}
    a = read_csv(f["mine", "both"], robot, drive_gain=gain)
    b = read_csv(f["theirs", "both"], robot, columns=cmap, drive_gain=gain)
    np.testing.assert_array_equal(b.t, a.t)
    np.testing.assert_array_equal(b.tau, a.tau)
    assert b.processing["torque"]["unit"] == "motor current [A]"
    # a currents file of its own: read through the map's t and i
    opts = ReadingOptions(filter="none", drive_gain=gain)
    [c] = read_log(f["mine", "q"], robot, options=opts, currents=f["mine", "i"])
    opts = ReadingOptions(filter="none", drive_gain=gain, columns=cmap)
    [d] = read_log(f["theirs", "q"], robot, options=opts, currents=f["theirs", "i"])
    np.testing.assert_array_equal(d.tau, c.tau)
    np.testing.assert_array_equal(d.q, c.q)
    with pytest.raises(mindyn.ArgumentError, match="has no i: a currents file is read"):
        opts = ReadingOptions(filter="none", drive_gain=gain, columns=RTDE)
        read_log(f["theirs", "q"], robot, options=opts, currents=f["theirs", "i"])


@pytest.mark.parametrize(
    "cmap, needle",
    [
        ({"x": "a", "t": "t", "q": "q{j}"}, "columns names the quantity 'x'; expected t, q, dq"),
        ({"t": "t", "q": "q{j}", "q[deg]": "p{j}"}, "columns gives q twice ('q' and 'q[deg]')"),
        ({"t": "t", "q": "a{j0}", "dq": "a{j0}"}, "columns maps column 'a0' twice (q1 and dq1)"),
        ({"t": "t", "q": "pos", "tau": "T{j}"}, "maps q to the one column 'pos' for 6 joints"),
        ({"t": "t", "q": "q{k}"}, "holds the placeholder {k}; expected {j} (joint number"),
        ({"t": "t{j}", "q": "q{j}"}, "t='t{j}' holds the placeholder {j}; t names one column"),
        ({"t": "t", "q": "q{j"}, "q='q{j' has an unmatched brace"),
        ({"t": "t", "q": ["a", "b"]}, "gives 2 names of q for a robot of 6 joints"),
        ({"t[min]": "t", "q": "q{j}"}, "gives t in 'min'; the units of t are s, ms, us"),
        ({"t": "t", "q[grad]": "q{j}"}, "gives q in 'grad'; the units of q are rad, deg"),
        ({"t": "t", "q": "q{j}", "tau": "T{j}", "i": "I{j}"}, "gives both tau and i"),
        ({"q": "q{j}", "tau": "T{j}"}, "columns has no t; a map names the time and position"),
        ({"t": "t", "q": "q{j}"}, "columns has no tau or i; the torques"),
        ({"t": "t", "q": "q{j}", "tau": 3}, "columns tau is the scalar 3; expected a column name"),
        ({"t": "t", "q": "q{j}", "tau": ""}, "gives an empty column name for tau"),
        ({"t": "t", "q": ["a", 1, "c", "d", "e", "f"]}, "columns q is the scalar 1; expected text"),
        ("t=t", "columns is a str 't=t'; expected a mapping"),
    ],
)
def test_a_malformed_map_is_a_one_line_argument_error(zcr, cmap, needle):
    robot, own, rtde = zcr
    with pytest.raises(mindyn.ArgumentError) as e:
        read_csv(rtde, robot, columns=cmap)
    assert needle in str(e.value) and "\n" not in str(e.value), str(e.value)


def test_a_mapped_column_the_file_lacks_is_named_with_the_closest_names(zcr):
    robot, own, rtde = zcr
    with pytest.raises(DataError) as e:
        read_csv(rtde, robot, columns={**RTDE, "q": "actual_q_{j}"})  # numbered from 1
    msg = str(e.value)
    assert msg.startswith(f"{rtde}: no column 'actual_q_6' (q6 of the column map)"), msg
    assert "the closest the file has: 'actual_q_5'" in msg, msg
    with pytest.raises(DataError, match="none of the file's 22 columns is close"):
        read_csv(rtde, robot, columns={**RTDE, "tau": "xyzzy{j}"})


def test_text_in_a_mapped_column_names_file_line_and_the_files_column(zcr, tmp_path):
    robot, own, rtde = zcr
    lines = rtde.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[4].split(",")
    cells[header.index("actual_q_2")] = "12,5".replace(",", ";")
    lines[4] = ",".join(cells)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError) as e:
        read_csv(bad, robot, columns=RTDE)
    assert str(e.value).startswith(f"{bad}, line 5, column actual_q_2: '12;5' is not a number")


@pytest.mark.parametrize(
    "value, needle",
    [
        ("t=timestamp,q=actual_q,tau=T{j}", "--columns maps q to the one column 'actual_q' for 6"),
        ("q=actual_q_{j0}", "argument --columns: has no t; a map names the time"),
        ("t[ms]=timestamp,actual_q_{j0}", "'actual_q_{j0}' is not QUANTITY=NAME"),
        ("t[ms]=timestamp;q=actual_q_{j0}", "t='timestamp;q=actual_q_{j0}' holds the placeholder"),
        ("t=timestamp,t=time", "argument --columns: gives t twice"),
        ("missing.yaml", "column map file 'missing.yaml' does not exist"),
        ("t[ms]=timestamp,q=actual_q_{j},tau=target_moment_{j0}", "no column 'actual_q_6'"),
        ("t[ms]=timestamp,q=actual_q_{j0},dq=actual_qd_{j0}", "--columns has no tau or i"),
    ],
)
def test_cli_column_map_errors_are_one_line(zcr, value, needle, capsys, monkeypatch, tmp_path):
    robot, own, rtde = zcr
    monkeypatch.chdir(tmp_path)
    rc = cli.main(["identify", "zcr07s", str(rtde), "--columns", value])
    err = capsys.readouterr().err
    assert rc == 2 and len(err.splitlines()) == 1 and needle in err, err


def test_cli_yaml_column_map_that_is_not_a_mapping(zcr, tmp_path, capsys):
    robot, own, rtde = zcr
    spec = tmp_path / "map.yml"
    spec.write_text("- t\n- q\n")
    rc = cli.main(["identify", "zcr07s", str(rtde), "--columns", str(spec)])
    err = capsys.readouterr().err
    assert rc == 2 and "expected a mapping of quantities to column names" in err, err


def test_the_cells_of_ignored_columns_do_not_change_what_is_read(zcr, tmp_path):
    """The rows cut down to the mapped columns (text in the others) read as the CSV reader reads
    them cell by cell: the same log with a quoted cell holding a comma in an ignored column
    (which only the CSV reader splits right) and with a blank line gives the same arrays."""
    robot, own, rtde = zcr
    lines = rtde.read_text().splitlines()
    quoted = [lines[0]] + [line.replace("RUNNING", '"RUNNING, remote"') for line in lines[1:]]
    quoted.insert(7, "")
    other = tmp_path / "quoted.csv"
    other.write_text("\r\n".join(quoted) + "\r\n")
    a = read_csv(rtde, robot, columns=RTDE)
    b = read_csv(other, robot, columns=RTDE)
    for x, y in ((a.t, b.t), (a.q, b.q), (a.dq, b.dq), (a.ddq, b.ddq), (a.tau, b.tau)):
        np.testing.assert_array_equal(x, y)
    c = read_csv(own, robot)  # and as under mindyn's names
    np.testing.assert_array_equal(a.q, c.q)


def test_a_map_with_a_ros_bag_is_refused(zcr, tmp_path, capsys):
    """A bag's joints are matched by name: a column map does not apply to it, and is refused
    (naming the option) before any log is read."""
    robot, own, rtde = zcr
    bag = tmp_path / "run.mcap"
    bag.write_bytes(b"")
    rc = cli.main(["identify", "zcr07s", str(rtde), str(bag), "--columns", RTDE_INLINE])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("mindyn: error: --columns applies to CSV logs; a ROS bag"), (
        err
    )


def test_a_header_the_map_cannot_be_matched_to_is_named_as_such(zcr, tmp_path):
    """The header checks of the reader hold with a map: a log separated by semicolons, or one
    without a header, is refused saying so (not as a mapped column missing)."""
    robot, own, rtde = zcr
    lines = rtde.read_text().splitlines()
    semi = tmp_path / "semi.csv"
    semi.write_text("\n".join(line.replace(",", ";") for line in lines) + "\n")
    with pytest.raises(DataError, match="the header is separated by semicolons, not commas"):
        read_csv(semi, robot, columns=RTDE)
    bare = tmp_path / "bare.csv"
    bare.write_text("\n".join(own.read_text().splitlines()[1:]) + "\n")
    with pytest.raises(DataError, match="holds numbers .* the header is missing"):
        read_csv(bare, robot, columns=RTDE)


def test_an_identification_json_with_a_malformed_recorded_map_is_named(zcr, tmp_path, capsys):
    robot, own, rtde = zcr
    doc = tmp_path / "id.json"
    assert (
        cli.main(["identify", "zcr07s", str(rtde), "--columns", RTDE_INLINE, "--json", str(doc)])
        == 0
    )
    d = json.loads(doc.read_text())
    d["reading"]["columns"]["x"] = "y"
    doc.write_text(json.dumps(d))
    capsys.readouterr()
    rc = cli.main(["predict", "zcr07s", str(doc), str(rtde), "-o", str(tmp_path / "p.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and f"{doc}: 'reading' columns names the quantity 'x'" in err, err

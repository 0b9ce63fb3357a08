"""Joint data in and out: CSV format, torque units, derivatives, and precise errors."""

from __future__ import annotations

import numpy as np
import pytest
from mindyn import cli, load
from mindyn.identification import IdentificationError, identify
from mindyn.identification.data import (
    DataError,
    DataFileNotFoundError,
    differentiate,
    read_csv,
    read_truth,
    truth_path,
    write_csv,
)

# The ZCR07S study, Table 4: motor rated torque [N m] and reducer ratio of the ZCR07S joints.
SEED_RATED = [2.390, 2.390, 1.270, 0.318, 0.318, 0.318]
SEED_GEAR = [120, 120, 100, 116, 80, 50]


def _log(n=3, m=400, rate=250.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(m) / rate
    q = np.sin(np.outer(t, rng.uniform(0.5, 2, n)) + rng.uniform(0, 1, n))
    dq = np.cos(q)
    tau = rng.normal(size=(m, n))
    return t, q, dq, tau


def _write(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(r) for r in rows) + "\n")
    return path


def test_roundtrip_with_logged_velocities(tmp_path):
    t, q, dq, tau = _log()
    p = write_csv(tmp_path / "a.csv", t, q, tau, dq=dq)
    assert p.read_text().splitlines()[0] == "t,q1,q2,q3,dq1,dq2,dq3,tau1,tau2,tau3"
    d = read_csv(p)
    # the accelerations are derived: the filter's start-up, 2 periods of its 10 Hz cut-off
    # (0.2 s, 50 samples at 250 Hz), dropped at each end
    k = 50
    assert d.processing["derivative_edges"]["samples"] == k
    assert d.n == 3 and d.m == t.size - 2 * k
    np.testing.assert_allclose(d.t, t[k:-k], rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(d.q, q[k:-k], rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(d.dq, dq[k:-k], rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(d.tau, tau[k:-k], rtol=1e-11, atol=1e-12)
    assert d.processing["velocity"]["source"] == "logged"
    assert d.processing["acceleration"]["source"] == "differentiated velocities"
    assert d.rate == pytest.approx(250.0)


def test_permille_torques_use_the_drive_table(tmp_path):
    robot = load("zcr07s")
    t, q, _, _ = _log(n=6)
    per = np.full((t.size, 6), 1000.0)
    per[:, 3] = -500.0
    d = read_csv(write_csv(tmp_path / "p.csv", t, q, per), robot, torque_unit="permille")
    expect = np.array(SEED_RATED) * np.array(SEED_GEAR)  # value x rated x gear / 1000
    expect[3] *= -0.5
    np.testing.assert_allclose(d.tau[0], expect, rtol=1e-12)
    assert d.processing["torque"]["unit"].startswith("permille")


def test_permille_without_drive_table_is_an_error(tmp_path):
    t, q, _, tau = _log(n=3)
    p = write_csv(tmp_path / "p.csv", t, q, tau)
    with pytest.raises(DataError, match="no rated torque / gear ratio for joint"):
        read_csv(p, load("puma560_3"), torque_unit="permille")
    with pytest.raises(DataError, match="unknown torque unit 'kNm'"):
        read_csv(p, load("puma560_3"), torque_unit="kNm")


@pytest.mark.parametrize("method", ["butter", "savgol"])
def test_derivatives_of_positions_match_closed_form(tmp_path, method):
    rate, f = 250.0, 0.4
    t = np.arange(2501) / rate
    w = 2 * np.pi * f
    q = np.column_stack([np.sin(w * t), 0.5 * np.cos(2 * w * t)])
    dq_exact = np.column_stack([w * np.cos(w * t), -w * np.sin(2 * w * t)])
    ddq_exact = np.column_stack([-(w**2) * np.sin(w * t), -2 * w**2 * np.cos(2 * w * t)])
    noisy = q + np.random.default_rng(1).normal(scale=1e-5, size=q.shape)
    p = write_csv(tmp_path / "d.csv", t, noisy, np.zeros_like(q))
    d = read_csv(p, filter=method)
    # every sample kept: the ends where the filters start up are dropped by the reader
    inner = slice(
        d.processing["derivative_edges"]["samples"],
        t.size - d.processing["derivative_edges"]["samples"],
    )
    np.testing.assert_array_equal(d.t, t[inner])
    e_v = np.abs(d.dq - dq_exact[inner]).max() / np.abs(dq_exact).max()
    e_a = np.abs(d.ddq - ddq_exact[inner]).max() / np.abs(ddq_exact).max()
    print(f"\n{method}: max relative error velocity {e_v:.2e}, acceleration {e_a:.2e}")
    assert e_v < 1e-3 and e_a < 1e-2
    info = d.processing["velocity"]
    assert info["source"] == "differentiated positions"
    if method == "butter":
        assert info["order"] == 4 and info["cutoff_Hz"] == pytest.approx(10.0)
    else:
        assert info["window_samples"] % 2 == 1 and info["polyorder"] == 3


def test_differentiate_rejects_bad_settings():
    t = np.arange(100) / 100.0
    x = np.zeros((100, 1))
    with pytest.raises(DataError, match="cutoff 60 Hz must be between 0 and half the rate"):
        differentiate(t, x, cutoff=60)
    with pytest.raises(DataError, match="unknown filter 'kalman'"):
        differentiate(t, x, filter="kalman")


def test_missing_and_extra_columns_are_named(tmp_path):
    rows = [["0", "1", "2", "3", "4"], ["0.004", "1", "2", "3", "4"]]
    p = _write(tmp_path / "c.csv", ["t", "q1", "q2", "tau1", "tau3"], rows)
    with pytest.raises(DataError) as e:
        read_csv(p, n=2)
    msg = str(e.value)
    assert "missing tau2" in msg and "unexpected tau3" in msg and "c.csv" in msg
    p = _write(
        tmp_path / "x.csv", ["t", "q1", "q2", "tau1", "tau2", "current1"], [r + ["0"] for r in rows]
    )
    with pytest.raises(DataError, match="unexpected current1"):
        read_csv(p, n=2)
    p = _write(
        tmp_path / "v.csv", ["t", "q1", "q2", "dq1", "tau1", "tau2"], [r + ["0"] for r in rows]
    )
    with pytest.raises(DataError, match="missing dq2"):
        read_csv(p, n=2)
    p = _write(tmp_path / "n.csv", ["time", "q1", "q2", "tau1", "tau2"], rows)
    with pytest.raises(DataError, match=r"missing t; unexpected time"):
        read_csv(p, n=2)


def _cut(text: str, fields: str) -> str:
    """``cut -d, -f FIELDS`` of a text, in Python: the 1-based columns of ``1-3,5``."""
    keep = []
    for part in fields.split(","):
        a, _, b = part.partition("-")
        keep += range(int(a), int(b or a) + 1)
    return "".join(
        ",".join(line.split(",")[k - 1] for k in keep) + "\n" for line in text.splitlines()
    )


@pytest.mark.parametrize("extra", [["temp1"], ["temp1", "mode"]])
def test_an_unknown_column_is_named_with_the_remedy_that_reads_the_log(extra, tmp_path, capsys):
    """A log with columns the reader does not know (a temperature, a mode) is refused naming
    each with its position and saying what to do: the reader has no option to skip a column,
    so the message gives the cut command that deletes them; that command's columns, applied
    here, give a log that reads as the data written."""
    t, q, dq, tau = _log(n=2, m=50)
    header = ["t", "q1", "temp1", "q2", "tau1", "tau2", "mode"]
    header = [h for h in header if h in extra or h not in ("temp1", "mode")]
    cells = {"t": t, "q1": q[:, 0], "q2": q[:, 1], "tau1": tau[:, 0], "tau2": tau[:, 1]}
    cells |= {"temp1": 20.0 + t, "mode": np.ones_like(t)}
    rows = [[repr(float(cells[h][i])) for h in header] for i in range(len(t))]
    path = _write(tmp_path / "log.csv", header, rows)
    with pytest.raises(DataError) as e:
        read_csv(path, n=2)
    msg = str(e.value)
    for name in extra:
        assert f"{name} (column {header.index(name) + 1})" in msg, msg
    assert "unless a column map names the ones to read (columns=" in msg, msg
    fields = msg.split("cut -d, -f")[1].split()[0]
    (tmp_path / "cut.csv").write_text(_cut(path.read_text(), fields))
    data = read_csv(tmp_path / "cut.csv", n=2, filter="none")
    np.testing.assert_array_equal(data.q, q)
    np.testing.assert_array_equal(data.tau, tau)
    rc = cli.main(["identify", "planar2", str(path)])
    err = capsys.readouterr().err
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert f"cut -d, -f{fields} " in err, err


def _trailing_commas(tmp_path, commas: int):
    """A two-joint log (t, q1, q2, tau1, tau2) whose header and rows end with ``commas`` commas,
    as a spreadsheet writes it: its text, its path and the positions and torques written."""
    t, q, dq, tau = _log(n=2, m=50)
    cols = [t, q[:, 0], q[:, 1], tau[:, 0], tau[:, 1]]
    end = "," * commas + "\n"
    text = "t,q1,q2,tau1,tau2" + end
    text += "".join(",".join(repr(float(c[i])) for c in cols) + end for i in range(len(t)))
    path = tmp_path / "log.csv"
    path.write_text(text)
    return text, path, q, tau


def test_a_trailing_comma_is_named_as_an_unnamed_column(tmp_path):
    """A spreadsheet's trailing comma gives the header a column with an empty name: the message
    read 'unexpected )' and 'delete  (column 6)'. It names the unnamed column and its position;
    the cut command given reads the log; two such columns are named as unnamed too."""
    text, path, q, _ = _trailing_commas(tmp_path, 1)
    with pytest.raises(DataError) as e:
        read_csv(path, n=2)
    msg = str(e.value)
    assert "unexpected an unnamed column)" in msg and "delete the unnamed column 6 " in msg, msg
    assert "unexpected )" not in msg and "delete  (" not in msg
    fields = msg.split("cut -d, -f")[1].split()[0]
    (tmp_path / "cut.csv").write_text(_cut(text, fields))
    np.testing.assert_array_equal(read_csv(tmp_path / "cut.csv", n=2, filter="none").q, q)


def test_a_double_trailing_comma_gets_the_cut_remedy_too(tmp_path):
    """Two trailing commas give the header two columns with an empty name: the message said an
    unnamed column appears twice, with no remedy. Both are named as unnamed columns with their
    positions, and the cut command given reads the log (the positions it gives back are the
    test's own)."""
    text, path, q, tau = _trailing_commas(tmp_path, 2)
    with pytest.raises(DataError) as e:
        read_csv(path, n=2)
    msg = str(e.value)
    assert "appears twice" not in msg, msg
    assert "the unnamed column 6, the unnamed column 7" in msg, msg
    fields = msg.split("cut -d, -f")[1].split()[0]
    assert fields == "1-5", msg
    (tmp_path / "cut.csv").write_text(_cut(text, fields))
    data = read_csv(tmp_path / "cut.csv", n=2, filter="none")
    np.testing.assert_array_equal(data.q, q)
    np.testing.assert_array_equal(data.tau, tau)


def test_wrong_joint_count_for_the_robot(tmp_path):
    t, q, _, tau = _log(n=3)
    p = write_csv(tmp_path / "a.csv", t, q, tau)
    with pytest.raises(DataError, match="6-joint robot.*missing q4, q5, q6"):
        read_csv(p, load("zcr07s"))


def test_time_must_increase_and_the_line_is_named(tmp_path):
    rows = [[f"{t}", "0", "0"] for t in (0.0, 0.004, 0.008, 0.006, 0.01)]
    p = _write(tmp_path / "t.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(
        DataError, match=r"t\.csv, line 5: time is not increasing \(t = 0\.006 after 0\.008\)"
    ):
        read_csv(p)


def test_nan_and_non_numbers_are_located(tmp_path):
    rows = [["0", "0", "0"], ["0.004", "0", "nan"], ["0.008", "0", "0"]]
    p = _write(tmp_path / "nan.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match="line 3, column tau1: NaN"):
        read_csv(p)
    rows[1][1] = "abc"
    p = _write(tmp_path / "s.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match="line 3, column q1: 'abc' is not a number"):
        read_csv(p)
    rows[1] = ["0.004", "0"]
    p = _write(tmp_path / "r.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match="line 3: 2 values for 3 columns"):
        read_csv(p)


@pytest.mark.parametrize(
    "cell, match",
    [
        ("1_000", r"'1_000' is not a number"),  # float() takes digit-group underscores
        ("\uff11", r"'\uff11' is not a number"),  # and full-width digits
        ("\u0661.5", r".* is not a number"),  # and Arabic-Indic ones
        ("0x10", r"'0x10' is not a number"),
        ("1.5\u00a0", r"'1.5\\xa0' is not a number"),  # a non-breaking space is no ASCII blank
        ("1e5e5", r"'1e5e5' is not a number"),
        (" nan", r"NaN"),
        ("-Infinity", r"an infinite value"),
        ("INF", r"an infinite value"),
        ("1e400", r"'1e400' is too large for a double"),
    ],
)
def test_cells_must_be_ascii_decimal_numbers(tmp_path, cell, match):
    rows = [["0", "0", "0"], ["0.004", cell, "0"], ["0.008", "0", "0"]]
    p = _write(tmp_path / "c.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match=rf"c\.csv, line 3, column q1: {match}"):
        read_csv(p, filter="none")


def test_accepted_number_spellings_read_exactly(tmp_path):
    # blanks around a number, signs, a bare point, exponents: values known from the text
    cells = [" 1.5", "+2", "-.25", "3.", "1E-3 ", "\t7e+2"]
    rows = [[str(0.004 * k), c, "0"] for k, c in enumerate(cells)]
    d = read_csv(_write(tmp_path / "ok.csv", ["t", "q1", "tau1"], rows), filter="none")
    assert d.q[:, 0].tolist() == [1.5, 2.0, -0.25, 3.0, 1e-3, 700.0]


def test_non_utf8_and_nul_bytes_are_one_line_errors(tmp_path):
    p = tmp_path / "b.csv"
    p.write_bytes(b"t,q1,tau1\n0,0,0\n0.004,\xff1,0\n0.008,0,0\n")
    with pytest.raises(
        DataError, match=r"b\.csv, line 3: not UTF-8 text \(byte 0xff at offset 22\)"
    ):
        read_csv(p)
    p.write_bytes(b"t,q1,tau1\n0,0,0\n0.004,\x001,0\n0.008,0,0\n")
    with pytest.raises(DataError, match=r"b\.csv, line 3, column q1: .* is not a number"):
        read_csv(p)
    # a byte-order mark (as spreadsheet programs write) is not part of the first column's name
    p.write_bytes(b"\xef\xbb\xbft,q1,tau1\n0,0,0\n0.004,1,0\n0.008,2,0\n")
    assert read_csv(p, filter="none").q[:, 0].tolist() == [0.0, 1.0, 2.0]


def test_header_indices_are_checked_before_use(tmp_path):
    # a huge joint index used to make a list of that many missing columns
    p = _write(tmp_path / "h.csv", ["t", "q99999999999999999999"], [["0", "1"], ["1", "2"]])
    with pytest.raises(DataError, match=r"h\.csv: column 'q99999999999999999999' implies"):
        read_csv(p, require_torque=False)
    for name in ("q01", "q\u0661"):  # leading zeros and non-ASCII digits are no indices
        p = _write(tmp_path / "z.csv", ["t", name], [["0", "1"], ["1", "2"]])
        with pytest.raises(DataError, match=r"z\.csv: no position columns .* \(it has"):
            read_csv(p, require_torque=False)


@pytest.mark.parametrize("first", ["0,0,0,0,0", "0.0, 0.1 ,-2e-3,1.5,nan", "# log\n0,1,2,3,4"])
def test_a_log_without_header_says_the_header_is_missing(tmp_path, first, capsys):
    # data from the first line on: repeated values used to be reported as a column twice
    p = tmp_path / "raw.csv"
    p.write_text(first + "\n0.004,1,2,3,4\n")
    with pytest.raises(DataError) as e:
        read_csv(p, n=2)
    msg = str(e.value)
    assert "raw.csv" in msg and "not column names: the header is missing" in msg, msg
    assert "t, q1..q2," in msg and "tau1..tau2" in msg and "twice" not in msg, msg
    assert cli.main(["identify", "planar2", str(p)]) == 2
    err = capsys.readouterr().err
    assert "the header is missing" in err and err.count("\n") == 1, err


@pytest.mark.parametrize("sep, word", [(";", "semicolons"), ("\t", "tabs")])
def test_a_log_separated_otherwise_is_named_as_such(tmp_path, sep, word, capsys):
    """A semicolon- or tab-separated log (a spreadsheet's export) was reported as missing every
    column; the message says how it is separated and what a log is."""
    p = tmp_path / "s.csv"
    rows = ["t,q1,q2,tau1,tau2", "0,0,0,1,2", "0.004,1,2,3,4"]
    p.write_text("\n".join(r.replace(",", sep) for r in rows) + "\n")
    with pytest.raises(DataError) as e:
        read_csv(p, n=2)
    msg = str(e.value)
    assert f"s.csv: the header is separated by {word}, not commas" in msg, msg
    assert "missing" not in msg and "t, q1..q2," in msg, msg
    assert cli.main(["identify", "planar2", str(p)]) == 2
    err = capsys.readouterr().err
    assert f"separated by {word}" in err and err.count("\n") == 1, err
    # a one-column log with a semicolon in its name is not taken for one
    q = tmp_path / "one.csv"
    q.write_text("t;x\n0\n1\n")
    with pytest.raises(DataError) as e:
        read_csv(q, n=1)
    assert "separated by" not in str(e.value)


def test_column_names_with_line_breaks_stay_on_one_line(tmp_path):
    p = tmp_path / "n.csv"
    p.write_text('t,q1,"x\ny"\n0,0,0\n1,1,1\n')
    with pytest.raises(DataError, match=r"n\.csv: .*unexpected x\\ny") as info:
        read_csv(p, require_torque=False)
    assert "\n" not in str(info.value)


def test_values_whose_derivatives_overflow_are_refused(tmp_path):
    rows = [["0", "1e308", "0"], ["0.004", "-1e308", "0"], ["0.008", "1e308", "0"]]
    p = _write(tmp_path / "o.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match=r"o\.csv: the velocities overflow"):
        read_csv(p, filter="none")
    # errors of the derivative settings name the file too
    rows = [[str(0.004 * k), "0", "0"] for k in range(5)]
    p = _write(tmp_path / "f.csv", ["t", "q1", "tau1"], rows)
    with pytest.raises(DataError, match=r"f\.csv: cutoff 10 Hz is below one cycle"):
        read_csv(p)


def test_empty_and_missing_files(tmp_path):
    (tmp_path / "e.csv").write_text("")
    with pytest.raises(DataError, match="empty"):
        read_csv(tmp_path / "e.csv")
    (tmp_path / "h.csv").write_text("t,q1,tau1\n0,0,0\n")
    with pytest.raises(DataError, match="1 data row"):
        read_csv(tmp_path / "h.csv")
    with pytest.raises(DataFileNotFoundError, match="does not exist"):
        read_csv(tmp_path / "nope.csv")
    assert issubclass(DataFileNotFoundError, FileNotFoundError)
    assert issubclass(DataError, ValueError)


def test_too_few_samples_for_the_parameters(tmp_path):
    robot = load("zcr07s")
    t, q, dq, tau = _log(n=6, m=8)
    d = read_csv(write_csv(tmp_path / "s.csv", t, q, tau, dq=dq), robot, filter="none")
    with pytest.raises(IdentificationError, match=r"8 samples x 6 joints = 48 equations for 52"):
        identify(robot, d, rotor=True, friction=True)
    with pytest.raises(IdentificationError, match="energy windows"):
        identify(robot, d, model="energy", rotor=True, friction=True, energy_window=1)


def test_truth_sidecar(tmp_path):
    p = tmp_path / "log.csv"
    assert truth_path(p).name == "log.truth.json"
    assert read_truth(p) is None
    truth_path(p).write_text('{"names": ["M1"], "values": [2.0]}')
    assert read_truth(p)["values"] == [2.0]
    truth_path(p).write_text("{nope")
    with pytest.raises(DataError, match="not valid JSON"):
        read_truth(p)


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ('{"names": ["M1", "M2"], "values": [2.0]}', "'values' holds 1 values for 2 names"),
        ('{"names": ["M1"], "values": ["x"]}', "the value of M1 is 'x'; expected a finite"),
        ('{"names": ["M1"], "values": [true]}', "the value of M1 is True; expected a finite"),
        ('{"names": "M1", "values": [1.0]}', "'names' must be a list of parameter names"),
    ],
)
def test_a_truth_sidecar_that_does_not_pair_names_and_values_is_refused(tmp_path, text, said):
    """A truth sidecar with fewer values than names was paired by zip, the missing names
    taken as zero: a wrong 'true' column without a word; a value that is not a number ended
    in 'could not convert string to float: 'x'' without the file. Both named with the file."""
    p = tmp_path / "log.csv"
    truth_path(p).write_text(text)
    with pytest.raises(DataError) as e:
        read_truth(p)
    assert str(e.value).startswith(f"{truth_path(p)}: ") and said in str(e.value)


def test_cli_reports_bad_data_in_one_line(tmp_path, capsys):
    rows = [["0", "0", "0"], ["0.004", "0", "0"], ["0.002", "0", "0"]]
    p = _write(tmp_path / "bad.csv", ["t", "q1", "tau1"], rows)
    rc = cli.main(["identify", "planar1", str(p)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("mindyn: error: ") and err.count("\n") == 1
    assert "line 4: time is not increasing" in err
    rc = cli.main(["identify", "planar1", str(tmp_path / "missing.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("mindyn: error: data file") and err.count("\n") == 1

"""The CSV reader's vectorised path against its strict cell-by-cell path: random logs, valid in
every spelling the grammar accepts and spoiled at random places, give the same arrays or the
same error through both; every short cell spelling is accepted by the fast path exactly when
the strict grammar accepts it, with the same value bit for bit."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from mindyn.identification import data as D
from mindyn.identification.data import DataError, read_csv


def _spell(x: float, rng) -> str:
    """``x`` in one of the spellings a cell may have."""
    k = int(rng.integers(9))
    if k == 0:
        return repr(x)
    if k == 1:
        return f"{x:.17e}".replace("e", "E")
    if k == 2:
        return f"{x:+.25f}"  # more digits than a double holds
    if k == 3:
        return f" \t{x:.6g} "
    if k == 4:
        mant, exp = f"{x:.20e}".split("e")
        return f"{mant}e{int(exp):+05d}"  # exponent with leading zeros
    if k == 5:
        s = f"{abs(x):.9f}"
        return ("-" if x < 0 else "") + ("0000" + s if abs(x) >= 1 else s.lstrip("0"))  # -.5
    if k == 6:
        return f"{int(round(x * 1000))}.e-3"  # digits, point, no fraction, exponent
    if k == 7:
        return f"{x * 1e6:.0f}e-6"  # digits and exponent, no point
    return f"{x:.3f}"


# malformed or refused cells, each refused by the strict grammar or by the CSV layout
_BAD = [
    "",
    " ",
    "1_000",
    "0x10",
    "nan",
    "-inf",
    "Infinity",
    "1e400",
    "-1e999",
    "1 2",
    "1e",
    "1e+",
    ".",
    "+",
    "--1",
    "1.2.3",
    "1e5e5",
    "e5",
    "+.e1",
    "\u0661",  # ARABIC-INDIC DIGIT ONE
    "1\u00a0",
    "abc",
    "#1",
    "1;2",
]
# spellings the strict path reads but the fast path may leave to it (same values expected)
_ODD = ['"1.5"', '" 2e1"', "1e-400", "-2.5e-330"]  # quoted; below the smallest double: zero


def _random_log(rng) -> str:
    """CSV text of a 2-joint log, valid or spoiled at random places."""
    n, m = 2, int(rng.integers(2, 40))
    header = ["t", "q1", "q2", "dq1", "dq2", "tau1", "tau2"]
    t = np.cumsum(rng.uniform(1e-3, 1e-2, m))
    vals = np.column_stack([t, rng.normal(scale=10.0 ** rng.integers(-3, 4), size=(m, 3 * n))])
    cells = [[_spell(float(v), rng) for v in row] for row in vals]
    for _ in range(int(rng.integers(0, 3))):
        r = int(rng.integers(m))
        c, k = int(rng.integers(len(cells[r]))), int(rng.integers(8))
        if k < 4:
            cells[r][c] = str(rng.choice(_BAD))
        elif k == 4:
            cells[r][c] = str(rng.choice(_ODD))
        elif k == 5:
            cells[r].append("1")  # a value too many
        elif k == 6:
            cells[r] = cells[r][:-1]  # a value too few
        elif r > 0:
            cells[r][0] = cells[r - 1][0]  # time not increasing
    lines = [",".join(header)] + [",".join(row) for row in cells]
    for _ in range(int(rng.integers(0, 2))):  # blank lines are skipped
        lines.insert(int(rng.integers(2, len(lines) + 1)), str(rng.choice(["", "", "", " \t"])))
    if rng.random() < 0.3:  # a comment, ASCII or not, before the header
        lines.insert(0, str(rng.choice(["# a comment", "# mesuré à 1 kHz, ±0.1 N m"])))
    end = str(rng.choice(["\n", "\r\n", "\r"], p=[0.6, 0.3, 0.1]))
    bom = "\ufeff" if rng.random() < 0.2 else ""
    return bom + end.join(lines) + (end if rng.random() < 0.7 else "")


def _read(path, strict: bool, monkeypatch):
    with monkeypatch.context() as mp:
        if strict:
            mp.setattr(D, "_fast_values", lambda *a: None)
        try:
            return read_csv(path, n=2, filter="none")
        except DataError as e:
            return str(e)


def test_fast_and_strict_paths_agree_on_random_logs(tmp_path, monkeypatch):
    rng = np.random.default_rng(7)
    fast_used = spoiled_count = 0
    calls = []
    real = D._fast_values

    def counting(*a):
        out = real(*a)
        calls.append(out is not None)
        return out

    monkeypatch.setattr(D, "_fast_values", counting)
    for k in range(300):
        text = _random_log(rng)
        path = tmp_path / f"log{k}.csv"
        path.write_bytes(text.encode())
        calls.clear()
        fast = _read(path, False, monkeypatch)
        fast_used += bool(calls and calls[0])
        strict = _read(path, True, monkeypatch)
        if isinstance(strict, str) or isinstance(fast, str):
            assert fast == strict, text
            assert not calls[0], text  # what the strict path refuses never passes the fast one
            spoiled_count += 1
            continue
        for name in ("t", "q", "dq", "ddq", "tau"):
            a, b = getattr(fast, name), getattr(strict, name)
            assert a.tobytes() == b.tobytes(), (name, text)
        assert fast.processing == strict.processing
    # both kinds were met in numbers: the comparison is not vacuous
    assert fast_used > 50 and spoiled_count > 80, (fast_used, spoiled_count)


def _cell_through_fast_path(cell: str):
    return D._fast_values(f"0,{cell}\n1,1\n".encode(), 2, 0)


def test_every_short_cell_spelling_is_accepted_exactly_as_the_grammar_says():
    accepted = 0
    for size in range(6):
        for chars in itertools.product("1.e+- ", repeat=size):
            cell = "".join(chars)
            try:
                want = D.parse_cell(cell, "x")
            except DataError:
                want = None
            got = _cell_through_fast_path(cell)
            if want is None:
                assert got is None, cell
            else:
                accepted += 1
                assert got is not None, cell
                assert got[0, 1].tobytes() == np.float64(want).tobytes(), cell
    assert accepted > 100


@pytest.mark.parametrize("cell", ["1E5", "1.5\t", "\t-2.e-1", "0.0000000000000000000000001"])
def test_other_spellings_take_the_fast_path(cell):
    got = _cell_through_fast_path(cell)
    assert got is not None and got[0, 1] == float(cell)


def test_hard_rounding_cases_are_bit_identical_to_float():
    rng = np.random.default_rng(3)
    cells = []
    for _ in range(20000):
        digits = "".join(rng.choice(list("0123456789"), size=int(rng.integers(1, 30))))
        cells.append(f"{digits[0]}.{digits[1:]}e{int(rng.integers(-320, 309))}")
    cells = [c for c in cells if np.isfinite(float(c))]
    text = "".join(f"{i},{c}\n" for i, c in enumerate(cells))
    got = D._fast_values(text.encode(), 2, 0)
    assert got is not None
    want = np.array([float(c) for c in cells])
    assert got[:, 1].tobytes() == want.tobytes()

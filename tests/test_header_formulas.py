"""The formulas in the comments of generated C and ST headers are written as `mindyn base`
writes them: coefficients without round-off digits, equal coefficients gathered. The expected
coefficients come from the PUMA 560's DH table (parallel-axis transfers of the masses carried
by the links), not from our output."""

from __future__ import annotations

import re

import mindyn
import pytest
from mindyn.cli import main
from mindyn.codegen import generate


def header_formulas(text: str) -> dict[str, str]:
    """The ``N. NAME = formula [value]`` entries of a generated header's comment, unwrapped."""
    parts = []
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("(*") and s.endswith("*)"):  # ST
            s = s[2:-2]
        parts.append(s.lstrip("/*").strip())  # C
    flat = re.sub(r"\s+", " ", " ".join(parts))
    return dict(re.findall(r"\d+\. (\w+) = (.*?) \[", flat))


@pytest.fixture(scope="module")
def puma():
    robot = mindyn.load("puma560")
    a, d = [row[0] for row in robot.dh], [row[2] for row in robot.dh]
    return robot, a, d


def expected(a, d) -> dict[str, str]:
    """Two formulas of the PUMA 560 in closed form (standard DH, joints 1..6): the masses of
    links 2..6 sit at distance a2 from joint 2's axis; links 3..6 regroup into link 1 with
    a2^2 - d3^2 + a3^2 (the lengths a3 along x3, d3 along z2 = z1 after joint 2)."""
    a2, a3, d3 = a[1], a[2], d[2]
    return {
        "XXR2": f"XX2 - YY2 + {a2**2:.10g}*(M2 + M3 + M4 + M5 + M6)",
        "YYR1_tail": f" - {a2**2 - d3**2 + a3**2:.10g}*(M3 + M4 + M5 + M6)",
    }


def test_closed_forms_are_the_base_set(puma):
    """The closed forms above are the regrouping the base set computes (to rounding)."""
    robot, a, d = puma
    bp = mindyn.base_parameters(robot)
    names, classical = bp.names, bp.classical_names
    Y = bp.Y
    xx2, yy1 = names.index("XXR2"), names.index("YYR1")
    for j in range(2, 7):
        assert Y[xx2, classical.index(f"M{j}")] == pytest.approx(a[1] ** 2, abs=1e-12)
    for j in range(3, 7):
        assert Y[yy1, classical.index(f"M{j}")] == pytest.approx(
            -(a[1] ** 2 - d[2] ** 2 + a[2] ** 2), abs=1e-12
        )


@pytest.mark.parametrize("lang", ["c", "st"])
def test_header_formulas_are_readable(puma, lang):
    robot, a, d = puma
    code = generate(robot, lang=lang, what="gravity")
    got = header_formulas(code.header if lang == "c" else code.text)
    want = expected(a, d)
    assert got["XXR2"] == want["XXR2"]
    assert got["YYR1"].endswith(want["YYR1_tail"]), got["YYR1"]
    # no coefficient keeps round-off digits (0.18645124000000002, 0.16434832749999997)
    for name, text in got.items():
        for number in re.findall(r"\d+\.\d+", text):
            assert len(number.replace(".", "").strip("0")) <= 12, (name, text)
    # the same text as mindyn base and BaseParameters.formulas
    bp = mindyn.base_parameters(robot)
    assert [f"{n} = {got[n]}" for n in bp.names] == bp.formulas


def test_cli_header_formulas(puma, tmp_path, capsys):
    robot, a, d = puma
    out = tmp_path / "puma"
    assert main(["codegen", "puma560", "--lang", "c", "-o", str(out)]) == 0
    capsys.readouterr()
    got = header_formulas((tmp_path / "puma.h").read_text())
    assert got["XXR2"] == expected(a, d)["XXR2"]

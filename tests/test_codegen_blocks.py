"""Structured Text and PLCopen XML from the blocks the C++ generator returns
(``GeneratedCode.program``): the blocks hold the whole program (a writer of this test, following
IEC 61131-3's syntax, gives back the generator's text from them, for several robots and every
kind of generated code), and the PLCopen XML written from them validates against the TC6 schema
and holds the same function blocks: the same variables, types and statements."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import mindyn
import pytest
from mindyn import codegen

XSD = Path(__file__).parent / "data" / "plcopen" / "tc6_xml_v201.xsd"
NS = {"x": codegen.PLCOPEN_NS, "h": "http://www.w3.org/1999/xhtml"}


def _decl(name: str, base: str, dims) -> str:
    if not dims:
        return f"  {name} : {base};\n"
    bounds = ", ".join(f"{lo}..{hi}" for lo, hi in dims)
    return f"  {name} : ARRAY[{bounds}] OF {base};\n"


def _block_text(name, sections, body) -> str:
    """One FUNCTION_BLOCK in IEC 61131-3 syntax: ``sections`` as (keyword, [(name, type,
    dims)]), VAR left out when empty."""
    out = f"FUNCTION_BLOCK {name}\n"
    for keyword, variables in sections:
        if keyword == "VAR" and not variables:
            continue
        out += keyword + "\n" + "".join(_decl(*v) for v in variables) + "END_VAR\n"
    return out + body + "END_FUNCTION_BLOCK\n"


def _text_of_program(program) -> str:
    """The Structured Text of the blocks, written here from their fields."""
    out = "".join(f"(* {c} *)\n" if c else "(* *)\n" for c in program.comments)
    for b in program.blocks:
        sections = [
            (kw, [(v.name, v.type, v.dims) for v in vs])
            for kw, vs in (("VAR_INPUT", b.inputs), ("VAR_OUTPUT", b.outputs), ("VAR", b.locals))
        ]
        body = (f"(* {b.note} *)\n" if b.note else "") + b.body
        out += "\n" + _block_text(b.name, sections, body)
    return out


def _codes():
    """Structured Text of several robots (a chain with motors coupling joints, a tree, a
    planar arm) and every kind: the dynamics functions (with parameters, baked in, offsets,
    classical parameters), the three controller steps and the momentum observer."""
    for name in ("planar2", "zcr07s", "puma560"):
        robot = mindyn.load(name)
        yield codegen.generate(robot, lang="st", rotor=True, friction=True)
        yield codegen.generate(robot, lang="st", what="id,gravity", numeric=True)
        yield codegen.generate(robot, lang="st", what="regressor", offset=True, base=False)
        for kind in codegen.CONTROLLERS:
            yield codegen.generate_controller(robot, kind, lang="st")
        yield codegen.generate_controller(robot, lang="st", gains={"kd": 2.0, "nu": 0.1})
        yield codegen.generate_observer(robot, lang="st")


def test_blocks_hold_the_generated_text():
    n = 0
    for code in _codes():
        assert _text_of_program(code.program) == code.text, code
        assert code.program.text() == code.text
        n += 1
    assert n == 24


def test_blocks_are_typed():
    robot = mindyn.load("puma560")
    reg = codegen.generate(robot, lang="st", what="regressor").program.blocks[0]
    assert [v.name for v in reg.inputs] == ["q", "dq", "ddq"]
    (w,) = reg.outputs
    base = mindyn.base_parameters(robot)
    assert (w.name, w.type, w.dims) == ("W", "LREAL", [(1, robot.n), (1, base.n)])
    assert w.declared_type == f"ARRAY[1..{robot.n}, 1..{base.n}] OF LREAL"
    ctl = codegen.generate_controller(robot, lang="st").program.blocks[0]
    reset = [v for v in ctl.inputs if v.name == "reset"][0]
    assert (reset.type, reset.dims) == ("BOOL", [])
    assert all(v.type in ("LREAL", "BOOL") for v in ctl.inputs + ctl.outputs + ctl.locals)
    assert codegen.generate(robot, lang="c").program is None


def _xml_block_text(pou) -> str:
    """A POU of the PLCopen XML back as a FUNCTION_BLOCK in Structured Text."""
    sections = []
    for keyword, tag in (
        ("VAR_INPUT", "inputVars"),
        ("VAR_OUTPUT", "outputVars"),
        ("VAR", "localVars"),
    ):
        variables = []
        for var in pou.findall(f"x:interface/x:{tag}/x:variable", NS):
            typ = var.find("x:type", NS)[0]
            if typ.tag == f"{{{codegen.PLCOPEN_NS}}}array":
                dims = [
                    (int(d.get("lower")), int(d.get("upper")))
                    for d in typ.findall("x:dimension", NS)
                ]
                base = typ.find("x:baseType", NS)[0].tag.split("}")[1]
            else:
                dims, base = [], typ.tag.split("}")[1]
            variables.append((var.get("name"), base, dims))
        sections.append((keyword, variables))
    return _block_text(pou.get("name"), sections, pou.find("x:body/x:ST/h:p", NS).text)


def test_plcopen_from_blocks_validates_and_holds_the_same_program(tmp_path):
    xmlschema = pytest.importorskip("xmlschema")
    robot = mindyn.load("zcr07s")
    base = mindyn.base_parameters(robot, rotor=True, friction=True)
    ctl = codegen.generate_controller(robot, lang="st", base=base)
    dyn = codegen.generate(robot, lang="st", base=base)
    obs = codegen.generate_observer(robot, lang="st", base=base)
    out = tmp_path / "project.xml"
    project = codegen.plcopen_project([ctl, dyn, obs.program], "zcr07s", comment="a test")
    out.write_bytes(project)
    xmlschema.XMLSchema(str(XSD)).validate(str(out))
    root = ET.parse(out).getroot()
    assert root.find("x:contentHeader", NS).get("name") == "zcr07s"
    assert root.find("x:contentHeader/x:Comment", NS).text == "a test"
    pous = root.findall("x:types/x:pous/x:pou", NS)
    blocks = [b for c in (ctl, dyn, obs) for b in c.program.blocks]
    assert [p.get("name") for p in pous] == [b.name for b in blocks]
    assert len(pous) == 5
    for pou, code in zip(pous, [ctl, dyn, dyn, dyn, obs]):
        # the function block as the Structured Text file has it, variables and statements
        assert "\n" + _xml_block_text(pou) in code.text, pou.get("name")
        doc = pou.find("x:documentation/h:p", NS).text
        assert doc.splitlines()[0] == code.program.comments[0]


@pytest.mark.parametrize("given", ["FUNCTION_BLOCK f\nEND_FUNCTION_BLOCK\n", "c"])
def test_plcopen_takes_generated_structured_text_only(given):
    code = given if given != "c" else codegen.generate("planar1", lang="c")
    with pytest.raises(mindyn.Error, match="Structured Text"):
        codegen.plcopen_project([code], "p")

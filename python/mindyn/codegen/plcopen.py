"""PLCopen XML (IEC 61131-10 / TC6 XML v2.01) projects of generated Structured Text: every
function block written from the blocks the C++ generator returns (:class:`mindyn._core.STProgram`:
typed variables per section, the statements), the same program as the Structured Text text."""

from __future__ import annotations

from collections.abc import Sequence

from .. import _args, _core
from .generation import GeneratedCode

__all__ = ["PLCOPEN_NS", "plcopen_project"]

PLCOPEN_NS = "http://www.plcopen.org/xml/tc6_0201"
_XHTML_NS = "http://www.w3.org/1999/xhtml"
#: The interface element of each variable section of a function block.
_SECTIONS = (("inputs", "inputVars"), ("outputs", "outputVars"), ("locals", "localVars"))


def _program(code, i: int) -> _core.STProgram:
    """The blocks of generated Structured Text: a :class:`GeneratedCode` in ``lang="st"`` or an
    :class:`mindyn._core.STProgram` (entry ``i`` of ``codes``)."""
    if isinstance(code, _core.STProgram):
        return code
    if isinstance(code, GeneratedCode) and code.program is not None:
        return code.program
    if isinstance(code, GeneratedCode):
        raise _args.fail(
            "codes", f"entry {i} is {code.lang!r} code; expected Structured Text (lang='st')"
        )
    raise _args.fail(
        "codes",
        f"entry {i} is a {type(code).__name__}; expected generated Structured Text (the "
        "GeneratedCode of lang='st', or its program)",
    )


def plcopen_project(codes: Sequence, project: str, *, comment: str = "") -> bytes:
    """A PLCopen XML (TC6 XML v2.01) project with the FUNCTION_BLOCKs of generated Structured
    Text as POUs (interface variables typed, bodies in ``<ST><xhtml:p>``, the comments before
    the blocks as each POU's documentation), ready for import into CODESYS and other IEC 61131-3
    tools. ``codes``: the :class:`GeneratedCode` (``lang="st"``) of :func:`generate`,
    :func:`generate_controller` or :func:`generate_observer`, or their ``program``. Returns
    UTF-8 XML bytes."""
    import datetime
    import xml.etree.ElementTree as ET

    if isinstance(codes, (str, bytes)) or not isinstance(codes, Sequence) or not codes:
        raise _args.fail("codes", "must be a non-empty list of generated Structured Text")
    programs = [_program(c, i) for i, c in enumerate(codes)]
    _args.text(project, "project")
    _args.text(comment, "comment", empty=True)
    ET.register_namespace("", PLCOPEN_NS)
    ET.register_namespace("xhtml", _XHTML_NS)

    def el(parent, tag, **attrs):
        return ET.SubElement(parent, f"{{{PLCOPEN_NS}}}{tag}", attrs)

    now = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat()
    root = ET.Element(f"{{{PLCOPEN_NS}}}project")
    from .._version import __version__

    el(
        root,
        "fileHeader",
        companyName="mindyn",
        productName="mindyn",
        productVersion=str(__version__),
        creationDateTime=now,
        contentDescription="generated robot dynamics and controllers",
    )
    header = el(root, "contentHeader", name=project, modificationDateTime=now)
    if comment:
        el(header, "Comment").text = comment
    coord = el(header, "coordinateInfo")
    for lang in ("fbd", "ld", "sfc"):
        el(el(coord, lang), "scaling", x="1", y="1")
    types = el(root, "types")
    el(types, "dataTypes")
    pous = el(types, "pous")
    for program in programs:
        notes = "\n".join(program.comments).strip()
        for fb in program.blocks:
            pou = el(pous, "pou", name=fb.name, pouType="functionBlock")
            interface = el(pou, "interface")
            for attr, tag in _SECTIONS:
                variables = getattr(fb, attr)
                if not variables:
                    continue
                section = el(interface, tag)
                for var in variables:
                    typ = el(el(section, "variable", name=var.name), "type")
                    if var.dims:
                        arr = el(typ, "array")
                        for lo, hi in var.dims:
                            el(arr, "dimension", lower=str(lo), upper=str(hi))
                        el(el(arr, "baseType"), var.type)
                    else:
                        el(typ, var.type)
            st = el(el(pou, "body"), "ST")
            note = f"(* {fb.note} *)\n" if fb.note else ""
            ET.SubElement(st, f"{{{_XHTML_NS}}}p").text = note + fb.body
            if notes:
                doc = el(pou, "documentation")
                ET.SubElement(doc, f"{{{_XHTML_NS}}}p").text = notes
    el(el(root, "instances"), "configurations")
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)

"""URDF transmissions written in forms ros_control's loaders do not take as such, but which
descriptions in use write: rewritten into the form the reader takes, on the same lines (so that
every later message names the line of the file), with a note per form.

- ROS 1 (``<transmission>`` in ``<robot>``, ``transmission_interface/...``): an ``<actuator>``
  without ``<mechanicalReduction>`` (Franka's and other Gazebo descriptions, whose simulator
  ignores the reduction) has reduction 1; a SimpleTransmission whose reduction sits in its
  ``<joint>`` alone has that reduction (ros_control reads the actuator's).
- ROS 2 (``<transmission>`` in ``<ros2_control>``): a SimpleTransmission whose reduction sits in
  its ``<actuator>`` alone has that reduction (ros2_control reads the joint's); a
  ``<param name="mechanical_reduction">`` or ``<param name="offset">`` in a ``<joint>`` or
  ``<actuator>`` is read as the ``<mechanical_reduction>`` or ``<offset>`` element
  (ros2_control reads the elements only, and 1 and 0 without them).
"""

from __future__ import annotations

import xml.parsers.expat
from dataclasses import dataclass, field

_TYPES = {
    "transmission_interface/SimpleTransmission": 1,
    "transmission_interface/DifferentialTransmission": 2,
    "transmission_interface/FourBarLinkageTransmission": 2,
}
_REDUCTIONS = ("mechanicalReduction", "mechanical_reduction")


@dataclass
class _Element:
    tag: str
    attrs: dict
    start: int  # byte offset of '<tag'
    line: int
    children: list = field(default_factory=list)
    text: str = ""
    end: int = -1  # byte offset just past the element

    def child(self, *tags: str) -> _Element | None:
        return next((c for c in self.children if c.tag in tags), None)


def _tree(data: bytes) -> _Element | None:
    """The element tree of ``data`` with byte offsets, or None when it is no XML (the URDF
    reader reports that)."""
    parser = xml.parsers.expat.ParserCreate()
    stack: list[_Element] = []
    top: list[_Element] = []

    def start(tag, attrs):
        e = _Element(tag, attrs, parser.CurrentByteIndex, parser.CurrentLineNumber)
        (stack[-1].children if stack else top).append(e)
        stack.append(e)

    def end(tag):
        e = stack.pop()
        at = parser.CurrentByteIndex
        close = _start_tag_end(data, e)
        e.end = close + 1 if data[close - 1] == 0x2F else data.index(b">", at) + 1

    def chars(text):
        if stack:
            stack[-1].text += text

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    try:
        parser.Parse(data, True)
    except (xml.parsers.expat.ExpatError, ValueError):
        return None
    return top[0] if top else None


def _start_tag_end(data: bytes, e: _Element) -> int:
    """The offset of the '>' closing the start tag of ``e`` (a '>' in a quoted attribute value
    is skipped)."""
    quote = 0
    for i in range(e.start, len(data)):
        c = data[i]
        if quote:
            quote = 0 if c == quote else quote
        elif c in (0x22, 0x27):
            quote = c
        elif c == 0x3E:
            return i
    return len(data) - 1


class _Edits:
    def __init__(self, data: bytes):
        self.data = data
        self.edits: list[tuple[int, int, bytes]] = []

    def add_child(self, e: _Element, xml_text: str) -> None:
        """Puts ``xml_text`` first inside element ``e`` (no line break: lines are kept)."""
        close = _start_tag_end(self.data, e)
        body = xml_text.encode()
        if self.data[close - 1] == 0x2F:  # <tag .../>
            self.edits.append((close - 1, close + 1, b">" + body + f"</{e.tag}>".encode()))
        else:
            self.edits.append((close + 1, close + 1, body))

    def remove(self, e: _Element) -> None:
        """Removes element ``e``, keeping its line breaks."""
        self.edits.append((e.start, e.end, b"\n" * self.data[e.start : e.end].count(b"\n")))

    def apply(self) -> bytes:
        out = self.data
        for a, b, text in sorted(self.edits, reverse=True):
            out = out[:a] + text + out[b:]
        return out


def _escaped(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _param(e: _Element, name: str) -> _Element | None:
    return next(
        (c for c in e.children if c.tag == "param" and c.attrs.get("name", "").strip() == name),
        None,
    )


def _ros1(t: _Element, count: int, edits: _Edits, notes: dict[str, list[str]]) -> None:
    where = f"'{t.attrs.get('name', '')}' (line {t.line})"
    actuators = [c for c in t.children if c.tag == "actuator"]
    joints = [c for c in t.children if c.tag == "joint"]
    own = t.child(*_REDUCTIONS)  # PR2's place for it
    if own is not None and (count != 1 or len(actuators) != 1):
        return  # refused by the reader, naming the actuator
    for a in actuators:
        if a.child(*_REDUCTIONS) is not None:
            continue
        moved = joints[0].child(*_REDUCTIONS) if count == 1 and len(joints) == 1 else None
        if own is not None and moved is None:
            edits.remove(own)
            edits.add_child(a, f"<mechanicalReduction>{_escaped(own.text)}</mechanicalReduction>")
            notes["transmission"].append(where)
            continue
        if moved is not None:
            edits.remove(moved)
            edits.add_child(a, f"<mechanicalReduction>{_escaped(moved.text)}</mechanicalReduction>")
            notes["joint"].append(where)
        else:
            edits.add_child(a, "<mechanicalReduction>1</mechanicalReduction>")
            notes["none"].append(where)


def _value(m: _Element, name: str) -> _Element | None:
    """The element, else the ``<param name=...>``, giving ``name`` in joint or actuator ``m``."""
    el = m.child(name, *(_REDUCTIONS if name == "mechanical_reduction" else ()))
    return el if el is not None else _param(m, name)


def _ros2(t: _Element, count: int, edits: _Edits, notes: dict[str, list[str]]) -> None:
    where = f"'{t.attrs.get('name', '')}' (line {t.line})"
    joints = [c for c in t.children if c.tag == "joint"]
    actuators = [c for c in t.children if c.tag == "actuator"]
    moved = None
    if count == 1 and len(joints) == 1 and len(actuators) == 1:
        if _value(joints[0], "mechanical_reduction") is None:
            moved = _value(actuators[0], "mechanical_reduction")
            if moved is None:  # a <param> of the transmission itself
                moved = _param(t, "mechanical_reduction")
        if moved is not None:
            edits.remove(moved)
            text = _escaped(moved.text)
            edits.add_child(joints[0], f"<mechanical_reduction>{text}</mechanical_reduction>")
            notes["actuator"].append(where)
    for m in joints + actuators:
        for name in ("mechanical_reduction", "offset"):
            p = _param(m, name)
            if p is None or p is moved or _value(m, name) is not p:
                continue
            edits.remove(p)
            edits.add_child(m, f"<{name}>{_escaped(p.text)}</{name}>")
            notes["param"].append(f'{where} <{m.tag} name="{m.attrs.get("name", "")}">')


def _signature(t: _Element) -> tuple:
    """What transmission ``t`` says but its hardware interfaces (and white space)."""

    def of(e: _Element) -> tuple:
        kept = [c for c in e.children if c.tag != "hardwareInterface"]
        return (e.tag, tuple(sorted(e.attrs.items())), e.text.strip(), tuple(map(of, kept)))

    return of(t)


_SAID = {
    "repeated": "a transmission declared again with the same name, joints, actuators and "
    "reductions, differing at most in its <hardwareInterface> (one per interface, as Franka's "
    "Gazebo descriptions write them), is read once",
    "none": "an <actuator> without <mechanicalReduction> has reduction 1 (ros_control's loaders "
    "require one; Gazebo's ros_control plugin runs such a joint at ratio 1)",
    "transmission": "a SimpleTransmission's <mechanicalReduction> written in <transmission> "
    "(PR2's place) is its reduction (ros_control reads the <actuator>'s)",
    "joint": "a SimpleTransmission's <mechanicalReduction> written in its <joint> alone is its "
    "reduction (ros_control reads the <actuator>'s)",
    "actuator": "a ros2_control SimpleTransmission's <mechanical_reduction> written in its "
    "<actuator> (or as a <param> of <transmission>) alone is its reduction (ros2_control "
    "reads the <joint>'s, 1 without one)",
    "param": 'a <param name="mechanical_reduction"> or <param name="offset"> is read as the '
    "<mechanical_reduction> or <offset> element (ros2_control reads the elements only: 1 and 0 "
    "without them)",
}


def normalise(data: bytes, source: str) -> tuple[str, str]:
    """The URDF text ``data`` with its transmissions in the form the reader takes and the note
    on the forms rewritten (one line), or ``("", "")`` when nothing is rewritten (or the text is
    no UTF-8 XML: the reader reports that)."""
    if b"transmission" not in data:
        return "", ""
    root = _tree(data)
    if root is None or root.tag != "robot":
        return "", ""
    edits = _Edits(data)
    notes: dict[str, list[str]] = {k: [] for k in _SAID}
    seen: dict[str, tuple] = {}
    for e in root.children:
        groups = [(e, False)] if e.tag == "transmission" else []
        if e.tag == "ros2_control":
            groups = [(t, True) for t in e.children if t.tag == "transmission"]
        for t, ros2 in groups:
            name = t.attrs.get("name", "")
            if seen.get(name, ()) == _signature(t):  # declared again per hardware interface
                edits.remove(t)
                notes["repeated"].append(f"'{name}' (line {t.line})")
                continue
            seen.setdefault(name, _signature(t))
            kind = t.child("plugin" if ros2 else "type")
            count = _TYPES.get(kind.text.strip() if kind is not None else "")
            if count is not None:
                (_ros2 if ros2 else _ros1)(t, count, edits, notes)
    if not edits.edits:
        return "", ""
    try:
        text = edits.apply().decode("utf-8")
    except UnicodeDecodeError:
        return "", ""
    said = "; ".join(f"{_SAID[k]}: {', '.join(v)}" for k, v in notes.items() if v)
    return (
        text,
        f"{source}: transmissions read in a form ros_control does not take as written: {said}",
    )

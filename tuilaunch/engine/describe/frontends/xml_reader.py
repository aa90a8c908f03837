"""XML launch files read with expat, each tag keeping its line and column."""

from __future__ import annotations

import bisect
import re
from xml.parsers import expat

from ...errors import DslError, Origin
from .element import XmlElement

_ATTRIBUTE = re.compile(rb"""\s([^\s=/>"']+)\s*=\s*(?:"[^"]*"|'[^']*')""")
_START_TAG_END = re.compile(rb"""(?:"[^"]*"|'[^']*'|[^"'>])*>""")


class _Positions:
    """Byte offsets to 1-based (line, column), columns counted in characters."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.line_starts = [0] + [m.end() for m in re.finditer(rb"\n", data)]

    def at(self, offset: int) -> tuple[int, int]:
        line = bisect.bisect_right(self.line_starts, offset)
        start = self.line_starts[line - 1]
        return line, len(self.data[start:offset].decode("utf-8", "replace")) + 1

    def attributes(self, tag_offset: int) -> dict[str, tuple[int, int]]:
        """Where each attribute of the start tag at this offset is written (expat does not
        say; errors about an attribute should point at it)."""
        end = _START_TAG_END.match(self.data, tag_offset)
        if end is None:
            return {}
        return {m.group(1).decode("utf-8", "replace"): self.at(m.start(1))
                for m in _ATTRIBUTE.finditer(self.data, tag_offset, end.end())}


def read_xml(text: str, path: str) -> XmlElement:
    """The root element of an XML launch file; a malformed file is one clear error."""
    parser = expat.ParserCreate()
    stack: list[XmlElement] = []
    roots: list[XmlElement] = []
    data = text.encode("utf-8")
    positions = _Positions(data)

    def start(tag: str, attributes: dict[str, str]) -> None:
        # expat columns count from 0; editors and compilers count from 1
        origin = Origin(path, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        element = XmlElement(tag, origin, dict(attributes), [])
        element.attribute_origins = {
            name: Origin(path, line, column)
            for name, (line, column) in positions.attributes(parser.CurrentByteIndex).items()}
        (stack[-1].elements if stack else roots).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        reason = expat.ErrorString(exc.code)
        raise DslError(f"not well-formed XML: {reason}",
                       Origin(path, exc.lineno, exc.offset + 1),
                       hint="check for an unclosed tag, a missing quote, or a bare & or < "
                       "(write &amp; and &lt;)") from None
    if not roots:
        raise DslError("the XML file has no root tag", Origin(path, 1, 1))
    root = roots[0]
    if root.tag != "launch":
        raise DslError(f"the root tag is <{root.tag}>, expected <launch>", root.origin,
                       hint="an XML launch file is <launch> ... </launch>")
    return root

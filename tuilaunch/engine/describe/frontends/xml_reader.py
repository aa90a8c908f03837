"""XML launch files read with expat, each tag keeping its line and column."""

from __future__ import annotations

from xml.parsers import expat

from ...errors import DslError, Origin
from .element import XmlElement


def read_xml(text: str, path: str) -> XmlElement:
    """The root element of an XML launch file; a malformed file is one clear error."""
    parser = expat.ParserCreate()
    stack: list[XmlElement] = []
    roots: list[XmlElement] = []

    def start(tag: str, attributes: dict[str, str]) -> None:
        # expat columns count from 0; editors and compilers count from 1
        origin = Origin(path, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        element = XmlElement(tag, origin, dict(attributes), [])
        (stack[-1].elements if stack else roots).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(text.encode("utf-8"), True)
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

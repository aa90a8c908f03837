"""XML and YAML launch files (launch's frontends) read into the same Description as Python.

`xml_reader` and `yaml_reader` turn a file into `Element`s that remember where they were
written; `walker` maps those onto the entities of `describe.entities`; `subst_parser` reads
the `$(...)` substitutions in attribute values. Nothing below `describe` knows the format.
"""

from __future__ import annotations

import os

from ...errors import LaunchError, Origin

XML_SUFFIXES = (".xml",)
YAML_SUFFIXES = (".yaml", ".yml")


def frontend_of(path: str) -> str | None:
    """'xml', 'yaml', or None for a Python file, chosen as launch does: by the extension.

    A ROS 1 style `.launch` file may be either; its first character decides.
    """
    lowered = path.lower()
    if lowered.endswith(XML_SUFFIXES):
        return "xml"
    if lowered.endswith(YAML_SUFFIXES):
        return "yaml"
    if lowered.endswith(".launch"):
        try:
            with open(path, encoding="utf-8") as handle:
                start = handle.read(256).lstrip()
        except (OSError, UnicodeDecodeError):
            return "xml"
        return "xml" if start.startswith("<") else "yaml"
    return None


def load_frontend_file(path: str, kind: str, origin: Origin | None = None) -> list[object]:
    """The top-level entities of an XML or YAML launch file."""
    from .element import Element
    from .walker import Walker

    try:
        with open(path, encoding="utf-8") as handle:
            text = handle.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise LaunchError(f"cannot read {path}: {exc}", origin) from None
    root: Element
    if kind == "xml":
        from .xml_reader import read_xml

        root = read_xml(text, os.path.abspath(path))
    else:
        from .yaml_reader import read_yaml

        root = read_yaml(text, os.path.abspath(path))
    return Walker(os.path.abspath(path)).description(root)


__all__ = ["frontend_of", "load_frontend_file"]

"""A FEBio file as a tree of XML elements that know their line (``xml.parsers.expat``), so
that every refusal can name the element and where it is."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from xml.parsers import expat

from tissuesim.errors import InputError

__all__ = ["FebError", "Node", "parse_feb"]


class FebError(InputError):
    """A FEBio file tissuesim cannot read or does not support (one line: file, element, line)."""


class Attributes(dict):
    """An element's attributes, remembering which ones the reader looked at (``get``, ``[]``,
    ``in``): after reading, one that was never looked at was dropped (a misspelt ``lcc="1"``),
    and ``read_feb`` refuses it."""

    #: the keys looked at; set on the instance at the first look (no __init__: a million
    #: <node>s are made with dict's own, and each keeps a small tuple)
    read: tuple[str, ...] = ()

    def _mark(self, key: object) -> None:
        if key not in self.read and isinstance(key, str):
            self.read = (*self.read, key)

    def __getitem__(self, key: str) -> str:
        self._mark(key)
        return super().__getitem__(key)

    def get(self, key: str, default=None):
        self._mark(key)
        return super().get(key, default)

    def __contains__(self, key: object) -> bool:
        self._mark(key)
        return super().__contains__(key)

    def unread(self) -> list[str]:
        """The attributes never looked at, in the file's order."""
        return [k for k in self.keys() if k not in self.read]


@dataclass
class Node:
    """One XML element: its tag, attributes, text (stripped), children and line."""

    tag: str
    attrib: dict[str, str]
    line: int
    source: str
    text: str = ""
    children: list[Node] = field(default_factory=list)

    def where(self) -> str:
        """``file:line <tag>``, the prefix of every message about this element."""
        return f"{self.source}:{self.line} <{self.tag}>"

    def error(self, message: str) -> FebError:
        """A FebError naming this element and its line."""
        return FebError(f"{self.where()}: {message}")

    def find(self, tag: str) -> Node | None:
        """The first child with this tag, or None."""
        return next((c for c in self.children if c.tag == tag), None)


def parse_feb(path: str | os.PathLike[str], root_tag: str = "febio_spec") -> Node:
    """Parse a ``.feb`` file into Nodes with line numbers; FebError for a file that is not
    well-formed XML (naming the line) or whose root is not ``<root_tag>`` (a model's
    ``<febio_spec>``; an optimisation's ``<febio_optimize>``)."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise FebError(f"{path}: cannot read the FEBio file ({exc.strerror})") from None
    parser = expat.ParserCreate()
    # expat hands text over in chunks (one per line, and at its buffer's edges): joined once
    # per element, so reading is linear in the file's size (appending each chunk to the
    # element's string copied it every time: a 200k-id set one id per line took 20 s)
    parser.buffer_text = True
    parser.buffer_size = 1 << 16
    stack: list[Node] = []
    chunks: list[list[str]] = []  # the text chunks of each element on the stack
    root: list[Node] = []

    def start(tag: str, attrib: dict[str, str]) -> None:
        node = Node(tag, Attributes(attrib), parser.CurrentLineNumber, path)
        (stack[-1].children if stack else root).append(node)
        stack.append(node)
        chunks.append([])

    def end(tag: str) -> None:
        node = stack.pop()
        text = chunks.pop()
        node.text = "".join(text).strip() if text else ""

    def chars(text: str) -> None:
        if chunks:
            chunks[-1].append(text)

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise FebError(
            f"{path}:{exc.lineno}: not well-formed XML ({expat.ErrorString(exc.code)})"
        ) from None
    except LookupError:  # the declaration names an encoding Python does not know
        found = re.search(rb"encoding\s*=\s*[\"']([^\"']*)", data[:400])
        name = found.group(1).decode("ascii", "replace") if found else "?"
        raise FebError(
            f"{path}:{parser.CurrentLineNumber} <?xml?>: unknown encoding {name!r}; save the "
            'file as UTF-8 and declare encoding="UTF-8" (or "ISO-8859-1")'
        ) from None
    if not root or root[0].tag != root_tag:
        tag = root[0].tag if root else "nothing"
        if tag == "febio_optimize":
            raise FebError(
                f"{path}: a FEBio optimisation file (<febio_optimize>), not a model: run it "
                "with its model, tissuesim run OPTIMISATION.feb --model MODEL.feb (FEBio's "
                "-s and -i)"
            )
        raise FebError(f"{path}: not a FEBio file: the root element is <{tag}>, not <{root_tag}>")
    return root[0]

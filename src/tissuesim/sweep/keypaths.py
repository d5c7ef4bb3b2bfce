"""Scene keys by their path in the scene's TOML tables: ``material.youngs_modulus`` (a one-body
scene), ``bodies[0].material.youngs_modulus`` (an array of tables by index),
``obstacles[probe].translation`` (by the table's ``name``), ``obstacles[probe].translation[2]``
(one component of a vector). A path names a key the scene already has: a misspelt key is an
error that names the table and suggests the nearest key, never a new key set silently."""

from __future__ import annotations

import difflib
import re
from typing import Any

from tissuesim.errors import InputError

__all__ = ["KeyPath", "parse_key_path"]

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_BRACKET = re.compile(r"\[([^\[\]]+)\]")


class KeyPath:
    """A parsed key path: ``parts`` are str (a table key, or a table's ``name`` in an array of
    tables when it came in brackets) or int (an index)."""

    def __init__(self, text: str, parts: list[tuple[str, str | int]]) -> None:
        self.text = text
        self.parts = parts  # ("key", name) | ("index", i) | ("name", name)

    def __repr__(self) -> str:
        return f"KeyPath({self.text!r})"

    def get(self, data: dict) -> Any:
        """The value at this path in the scene ``data``; InputError naming the part that is
        not there and how to fix it."""
        node: Any = data
        where = "the scene's top level"
        for kind, part in self.parts:
            node, where = _step(node, kind, part, where, self.text)
        return node

    def set(self, data: dict, value: Any) -> None:
        """Put ``value`` at this path in ``data`` (changed in place; the path must exist)."""
        node: Any = data
        where = "the scene's top level"
        for kind, part in self.parts[:-1]:
            node, where = _step(node, kind, part, where, self.text)
        kind, part = self.parts[-1]
        _step(node, kind, part, where, self.text)  # checks that it is there
        if kind == "name":
            node[_named(node, part, where, self.text)] = value
        else:
            node[part] = value


def parse_key_path(text: str) -> KeyPath:
    """``a.b[0].c[name]`` -> a KeyPath; InputError for a malformed path."""
    text = text.strip()
    parts: list[tuple[str, str | int]] = []
    pos = 0
    while pos < len(text):
        if text[pos] == "[" and parts:
            m = _BRACKET.match(text, pos)
        else:
            if parts:
                pos += text[pos] == "."
                if pos == len(text) or text[pos - 1] != ".":
                    m = None
                else:
                    m = _NAME.match(text, pos)
            else:
                m = _NAME.match(text, pos)
        if m is None:
            raise InputError(
                f"--vary {text}: not a key path at character {pos + 1}; write keys joined by "
                "dots, an array of tables' entry by index or name in brackets, e.g. "
                "material.youngs_modulus, bodies[0].material.youngs_modulus, "
                "obstacles[probe].translation[2]"
            )
        if m.re is _NAME:
            parts.append(("key", m.group(0)))
        else:
            inner = m.group(1).strip().strip("'\"")
            if re.fullmatch(r"-?\d+", inner):
                parts.append(("index", int(inner)))
            else:
                parts.append(("name", inner))
        pos = m.end()
    if not parts or parts[0][0] != "key":
        raise InputError(
            f"--vary {text}: a key path starts with a table or key name, e.g. "
            "material.youngs_modulus"
        )
    return KeyPath(text, parts)


def _step(node: Any, kind: str, part: str | int, where: str, path: str) -> tuple[Any, str]:
    if kind == "key":
        if not isinstance(node, dict):
            raise InputError(
                f"--vary {path}: {where} is not a table, so it has no key {part!r}"
                + ("; pick one entry first, by index [0] or name [NAME]" if _is_list(node) else "")
            )
        if part not in node:
            close = difflib.get_close_matches(str(part), sorted(node), n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"its keys: {sorted(node)}"
            raise InputError(
                f"--vary {path}: {where} has no key {part!r}; {hint} (a key the scene leaves "
                "at its default must be written in the scene to be varied)"
            )
        return node[part], f"[{part}]" if where.startswith("the scene") else f"{where}.{part}"
    if not _is_list(node):
        raise InputError(f"--vary {path}: {where} is not an array, so [{part}] selects nothing")
    if kind == "index":
        if not -len(node) <= int(part) < len(node):
            raise InputError(
                f"--vary {path}: {where} has {len(node)} entries, so [{part}] is out of range "
                f"(0 to {len(node) - 1})"
            )
        return node[int(part)], f"{where}[{part}]"
    return node[_named(node, str(part), where, path)], f"{where}[{part}]"


def _named(node: list, name: str, where: str, path: str) -> int:
    names = [item.get("name") if isinstance(item, dict) else None for item in node]
    if name in names:
        return names.index(name)
    known = [n for n in names if n is not None]
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"did you mean {close[0]!r}?" if close else f"names there: {known or 'none'}"
    raise InputError(
        f"--vary {path}: {where} has no entry named {name!r}; {hint} (or select by index, [0])"
    )


def _is_list(node: Any) -> bool:
    return isinstance(node, list)

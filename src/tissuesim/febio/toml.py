"""A small TOML writer for the scenes ``convert`` writes (tables, arrays of tables, inline
tables, strings, numbers, booleans and lists of them)."""

from __future__ import annotations

import json
import math

__all__ = ["dumps"]


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if v == math.inf:  # an open-ended time window
            return "inf"
        if not math.isfinite(v):
            raise ValueError(f"a scene value must be finite, not {v}")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string: JSON's escapes are TOML's
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _key(k: str) -> str:
    bare = k and all(c.isalnum() or c in "_-" for c in k)
    return k if bare else json.dumps(k)


def _is_table_array(v) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def _table(lines: list[str], prefix: str, data: dict, array: bool = False) -> None:
    if prefix:
        lines.append(f"[[{prefix}]]" if array else f"[{prefix}]")
    nested = []
    for k, v in data.items():
        if isinstance(v, dict) and not _inline(k, v) or _is_table_array(v):
            nested.append((k, v))
        else:
            lines.append(f"{_key(k)} = {_value(v)}")
    for k, v in nested:
        name = f"{prefix}.{_key(k)}" if prefix else _key(k)
        lines.append("")
        if isinstance(v, dict):
            _table(lines, name, v)
        else:
            for i, item in enumerate(v):
                if i:
                    lines.append("")
                _table(lines, name, item, array=True)


def _inline(key: str, value: dict) -> bool:
    """Selectors, shapes and surfaces stay inline (``vertices = { tagged = "left" }``)."""
    return key not in ("simulation", "material", "mesh", "gravity", "run", "contact", "newton")


def dumps(data: dict, comments: list[str] = ()) -> str:
    """``data`` as TOML text, ``comments`` as ``#`` lines at the top."""
    lines = [f"# {c}" for c in comments]
    if lines:
        lines.append("")
    _table(lines, "", data)
    return "\n".join(lines).strip() + "\n"

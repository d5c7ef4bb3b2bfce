"""Atomic file writes: a reader (or a crash) sees the old file or the new one, never half of one.

Every writer here writes to a hidden temporary file in the target's directory, flushes and
fsyncs it, then ``os.replace``-s it over the target (atomic on POSIX and Windows within one
file system). A crash can leave a hidden ``.{stem}.tmp-XXXX{suffix}`` file behind, never a torn
target. Temporary names keep the target's suffix, so tools that infer the format from the
extension (Pillow, meshio, matplotlib) still work on them; the next run into the directory
removes such leftovers (``remove_leftovers``).
"""

from __future__ import annotations

import json
import math
import os
import re
import secrets
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "atomic_output",
    "atomic_outputs",
    "remove_leftovers",
    "to_json_compatible",
    "write_json_atomic",
    "write_text_atomic",
]

#: the temporary files of these writers (``_tmp_path``): only they match it
_LEFTOVER = re.compile(r"\..+\.tmp-[0-9a-f]{8}(\.[A-Za-z0-9]+)?")


def _tmp_path(path: Path) -> Path:
    return path.with_name(f".{path.stem}.tmp-{secrets.token_hex(4)}{path.suffix}")


def remove_leftovers(directory: str | os.PathLike[str]) -> list[str]:
    """Delete the temporary files a killed writer left in ``directory`` (hidden, named as
    ``_tmp_path`` names them, nothing else); returns their names."""
    removed = []
    for path in Path(directory).glob(".*.tmp-*"):
        if _LEFTOVER.fullmatch(path.name) and path.is_file():
            path.unlink(missing_ok=True)
            removed.append(path.name)
    return removed


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(directory: Path) -> None:
    try:  # makes the rename itself durable; not possible on every platform
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextmanager
def atomic_output(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success fsync it and move it onto ``path``.

    The caller writes the whole file to the yielded path (with any library). If the body raises,
    the temporary file is removed and ``path`` is left untouched.
    """
    target = Path(path)
    tmp = _tmp_path(target)
    try:
        yield tmp
        _fsync_file(tmp)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync_dir(target.parent)


@contextmanager
def atomic_outputs(paths: list[Path]) -> Iterator[list[Path]]:
    """``atomic_output`` for files that belong together (a scene and its meshes): yield one
    temporary path per target; on success all of them replace their targets, and if anything
    fails (writing, or moving one into place) every target is left as it was before.

    Moving several files is not one operation: the old targets are first moved aside to
    hidden names, the new files moved in, and the old ones deleted only once all are in; a
    failure moves the old ones back. A crash in that short window can leave hidden leftovers
    (``remove_leftovers``), never a new file beside an old one silently."""
    targets = [Path(p) for p in paths]
    tmps = [_tmp_path(t) for t in targets]
    saved: list[tuple[Path, Path]] = []  # (target, where its old file was moved)
    placed: list[Path] = []
    try:
        yield tmps
        for tmp in tmps:
            _fsync_file(tmp)
        for target, tmp in zip(targets, tmps, strict=True):
            if target.exists():
                aside = _tmp_path(target)
                os.replace(target, aside)
                saved.append((target, aside))
            os.replace(tmp, target)
            placed.append(target)
    except BaseException:
        for target in placed:
            target.unlink(missing_ok=True)
        for target, aside in saved:
            os.replace(aside, target)
        for tmp in tmps:
            tmp.unlink(missing_ok=True)
        raise
    for _, aside in saved:
        aside.unlink(missing_ok=True)
    for directory in {t.parent for t in targets}:
        _fsync_dir(directory)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; return the path."""
    target = Path(path)
    with atomic_output(target) as tmp, open(tmp, "w", encoding="utf-8", newline="") as f:
        f.write(text)
        f.flush()
    return target


def to_json_compatible(obj: Any) -> Any:
    """Convert ``obj`` to plain Python for strict JSON.

    numpy scalars and arrays become Python numbers and (nested) lists, tuples become lists,
    ``Path`` becomes ``str``, mapping keys become ``str``, and non-finite floats (NaN, +-inf)
    become ``None`` (JSON ``null``), because strict JSON has no NaN or Infinity.
    """
    if isinstance(obj, Mapping):
        return {str(k): to_json_compatible(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return to_json_compatible(obj.tolist())
    if isinstance(obj, np.generic):
        return to_json_compatible(obj.item())
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [to_json_compatible(v) for v in obj]
    if isinstance(obj, bool) or obj is None or isinstance(obj, (int, str)):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if isinstance(obj, complex):
        raise TypeError(f"cannot write complex number {obj!r} as JSON; store real and imag parts")
    raise TypeError(f"cannot write {type(obj).__name__} as JSON; convert it to plain data first")


def write_json_atomic(path: str | os.PathLike[str], obj: Any, *, indent: int | None = 2) -> Path:
    """Write ``obj`` as strict JSON to ``path`` atomically; return the path.

    numpy scalars/arrays are converted to Python numbers/lists. Non-finite floats (NaN, inf,
    -inf) are written as ``null``, so the file is valid strict JSON; a reader gets ``None`` back
    for them. See ``to_json_compatible`` for the full conversion.
    """
    text = json.dumps(to_json_compatible(obj), indent=indent, allow_nan=False) + "\n"
    return write_text_atomic(path, text)

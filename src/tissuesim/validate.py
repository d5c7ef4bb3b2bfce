"""Shared validators: every value is checked once, where it enters (API call or scene table).

Each returns the value in its canonical type (float, int, float array) or raises InputError
naming the argument (``name``), saying what was expected and echoing at most a short
excerpt of what was given (``short``), never Python's own wording ("'<' not supported ...").
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError, ResourceError

__all__ = [
    "short",
    "real",
    "integer",
    "choice",
    "vector",
    "indices",
    "positive_field",
    "regular_file",
    "check_memory",
    "available_memory",
]

MAX_ECHO = 60  # characters of a bad value an error message repeats


def short(value: Any, limit: int = MAX_ECHO) -> str:
    """repr of ``value`` cut to ``limit`` characters (a 1 MB string is not echoed whole)."""
    try:
        text = repr(value)
    except Exception:  # a user object whose repr fails
        text = f"<{type(value).__name__}>"
    if len(text) > limit:
        text = f"{text[: limit - 15]}... ({len(text)} characters)"
    return text


def _is_real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def real(
    value: Any,
    name: str,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
) -> float:
    """A finite real number in [low, high] (open ends with ``low_open`` / ``high_open``)."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if not _is_real(value):
        raise InputError(f"{name} must be a number{_unit(unit)}, not {short(value)}")
    try:
        x = float(value)
    except OverflowError:  # a 400-digit integer
        raise InputError(f"{name} = {short(value)} is too large for a float{_unit(unit)}") from None
    if not math.isfinite(x):
        raise InputError(f"{name} must be a finite number{_unit(unit)}, not {short(value)}")
    if low is not None and (x <= low if low_open else x < low):
        raise InputError(f"{name} must be {'>' if low_open else '>='} {low:g}, not {short(value)}")
    if high is not None and (x >= high if high_open else x > high):
        raise InputError(
            f"{name} must be {'<' if high_open else '<='} {high:g}, not {short(value)}"
        )
    return x


def _unit(unit: str) -> str:
    return f" ({unit})" if unit else ""


def integer(value: Any, name: str, *, low: int | None = None, high: int | None = None) -> int:
    """An integer (not a bool, not a float such as 2.5 or 2.0) in [low, high]."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InputError(f"{name} must be an integer, not {short(value)}")
    k = int(value)
    if (low is not None and k < low) or (high is not None and k > high):
        bound = (
            f"in {low}..{high}"
            if low is not None and high is not None
            else f">= {low}"
            if low is not None
            else f"<= {high}"
        )
        raise InputError(f"{name} must be an integer {bound}, not {short(value)}")
    return k


def choice(value: Any, name: str, choices: Sequence[str]) -> str:
    """One of ``choices`` (strings)."""
    if not isinstance(value, str) or value not in choices:
        raise InputError(f"{name} must be one of {list(choices)}, not {short(value)}")
    return value


def vector(
    value: Any,
    name: str,
    lengths: int | Sequence[int],
    *,
    unit: str = "",
    positive: bool = False,
) -> np.ndarray:
    """A 1-D array of finite numbers whose length is one of ``lengths``."""
    allowed = (lengths,) if isinstance(lengths, int) else tuple(lengths)
    want = " or ".join(str(n) for n in allowed)
    items = value.tolist() if isinstance(value, np.ndarray) else value
    if isinstance(items, str) or not isinstance(items, Sequence):
        raise InputError(
            f"{name} must be a list of {want} numbers{_unit(unit)}, not {short(value)}"
        )
    if len(items) not in allowed or not all(_is_real(v) for v in items):
        raise InputError(
            f"{name} must be a list of {want} numbers{_unit(unit)}, not {short(value)}"
        )
    out = np.array([real(v, f"{name}[{i}]", unit=unit) for i, v in enumerate(items)])
    if positive and not (out > 0).all():
        raise InputError(f"{name} must hold numbers > 0{_unit(unit)}, not {short(value)}")
    return out


def positive_field(
    value: Any, name: str, n: int, unit: str = "", entry: str = "element"
) -> np.ndarray:
    """A number > 0, or one per ``entry`` ((n,) array), as an (n,) float array."""
    if _is_real(value) or (isinstance(value, np.ndarray) and value.ndim == 0):
        return np.full(n, real(value, name, low=0.0, low_open=True, unit=unit))
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != (n,) or not np.issubdtype(arr.dtype, np.number):
        raise InputError(
            f"{name} must be a number{_unit(unit)} or {n} numbers (one per {entry}), "
            f"not {short(value)}"
        )
    arr = arr.astype(float)
    bad = ~(np.isfinite(arr) & (arr > 0))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise InputError(
            f"{name} must be finite and > 0{_unit(unit)}; {entry} {k} has {float(arr[k])!r} "
            f"({int(bad.sum())} such entries)"
        )
    return arr


def indices(value: Any, name: str, n: int, *, what: str = "vertex") -> np.ndarray:
    """Indices into 0..n-1 as int64 (a boolean mask or floats are refused: numpy would
    silently select other entries)."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}: {what} indices must be integers, not {short(value)}") from None
    if arr.dtype == bool:
        raise InputError(f"{name}: got a boolean mask; pass {what} indices (np.flatnonzero(mask))")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"{name}: {what} indices must be integers, got {arr.dtype} values")
    v = arr.astype(np.int64).ravel()
    if v.size and (v.min() < 0 or v.max() >= n):
        raise InputError(
            f"{name}: {what} indices must be in [0, {n}); got {int(v.min())}..{int(v.max())} "
            "(out of range)"
        )
    return v


def regular_file(path: str | os.PathLike[str], what: str) -> Path:
    """``path`` if it is a readable regular file; a FIFO, device or directory would block or
    mislead a reader, so they are refused before anything opens them."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such {what}; check the path")
    if not p.is_file():
        kind = "a directory" if p.is_dir() else "not a regular file (a FIFO, socket or device)"
        raise InputError(f"{p}: the {what} is {kind}; give a regular file")
    if not os.access(p, os.R_OK):
        raise InputError(f"{p}: the {what} is not readable (permissions); fix them or copy it")
    return p


def available_memory() -> int:
    """Bytes of memory this process may still use: the machine's available memory, capped by
    a cgroup limit when there is one."""
    total = None
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    total = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    if total is None:
        try:
            total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
        except (ValueError, OSError, AttributeError):
            total = 2**40  # unknown: do not refuse
    for limit_file in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            text = Path(limit_file).read_text().strip()
        except OSError:
            continue
        if text.isdigit():
            total = min(total, int(text))
    return total


def check_memory(estimate_bytes: float, what: str, how: str) -> None:
    """Refuse, before allocating, a size whose memory estimate exceeds what the machine has."""
    free = available_memory()
    if estimate_bytes > free:
        raise ResourceError(
            f"{what} needs about {_bytes(estimate_bytes)} of memory; this machine has "
            f"{_bytes(free)} available. {how}"
        )


def _bytes(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} PiB"

"""What a study varies and its samples: each parameter is a scene key path with a list of values
(a grid: the product of the lists) or an interval that a sampler (Sobol, Latin hypercube,
uniform random; SciPy's ``qmc``, seeded) fills.

Values on the command line (``--vary KEY=VALUES``; the same strings in Python):

- ``1e3,2e3,5e3``: these values (numbers; ``true`` / ``false``; other words as strings);
  ``[[0, 0, 0.01], [0, 0, 0.02]]``: a TOML array of values (vectors);
- ``1e3:5e3:5``: 5 values evenly spaced from 1e3 to 5e3, both ends included (NumPy's
  ``linspace``); ``1e3:1e5:5:log``: 5 values evenly spaced in log (``geomspace``);
- ``1e3:5e3``: the interval [1e3, 5e3], sampled by ``--sampler sobol|lhs|random``;
  ``1e3:1e5:log``: sampled uniformly in log;
- ``glob:meshes/*.vtu``: the files matching the pattern in the scene's folder (a mesh per
  sample), sorted.
"""

from __future__ import annotations

import itertools
import math
import re
import tomllib
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.sweep.keypaths import KeyPath, parse_key_path

__all__ = ["Interval", "Parameter", "SAMPLERS", "parse_values", "parameters", "make_samples"]

SAMPLERS = ("grid", "sobol", "lhs", "random")
_HOW = (
    "write a list 1e3,2e3,5e3, a TOML array [[0,0,1],[0,0,2]], evenly spaced values "
    "LOW:HIGH:N (N >= 1, both ends; LOW:HIGH:N:log for log spacing) or an interval LOW:HIGH "
    "(LOW:HIGH:log) for --sampler sobol|lhs|random"
)


@dataclass(frozen=True)
class Interval:
    """An interval [low, high] of a parameter that a sampler fills (``log``: uniform in log)."""

    low: float
    high: float
    log: bool = False

    def scale(self, u: np.ndarray) -> np.ndarray:
        """Points u in [0, 1) -> values in the interval."""
        if self.log:
            a, b = math.log(self.low), math.log(self.high)
            return np.exp(a + u * (b - a))
        return self.low + u * (self.high - self.low)


@dataclass(frozen=True)
class Parameter:
    """A varied scene key: its path and either discrete ``values`` or an ``interval``."""

    path: KeyPath
    values: tuple | None = None
    interval: Interval | None = None

    @property
    def key(self) -> str:
        return self.path.text


def parse_values(text: str, key: str) -> tuple | Interval:
    """The values of one ``--vary KEY=VALUES`` (see the module's docstring)."""
    text = text.strip()
    if not text:
        raise InputError(f"--vary {key}=: no values; {_HOW}")
    if text.startswith("["):
        try:
            values = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError as exc:
            raise InputError(
                f"--vary {key}={_short(text)}: not a TOML array ({exc}); {_HOW}"
            ) from None
        if not values:
            raise InputError(f"--vary {key}={_short(text)}: an empty array; {_HOW}")
        return tuple(values)
    if ":" in text:
        return _range(text, key)
    return tuple(_scalar(item, key, text) for item in text.split(","))


def _range(text: str, key: str) -> tuple | Interval:
    parts = [p.strip() for p in text.split(":")]
    log = parts[-1].lower() == "log"
    if log:
        parts = parts[:-1]
    bad = f"--vary {key}={_short(text)}: malformed range; {_HOW}"
    if len(parts) not in (2, 3):
        raise InputError(bad)
    try:
        low, high = float(parts[0]), float(parts[1])
    except ValueError:
        raise InputError(bad) from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise InputError(f"--vary {key}={_short(text)}: the ends must be finite numbers")
    if log and (low <= 0 or high <= 0):
        raise InputError(f"--vary {key}={_short(text)}: a log range needs ends > 0")
    if len(parts) == 2:
        if not low < high:
            raise InputError(f"--vary {key}={_short(text)}: an interval needs LOW < HIGH")
        return Interval(low, high, log)
    if not re.fullmatch(r"\d+", parts[2]) or int(parts[2]) < 1:
        raise InputError(f"--vary {key}={_short(text)}: the count N must be an integer >= 1")
    n = int(parts[2])
    values = np.geomspace(low, high, n) if log else np.linspace(low, high, n)
    return tuple(float(v) for v in values)


def _scalar(item: str, key: str, text: str) -> Any:
    item = item.strip()
    if not item:
        raise InputError(f"--vary {key}={_short(text)}: an empty value in the list; {_HOW}")
    for convert in (int, float):
        try:
            value = convert(item)
        except ValueError:
            continue
        if isinstance(value, float) and not math.isfinite(value):
            raise InputError(f"--vary {key}={_short(text)}: {item!r} is not a finite number")
        return value
    if item in ("true", "false"):
        return item == "true"
    if re.fullmatch(r"[A-Za-z_][\w./-]*", item):
        return item  # a word: a law's name, a mesh file
    try:
        return tomllib.loads(f"v = {item}")["v"]  # a quoted string
    except tomllib.TOMLDecodeError:
        raise InputError(
            f"--vary {key}={_short(text)}: {_short(item)} is not a number or a word; {_HOW}"
        ) from None


def parameters(
    vary: Mapping[str, Any] | Sequence[str], data: dict | None, base_dir: Path | None = None
) -> list[Parameter]:
    """The study's parameters from ``vary`` ({key path: values} or ["KEY=VALUES", ...]),
    each path checked against the scene's ``data``; ``data`` None (a study of a function):
    each key is a keyword argument's name. ``glob:PATTERN`` values are the files matching it
    in ``base_dir`` (the scene's folder; default the working directory), sorted."""
    if isinstance(vary, Mapping):
        items = list(vary.items())
    else:
        items = []
        for spec in vary:
            key, sep, values = str(spec).partition("=")
            if not sep or not key.strip():
                raise InputError(
                    f"--vary {_short(str(spec))}: write KEY=VALUES, e.g. "
                    "material.youngs_modulus=1e3:5e3:5"
                )
            items.append((key.strip(), values))
    if not items:
        raise InputError("a study needs at least one --vary KEY=VALUES")
    out, seen = [], set()
    for key, spec in items:
        path = parse_key_path(key)
        if path.text in seen:
            raise InputError(f"--vary {path.text}: given twice; give each key once")
        seen.add(path.text)
        if data is not None:
            path.get(data)  # the key must be in the scene
        elif len(path.parts) != 1:
            raise InputError(
                f"vary[{path.text!r}]: a study of a function varies its keyword arguments: "
                "give each as a name (E, probe_depth), not a path"
            )
        if isinstance(spec, str) and spec.strip().startswith("glob:"):
            spec = _files(spec.strip().removeprefix("glob:"), path.text, base_dir)
        if isinstance(spec, str):
            spec = parse_values(spec, path.text)
        if isinstance(spec, Interval):
            out.append(Parameter(path, interval=spec))
            continue
        if isinstance(spec, np.ndarray):
            spec = spec.tolist()
        if isinstance(spec, (list, tuple)) and spec:
            out.append(Parameter(path, values=tuple(_plain(v) for v in spec)))
            continue
        raise InputError(
            f"vary[{path.text!r}]: give a non-empty list of values, an Interval(low, high) or a "
            f"string such as '1e3:5e3:5'; not {_short(repr(spec))}"
        )
    return out


def _files(pattern: str, key: str, base_dir: Path | None) -> tuple[str, ...]:
    """The files matching ``pattern`` in ``base_dir``, as paths relative to it, sorted."""
    base = Path(".") if base_dir is None else Path(base_dir)
    if not pattern or Path(pattern).is_absolute():
        raise InputError(
            f"--vary {key}=glob:{_short(pattern)}: give a pattern relative to the scene's "
            "folder, e.g. glob:meshes/*.vtu"
        )
    found = sorted(p.relative_to(base).as_posix() for p in base.glob(pattern) if p.is_file())
    if not found:
        raise InputError(
            f"--vary {key}=glob:{_short(pattern)}: no file matches in {base} (the pattern is "
            "relative to the scene's folder)"
        )
    return tuple(found)


def make_samples(
    params: list[Parameter], samples: int | None, sampler: str, seed: int
) -> list[dict[str, Any]]:
    """Every run's values, {key path: value}: the product of the value lists (the first key
    varies slowest) and, for intervals, ``samples`` points of ``sampler`` for each of them."""
    if sampler not in SAMPLERS:
        raise InputError(f"--sampler {sampler!r}: choose one of {', '.join(SAMPLERS)}")
    lists = [p for p in params if p.values is not None]
    intervals = [p for p in params if p.interval is not None]
    if intervals and sampler == "grid":
        raise InputError(
            f"--vary {intervals[0].key}: an interval LOW:HIGH needs a sampler: give a count "
            "LOW:HIGH:N for a grid, or --sampler sobol|lhs|random with --samples N"
        )
    if sampler != "grid" and not intervals:
        raise InputError(
            f"--sampler {sampler}: no interval to sample; give one as KEY=LOW:HIGH, or use "
            "--sampler grid"
        )
    if intervals and (samples is None or samples < 1):
        raise InputError(f"--sampler {sampler}: give the number of samples, --samples N (N >= 1)")
    if not intervals and samples is not None:
        raise InputError(
            "--samples N applies to intervals (KEY=LOW:HIGH with --sampler sobol|lhs|random); "
            "a grid has as many runs as the product of its value lists"
        )
    points = _points(len(intervals), samples or 0, sampler, seed) if intervals else None
    grid = list(itertools.product(*(p.values for p in lists)))
    out = []
    for combo in grid:
        fixed = {p.key: v for p, v in zip(lists, combo, strict=True)}
        if points is None:
            out.append(fixed)
            continue
        columns = [p.interval.scale(points[:, j]) for j, p in enumerate(intervals)]
        for i in range(points.shape[0]):
            drawn = {p.key: float(c[i]) for p, c in zip(intervals, columns, strict=True)}
            out.append({**fixed, **drawn})
    return out


def _points(d: int, n: int, sampler: str, seed: int) -> np.ndarray:
    """n points in [0, 1)^d, the same for the same seed."""
    if sampler == "random":
        return np.random.default_rng(seed).random((n, d))
    from scipy.stats import qmc

    if sampler == "lhs":
        return qmc.LatinHypercube(d, rng=np.random.default_rng(seed)).random(n)
    engine = qmc.Sobol(d, scramble=True, rng=np.random.default_rng(seed))
    with warnings.catch_warnings():  # n not a power of 2 loses Sobol's balance: documented
        warnings.simplefilter("ignore", UserWarning)
        return engine.random(n)


def coerce(value: Any, current: Any) -> Any:
    """A sample's value in the type of the scene's value: a float for an integer key is
    rounded (divisions, steps); an int for a float key becomes a float."""
    value = _plain(value)
    if type(current) is int and isinstance(value, float) and math.isfinite(value):
        return int(round(value))
    if type(current) is float and type(value) is int:
        return float(value)
    return value


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _short(text: str) -> str:
    return text if len(text) <= 60 else text[:57] + "..."

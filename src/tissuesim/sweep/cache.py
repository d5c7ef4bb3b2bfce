"""A worker's mesh cache: the runs of a study that read the same mesh file, mesh the same
surface or generate the same box, do it once per worker process instead of once per run; and
the same for the sparsity analysis of a shared mesh (the Hessian's CSR pattern and its scatter
maps, ``assembly/pattern.py``: 0.07 s for 1.6e4 tetrahedra, 0.28 s for 4.8e4, a tenth of a
short run's time).

``read_mesh`` (meshio's parse, the checks), ``mesh_surface`` (a tetrahedralisation: seconds
to minutes for an organ) and the generators ``box``, ``ellipsoid``, ``rectangle`` (a third of
a small scene's build, its checks included) are pure functions of the file's bytes and their
arguments, so a worker keeps their results: keyed by the file's resolved path, its contents'
hash (BLAKE2b, so a file rewritten between runs is read again, whatever its time stamp) and
the arguments, at most ``MAX_MESHES`` meshes, the least recently used dropped first. Every
run gets its own deep copy (a run may cut or tear its mesh), so a run's numbers are those
without the cache, bit for bit (tests/sweep/test_sweep_cache.py). ``SparsityPattern.
from_stencils`` and ``from_entries`` are pure functions of their arguments (the element
stencils' bytes), kept the same way: at most ``MAX_PATTERNS`` (a 4.8e4-tetrahedron pattern
is 60 MB), each run given its own copy (0.02 s); and so are P1 elements' rest shapes
(``kinematics/p1.py``'s ``shape_gradients``: a model's regions and a parameter's copies,
``identification/sensitivity.py``, share them), and the closest-point search that glues two
bodies (``coupling/tie.py``'s ``tie_points``),
keyed by both meshes' points and cells and the search distance (the tie's stiffness, which
follows the materials, is applied after).

The cache is on only inside a study's run (``execute_run``, a thread-local switch; off
everywhere with ``TISSUESIM_SWEEP_CACHE=0`` in the environment), through wrappers put once in
place of these functions in ``tissuesim.mesh`` and ``tissuesim`` (where the scene loader
imports them when it builds a mesh, and where a study's builder function finds them): the
same calls outside a study's run go straight to the functions, uncached.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import os
import sys
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

__all__ = [
    "MAX_MESHES",
    "MAX_PATTERNS",
    "install",
    "enabled",
    "clear",
    "stats",
    "pattern_stats",
    "tie_stats",
]

#: meshes kept per worker (a 1e5-tetrahedron mesh is about 4 MB)
MAX_MESHES = 8
#: sparsity patterns kept per worker (60 MB for 4.8e4 tetrahedra)
MAX_PATTERNS = 4
#: ties between two bodies kept per worker (a scene's glued pairs)
MAX_TIES = 16
#: P1 rest shapes (shape gradients and measures) kept per worker (a body's regions each have
#: theirs; 5 MB for 4.8e4 tetrahedra)
MAX_REST_SHAPES = 16

_local = threading.local()
_lock = threading.Lock()
_meshes: OrderedDict[tuple, Any] = OrderedDict()
_stats = {"hits": 0, "misses": 0}
_patterns: OrderedDict[tuple, Any] = OrderedDict()
_pattern_stats = {"hits": 0, "misses": 0}
_shapes: OrderedDict[tuple, Any] = OrderedDict()
_shape_stats = {"hits": 0, "misses": 0}
_ties: OrderedDict[tuple, Any] = OrderedDict()
_tie_stats = {"hits": 0, "misses": 0}
_installed = False


def stats() -> dict[str, int]:
    """This process's mesh cache: hits, misses (since ``clear``) and meshes kept."""
    with _lock:
        return {**_stats, "meshes": len(_meshes)}


def pattern_stats() -> dict[str, int]:
    """This process's sparsity pattern cache: hits, misses (since ``clear``), patterns kept."""
    with _lock:
        return {**_pattern_stats, "patterns": len(_patterns)}


def tie_stats() -> dict[str, int]:
    """This process's tie cache: hits, misses (since ``clear``) and ties kept."""
    with _lock:
        return {**_tie_stats, "ties": len(_ties)}


def clear() -> None:
    """Forget every mesh and pattern kept and the counts."""
    with _lock:
        _meshes.clear()
        _stats.update(hits=0, misses=0)
        _patterns.clear()
        _pattern_stats.update(hits=0, misses=0)
        _shapes.clear()
        _shape_stats.update(hits=0, misses=0)
        _ties.clear()
        _tie_stats.update(hits=0, misses=0)


@contextmanager
def enabled() -> Iterator[None]:
    """The cache on in this thread while inside (a study's run)."""
    before = getattr(_local, "on", False)
    _local.on = os.environ.get("TISSUESIM_SWEEP_CACHE", "1") != "0"
    try:
        yield
    finally:
        _local.on = before


def _file_key(path: Any) -> tuple | None:
    """(resolved path, size, contents' hash) of a regular file, or None (not a path, not a
    regular file, unreadable: the wrapped function then reports it as it would)."""
    if not isinstance(path, str | os.PathLike):
        return None
    try:
        real = os.path.realpath(os.fspath(path))
        if not os.path.isfile(real):
            return None
        digest = hashlib.blake2b(digest_size=16)
        with open(real, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
        return (real, os.path.getsize(real), digest.hexdigest())
    except (OSError, TypeError, ValueError):
        return None


def _value_key(value: Any) -> Any:
    """A hashable key of an argument: numbers, strings, paths, lists, tuples, dicts and NumPy
    arrays (by their bytes); TypeError for anything else (then not cached)."""
    if value is None or isinstance(value, bool | int | float | str):
        return (type(value).__name__, value)
    if isinstance(value, os.PathLike):
        return ("path", os.fspath(value))
    if isinstance(value, np.ndarray | np.generic):
        a = np.ascontiguousarray(value)
        if a.dtype.hasobject:
            raise TypeError("an object array")
        return ("array", a.shape, a.dtype.str, hashlib.blake2b(a.tobytes()).hexdigest())
    if isinstance(value, list | tuple):
        return (type(value).__name__, *(_value_key(v) for v in value))
    if isinstance(value, dict):
        return ("dict", *sorted((str(k), _value_key(v)) for k, v in value.items()))
    raise TypeError(f"no cache key for {type(value).__name__}")


def _option_key(options: dict) -> tuple | None:
    try:
        return tuple(sorted((k, _value_key(v)) for k, v in options.items()))
    except TypeError:
        return None


def _kept(store: OrderedDict, counts: dict, limit: int, key: tuple, make: Callable[[], Any]):
    """A copy of ``store[key]``, made by ``make`` on a miss (the least recently used dropped
    beyond ``limit``)."""
    with _lock:
        value = store.get(key)
        if value is not None:
            store.move_to_end(key)
            counts["hits"] += 1
    if value is None:
        value = make()
        with _lock:
            counts["misses"] += 1
            store[key] = value
            while len(store) > limit:
                store.popitem(last=False)
    return copy.deepcopy(value)


def _cached(kind: str, function: Callable[..., Any]) -> Callable[..., Any]:
    """``function(path, *args, **options)`` cached by the file and the options while the cache
    is on in this thread (a generator, ``kind`` "generator:NAME": by its arguments alone)."""
    generator = kind.startswith("generator")

    @functools.wraps(function)
    def wrapper(*args: Any, **options: Any) -> Any:
        if not getattr(_local, "on", False):
            return function(*args, **options)
        file = () if generator else _file_key(args[0] if args else None)
        rest = _option_key({**{f"#{i}": a for i, a in enumerate(args)}, **options})
        if file is None or rest is None:
            return function(*args, **options)
        key = (kind, *file, rest)
        return _kept(_meshes, _stats, MAX_MESHES, key, lambda: function(*args, **options))

    wrapper.__wrapped_by_sweep_cache__ = True  # type: ignore[attr-defined]
    return wrapper


def _cached_pattern(name: str, function: Callable[..., Any]) -> classmethod:
    """A classmethod of ``SparsityPattern`` (``function``: the original, bound) cached by its
    arguments' values while the cache is on in this thread."""

    @functools.wraps(function)
    def wrapper(cls: type, *args: Any, **options: Any) -> Any:
        if not getattr(_local, "on", False):
            return function(*args, **options)
        key = _option_key({**{f"#{i}": a for i, a in enumerate(args)}, **options})
        if key is None:
            return function(*args, **options)
        make = lambda: function(*args, **options)  # noqa: E731
        return _kept(_patterns, _pattern_stats, MAX_PATTERNS, (name, key), make)

    wrapper.__wrapped_by_sweep_cache__ = True  # type: ignore[attr-defined]
    return classmethod(wrapper)


def _cached_shapes(function: Callable[..., Any]) -> Callable[..., Any]:
    """``shape_gradients(points, cells)`` cached by the arrays' bytes while the cache is on."""

    @functools.wraps(function)
    def wrapper(points: np.ndarray, cells: np.ndarray) -> Any:
        if not getattr(_local, "on", False):
            return function(points, cells)
        key = _option_key({"points": points, "cells": cells})
        if key is None:
            return function(points, cells)
        make = lambda: function(points, cells)  # noqa: E731
        return _kept(_shapes, _shape_stats, MAX_REST_SHAPES, key, make)

    wrapper.__wrapped_by_sweep_cache__ = True  # type: ignore[attr-defined]
    return wrapper


def _mesh_key(mesh: Any) -> tuple:
    """A mesh by what a tie's search reads: its points and cells (a cut mesh's fractions and
    levels too, so that a cut copy is never taken for its uncut mesh)."""
    names = ("points", "cells", "cell_fractions", "cell_levels", "cell_more_levels")
    return tuple(_value_key(getattr(mesh, name, None)) for name in names)


def _cached_tie(function: Callable[..., Any]) -> Callable[..., Any]:
    """``tie_points(a, mesh_a, b, mesh_b, **options)`` cached by the meshes' arrays, the
    names (its error message names them) and the options while the cache is on."""

    @functools.wraps(function)
    def wrapper(a: str, mesh_a: Any, b: str, mesh_b: Any, **options: Any) -> Any:
        call = lambda: function(a, mesh_a, b, mesh_b, **options)  # noqa: E731
        if not getattr(_local, "on", False):
            return call()
        try:
            key = (a, b, _mesh_key(mesh_a), _mesh_key(mesh_b), _option_key(options))
        except TypeError:
            return call()
        if key[-1] is None:
            return call()
        return _kept(_ties, _tie_stats, MAX_TIES, key, call)

    wrapper.__wrapped_by_sweep_cache__ = True  # type: ignore[attr-defined]
    return wrapper


def install() -> None:
    """Put the caching wrappers in place (once per process; idempotent)."""
    global _installed
    with _lock:
        if _installed:
            return
        import tissuesim.mesh
        import tissuesim.mesh.from_surface.tetrahedralize as tetrahedralize

        # the package itself is loaded (this module is part of it): taken from sys.modules, so
        # no import of it from inside it (tests/test_layout.py: no cycles)
        tissuesim = sys.modules["tissuesim"]

        wrappers = {
            "read_mesh": _cached("file", tissuesim.mesh.read_mesh),
            "mesh_surface": _cached("surface", tetrahedralize.mesh_surface),
        }
        for name in ("box", "ellipsoid", "rectangle"):
            wrappers[name] = _cached(f"generator:{name}", getattr(tissuesim.mesh, name))
        for name, wrapper in wrappers.items():
            setattr(tissuesim.mesh, name, wrapper)
            setattr(tissuesim, name, wrapper)
        tetrahedralize.mesh_surface = wrappers["mesh_surface"]
        from tissuesim.assembly.pattern import SparsityPattern

        for name in ("from_stencils", "from_entries"):
            setattr(SparsityPattern, name, _cached_pattern(name, getattr(SparsityPattern, name)))
        import tissuesim.kinematics.p1 as p1

        p1.shape_gradients = _cached_shapes(p1.shape_gradients)
        import tissuesim.coupling.tie as tie

        tie.tie_points = _cached_tie(tie.tie_points)
        _installed = True

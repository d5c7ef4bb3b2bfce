"""Adapters to the external tetrahedral meshers that ``mesh_surface`` can call.

Each adapter takes a triangle surface (points (n, 3) float64, faces (k, 3) int64) and a target
edge length ``size`` (in the units of the points) and returns the raw output of its mesher,
(points (p, 3) float64, tetrahedra (m, 4) int64), unchecked: ``mesh/from_surface/tetrahedralize.py``
checks it. The meshers are optional dependencies, imported only when called:

- ``pytetwild`` (fTetWild, MPL-2.0): envelope-based, meshes non-manifold, self-touching and open
  surfaces (it fills by the generalised winding number); the default (docs/meshing.md).
- ``tetgen`` (MIT wrapper of the AGPL TetGen): constrained Delaunay; keeps the input triangles,
  so it needs a closed, manifold, non-self-intersecting surface.
- ``gmsh`` (GPL): the surface is reparametrised and remeshed to ``size``; needs a closed surface,
  and may return no tetrahedra without raising on a bad one.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import tempfile
from collections.abc import Callable

import numpy as np

from tissuesim.errors import InputError, MeshError

__all__ = ["MESHERS", "INSTALL_HINT", "available_meshers", "mesh_threads", "run_mesher"]

#: the meshers in the order ``mesher="auto"`` tries them (the first one installed is used)
MESHERS = ("pytetwild", "tetgen", "gmsh")
INSTALL_HINT = "pip install pytetwild"  # a dependency of tissuesim: missing only if removed
_PACKAGE = {"pytetwild": "pytetwild", "tetgen": "tetgen", "gmsh": "gmsh"}


def available_meshers() -> list[str]:
    """The meshers of ``MESHERS`` that are installed (importable), in order of preference."""
    return [m for m in MESHERS if importlib.util.find_spec(_PACKAGE[m]) is not None]


def _import(name: str):
    try:
        return __import__(_PACKAGE[name])
    except ImportError as exc:
        extra = (
            INSTALL_HINT
            if name == "pytetwild"
            else f'pip install "tissuesim[{name}]" (or {INSTALL_HINT} for the default, pytetwild)'
        )
        raise InputError(
            f"mesher {name!r} is not installed ({exc}); install it with {extra}"
        ) from exc
    except OSError as exc:  # gmsh needs system GL/X libraries
        raise InputError(
            f"mesher {name!r} is installed but cannot load ({exc}); gmsh needs the system's "
            f"libGLU / libXcursor / libXinerama (apt-get install libglu1-mesa libxcursor1 "
            f"libxinerama1), or use mesher 'pytetwild' ({INSTALL_HINT})"
        ) from exc


#: the child that runs fTetWild: it reads surface.npz and writes volume.npz in its directory
_PYTETWILD_CHILD = """
import sys, types
import numpy as np
try:
    import pytetwild
except ModuleNotFoundError as exc:  # pytetwild's PyVista accessor; tetrahedralize needs none
    if exc.name != "pyvista":
        raise
    sys.modules["pyvista"] = types.ModuleType("pyvista")
    for name in [m for m in sys.modules if m.startswith("pytetwild")]:
        del sys.modules[name]
    import pytetwild
d = np.load("surface.npz")
v, t = pytetwild.tetrahedralize(d["points"], d["faces"], edge_length_abs=float(d["size"]),
                                epsilon=float(d["epsilon"]), coarsen=bool(d["coarsen"]),
                                num_threads=int(d["threads"]), quiet=True)
np.savez("volume.npz", points=v, tets=t)
"""

#: fTetWild's threads (0: all cores); its output varies a little from run to run, even on one
THREADS_VARIABLE = "TISSUESIM_MESH_THREADS"


def mesh_threads() -> int:
    """pytetwild's threads from TISSUESIM_MESH_THREADS (0, every core, when unset)."""
    value = os.environ.get(THREADS_VARIABLE, "").strip()
    if not value:
        return 0
    if not value.isdigit() or int(value) < 1:
        raise InputError(
            f"{THREADS_VARIABLE}={value!r}: give a whole number of threads >= 1 (or unset it "
            "for every core)"
        )
    return int(value)


def _pytetwild(
    points: np.ndarray, faces: np.ndarray, size: float, epsilon: float = 1e-3, coarsen: bool = False
) -> tuple:
    """fTetWild in a child process in a temporary directory: it writes __tracked_surface.stl
    into its working directory (not the user's), and a crash or an abort of the C++ code
    becomes an error here instead of ending the caller's process."""
    import subprocess
    import sys

    # not imported here: pytetwild imports PyVista (an optional extra) for an accessor that
    # its tetrahedralize does not use; the child stands in for PyVista when it is missing
    if importlib.util.find_spec(_PACKAGE["pytetwild"]) is None:
        raise InputError(f"mesher 'pytetwild' is not installed; install it with {INSTALL_HINT}")
    with tempfile.TemporaryDirectory(prefix="tissuesim-tetwild-") as tmp:
        # edge_length_abs: the target edge length; the envelope (epsilon, by default 1e-3 of
        # the bounding-box diagonal) bounds how far the boundary may lie from the input surface
        np.savez(
            os.path.join(tmp, "surface.npz"),
            points=points,
            faces=faces.astype(np.int32),
            size=size,
            epsilon=epsilon,
            coarsen=coarsen,
            threads=mesh_threads(),
        )
        run = subprocess.run(
            [sys.executable, "-c", _PYTETWILD_CHILD], cwd=tmp, capture_output=True, text=True
        )
        if run.returncode != 0:
            said = " ".join(run.stderr.strip().splitlines()[-1:]) or "no message"
            raise RuntimeError(f"fTetWild exited with status {run.returncode}: {said}")
        with np.load(os.path.join(tmp, "volume.npz")) as out:
            return out["points"], out["tets"]


def _tetgen(points: np.ndarray, faces: np.ndarray, size: float) -> tuple:
    tetgen = _import("tetgen")
    gen = tetgen.TetGen(points, faces.astype(np.int32))
    # maxvolume: the volume of the regular tetrahedron of edge ``size``; minratio 1.5 (radius /
    # shortest edge) and mindihedral 10 degrees refine bad elements without stalling
    out = gen.tetrahedralize(
        quality=True,
        minratio=1.5,
        mindihedral=10.0,
        maxvolume=size**3 / (6.0 * np.sqrt(2.0)),
        quiet=True,
    )
    return out[0], out[1]


def _gmsh(points: np.ndarray, faces: np.ndarray, size: float) -> tuple:
    gmsh = _import("gmsh")
    import meshio

    with tempfile.TemporaryDirectory(prefix="tissuesim-gmsh-") as tmp:
        stl = os.path.join(tmp, "surface.stl")
        meshio.write_points_cells(stl, points, [("triangle", faces)], binary=True)
        gmsh.initialize(readConfigFiles=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.option.setNumber("General.NumThreads", 1)
            gmsh.merge(stl)
            # split the surface at sharp edges, reparametrise it and remesh it to ``size``
            gmsh.model.mesh.classifySurfaces(40 * np.pi / 180, True, True, np.pi)
            gmsh.model.mesh.createGeometry()
            surfaces = [tag for _, tag in gmsh.model.getEntities(2)]
            loop = gmsh.model.geo.addSurfaceLoop(surfaces)
            gmsh.model.geo.addVolume([loop])
            gmsh.model.geo.synchronize()
            gmsh.option.setNumber("Mesh.MeshSizeMax", size)
            gmsh.option.setNumber("Mesh.MeshSizeMin", size / 4)
            gmsh.model.mesh.generate(3)
            tags, coords, _ = gmsh.model.mesh.getNodes()
            types, _, nodes = gmsh.model.mesh.getElements(3)
        finally:
            with contextlib.suppress(Exception):
                gmsh.finalize()
    pts = np.asarray(coords, dtype=np.float64).reshape(-1, 3)
    index = np.zeros(int(tags.max()) + 1 if len(tags) else 1, dtype=np.int64)
    index[np.asarray(tags, dtype=np.int64)] = np.arange(len(tags))
    tets = [
        np.asarray(n, dtype=np.int64).reshape(-1, 4)
        for ty, n in zip(types, nodes, strict=True)
        if ty == 4  # 4-node tetrahedra
    ]
    t = index[np.concatenate(tets)] if tets else np.zeros((0, 4), dtype=np.int64)
    return pts, t


_ADAPTERS: dict[str, Callable[..., tuple]] = {
    "pytetwild": _pytetwild,
    "tetgen": _tetgen,
    "gmsh": _gmsh,
}


def run_mesher(
    name: str,
    points: np.ndarray,
    faces: np.ndarray,
    size: float,
    source: str,
    options: dict[str, float | bool] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Run mesher ``name`` on the surface; (points (p, 3), tetrahedra (m, 4) int64), unchecked.

    options: pytetwild's ``epsilon`` (the envelope relative to the bounding-box diagonal) and
    ``coarsen``; the other meshers take none (``tetrahedralize`` refuses them).

    A missing mesher raises InputError with the install line; a mesher that raises is
    reported as a MeshError naming ``source`` and suggesting another mesher.
    """
    adapter = _ADAPTERS[name]
    if name != "pytetwild":  # (pytetwild is imported by its child process only)
        _import(name)  # a missing mesher is an install problem, not a meshing failure
    try:
        v, t = adapter(
            np.ascontiguousarray(points), np.ascontiguousarray(faces), size, **(options or {})
        )
    except InputError:
        raise
    except Exception as exc:
        others = [m for m in MESHERS if m != name]
        raise MeshError(
            f"{source}: mesher {name!r} failed ({type(exc).__name__}: "
            f"{' '.join(str(exc).split())[:300]}); check the surface (closed, no "
            f"self-intersections), or try mesher {' or '.join(map(repr, others))}"
        ) from exc
    v = np.asarray(v, dtype=np.float64).reshape(-1, 3)
    t = np.asarray(t, dtype=np.int64)
    return v, (t.reshape(-1, 4) if t.size else np.zeros((0, 4), dtype=np.int64))

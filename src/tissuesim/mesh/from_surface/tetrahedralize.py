"""A triangle surface (STL, OBJ, PLY, ... or arrays) -> a checked P1 tetrahedral ``Mesh``.

``mesh_surface`` reads the surface with meshio, welds it, runs an external mesher
(``mesh/from_surface/meshers.py``: pytetwild, a dependency, by default; tetgen or gmsh on request,
the extras ``tissuesim[tetgen]`` / ``tissuesim[gmsh]``) and checks what comes back: no tetrahedra,
tangled (mixed-orientation) or degenerate tetrahedra and a volume far from the surface's are errors
or warnings, never a silent bad mesh. ``tetrahedralize`` returns the mesh with a quality report
(tetrahedra, points, dihedral angles, radius ratio, volume against the surface's enclosed volume),
which ``tissuesim mesh`` prints. The robustness of each mesher is measured in docs/meshing.md
(``benchmarks/meshers.py``).
"""

from __future__ import annotations

import os
import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tissuesim.errors import InputError, MeshError
from tissuesim.mesh.from_surface.meshers import INSTALL_HINT, MESHERS, available_meshers, run_mesher
from tissuesim.mesh.from_surface.sizing import MAX_TETRAHEDRA, meshing_options, to_count
from tissuesim.mesh.from_surface.smoothing import DEFAULT_SMOOTHING_ITERATIONS, smooth_surface
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import short

__all__ = [
    "Surface",
    "SurfaceMeshing",
    "read_surface",
    "dihedral_angles",
    "mesh_surface",
    "tetrahedralize",
]

#: default target edge length, as a fraction of the bounding-box diagonal (fTetWild's default)
DEFAULT_SIZE_FRACTION = 0.05
#: the volume of the tet mesh may differ from the surface's by this much before a warning
VOLUME_TOLERANCE = 0.05
#: a mesh with less than this fraction of the surface's volume is an error (check_volume)
MIN_VOLUME_RATIO = 0.5
_VOLUME_CELLS = ("tetra", "tetra10", "hexahedron", "wedge", "pyramid")


@dataclass(frozen=True)
class Surface:
    """A welded triangle surface: points (n, 3) float64, faces (k, 3) int64, and its origin.

    ``boundary_edges``: edges used by one triangle (a hole has them; 0 for a closed surface);
    ``nonmanifold_edges``: edges shared by more than two triangles; ``misoriented_edges``:
    edges two triangles run through in the same direction (a flipped triangle); ``volume``: the
    enclosed volume by the divergence theorem (negative for an inside-out surface; for an open
    or misoriented one it is only an estimate).
    """

    points: np.ndarray
    faces: np.ndarray
    source: str
    boundary_edges: int = 0
    nonmanifold_edges: int = 0
    misoriented_edges: int = 0
    removed_faces: int = 0

    @property
    def closed(self) -> bool:
        return self.boundary_edges == 0

    @property
    def volume(self) -> float:
        x = self.points[self.faces]
        return float(np.einsum("ki,ki->k", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6.0)

    @property
    def diagonal(self) -> float:
        return float(np.linalg.norm(np.ptp(self.points[self.faces.ravel()], axis=0)))


@dataclass(frozen=True)
class SurfaceMeshing:
    """The result of ``tetrahedralize``: the checked mesh and its quality report (plain values)."""

    mesh: Mesh
    report: dict[str, Any] = field(default_factory=dict)


def _surface_arrays(source: Any) -> tuple[np.ndarray, np.ndarray, str]:
    """(points, triangles, name) from a file path or a (points, faces) pair."""
    if isinstance(source, str | os.PathLike):
        return _read_file(os.fspath(source))
    if isinstance(source, tuple | list) and len(source) == 2:
        points, faces = source
        try:
            p = np.array(points, dtype=np.float64)
            f = np.array(faces)
        except (TypeError, ValueError) as exc:
            raise MeshError(
                f"surface arrays: points or faces are not numeric arrays: {exc}"
            ) from exc
        return p, f, "<surface arrays>"
    raise InputError(
        f"mesh_surface: surface must be a file path (STL, OBJ, PLY, ...) or a (points, faces) "
        f"pair of arrays, not {short(source)}"
    )


def _read_file(path: str) -> tuple[np.ndarray, np.ndarray, str]:
    from tissuesim.mesh.io import _load
    from tissuesim.validate import regular_file

    if not os.path.exists(path):
        raise MeshError(f"{path}: no such surface file; check the path (cwd is {os.getcwd()})")
    try:
        regular_file(path, "surface file")
    except InputError as exc:
        raise MeshError(str(exc)) from None
    m = _load(path)
    types = sorted({b.type for b in m.cells})
    volume = [t for t in types if t in _VOLUME_CELLS]
    if volume:
        raise MeshError(
            f"{path}: already a volume mesh ({', '.join(volume)} cells); read it with "
            f"read_mesh (tissuesim info / mesh = {{ file = ... }}) instead of meshing its surface"
        )
    tris = [np.asarray(b.data)[:, :3] for b in m.cells if b.type in ("triangle", "triangle6")]
    # quadrilaterals (OBJ, PLY) are split along a diagonal
    for b in m.cells:
        if b.type in ("quad", "quad8", "quad9"):
            q = np.asarray(b.data)[:, :4]
            tris += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
    if not tris:
        raise MeshError(
            f"{path}: no surface triangles (cell types found: {', '.join(types) or 'none'}); "
            f"give a closed triangle surface (STL, OBJ, PLY, ...)"
        )
    points = np.asarray(m.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise MeshError(f"{path}: surface points have shape {points.shape}; expected (n, 3)")
    return points, np.concatenate(tris).astype(np.int64), path


def _edge_counts(faces: np.ndarray) -> tuple[np.ndarray, int]:
    """Triangles per undirected edge, and the number of edges run twice in one direction."""
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    _, counts = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    _, same = np.unique(directed, axis=0, return_counts=True)
    return counts, int((same > 1).sum())


def read_surface(source: Any) -> Surface:
    """Read and weld a triangle surface from a file (any format meshio reads: STL, OBJ, PLY,
    OFF, VTK, ...) or a (points (n, 3), faces (k, 3)) pair.

    Vertices within 1e-9 of the bounding-box diagonal are merged (STL stores every triangle's
    corners apart), triangles that collapse or repeat another are removed, unused vertices
    dropped. Raises MeshError naming the file for a missing or unreadable file, a volume mesh,
    a file with no triangles, non-finite points or bad indices.
    """
    from scipy.spatial import cKDTree

    points, faces, name = _surface_arrays(source)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 4:
        raise MeshError(f"{name}: surface points have shape {points.shape}; expected (n >= 4, 3)")
    if not np.isfinite(points).all():
        raise MeshError(f"{name}: the surface has non-finite point coordinates; fix the file")
    if faces.ndim != 2 or faces.shape[1] != 3 or not np.issubdtype(faces.dtype, np.integer):
        raise MeshError(
            f"{name}: faces must be an integer (k, 3) array of triangle corners, got shape "
            f"{faces.shape} of {faces.dtype}"
        )
    faces = faces.astype(np.int64)
    if len(faces) < 4 or faces.min() < 0 or faces.max() >= len(points):
        raise MeshError(
            f"{name}: faces must be at least 4 triangles with 0-based indices below "
            f"{len(points)} (the number of points)"
        )
    k0 = len(faces)
    diag = float(np.linalg.norm(np.ptp(points[faces.ravel()], axis=0)))
    if not diag > 0:
        raise MeshError(f"{name}: all surface points coincide; the surface has no extent")
    pairs = cKDTree(points).query_pairs(1e-9 * diag, output_type="ndarray")
    if len(pairs):  # each vertex -> the lowest index of its group of coincident vertices
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components

        n = len(points)
        g = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
        _, label = connected_components(g, directed=False)
        first = np.full(label.max() + 1, n)
        np.minimum.at(first, label, np.arange(n))
        faces = first[label][faces]
    s = np.sort(faces, axis=1)
    x = points[faces]
    area2 = np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    keep = (s[:, 0] != s[:, 1]) & (s[:, 1] != s[:, 2]) & (area2 > 1e-14 * diag**2)
    _, unique = np.unique(s[keep], axis=0, return_index=True)
    faces = faces[np.flatnonzero(keep)[np.sort(unique)]]
    if len(faces) < 4:
        raise MeshError(f"{name}: fewer than 4 non-degenerate triangles; not a closed surface")
    used = np.unique(faces)
    new = np.full(len(points), -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    counts, misoriented = _edge_counts(new[faces])
    return Surface(
        points=points[used],
        faces=new[faces],
        source=name,
        boundary_edges=int((counts == 1).sum()),
        nonmanifold_edges=int((counts > 2).sum()),
        misoriented_edges=misoriented,
        removed_faces=k0 - len(faces),
    )


def dihedral_angles(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Interior dihedral angles (m, 6) in degrees of tetrahedra ``tets`` (m, 4) of ``points``.

    70.53 degrees everywhere for the regular tetrahedron; near 0 or 180 for slivers and caps.
    """
    x = np.asarray(points, dtype=np.float64)[np.asarray(tets)]
    opposite = ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2))
    normals = []
    for k, (a, b, c) in enumerate(opposite):
        n = np.cross(x[:, b] - x[:, a], x[:, c] - x[:, a])
        n *= np.sign(np.einsum("mi,mi->m", n, x[:, a] - x[:, k]))[:, None]  # outward
        normals.append(n / np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None])
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    cos = np.stack([-np.einsum("mi,mi->m", normals[i], normals[j]) for i, j in pairs], axis=1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _size(size: Any, surface: Surface) -> float:
    diag = surface.diagonal
    if size is None:
        return DEFAULT_SIZE_FRACTION * diag
    if isinstance(size, bool) or not isinstance(size, int | float) or not np.isfinite(size):
        raise InputError(f"size must be a number (target edge length in metres), not {short(size)}")
    if size <= 0:
        raise InputError(f"size must be > 0 (target edge length in metres), not {size!r}")
    if size > diag:
        raise InputError(
            f"size {size:g} is larger than the surface's bounding-box diagonal ({diag:.4g}): "
            f"check the units (metres); about {DEFAULT_SIZE_FRACTION * diag:.3g} is typical"
        )
    volume = abs(surface.volume) or float(np.prod(np.ptp(surface.points, axis=0)))
    estimate = volume / (size**3 / (6.0 * np.sqrt(2.0))) * 1.5
    if estimate > MAX_TETRAHEDRA:
        million = size * (estimate / 1e6) ** (1 / 3)  # the size for about 1e6 tetrahedra
        raise InputError(
            f"size {size:g} would make about {estimate:.3g} tetrahedra (more than "
            f"{MAX_TETRAHEDRA:g}); give a larger size, e.g. {million:.3g} (a million tetrahedra)"
        )
    return float(size)


def _choose(mesher: Any) -> str:
    if mesher == "auto":
        found = available_meshers()
        if not found:
            raise InputError(
                f"no tetrahedral mesher is installed; install pytetwild with {INSTALL_HINT} "
                "(or \"tissuesim[tetgen]\" / \"tissuesim[gmsh]\" with mesher='tetgen' / 'gmsh')"
            )
        return found[0]
    if not isinstance(mesher, str) or mesher not in MESHERS:
        raise InputError(f"mesher must be 'auto' or one of {list(MESHERS)}, not {short(mesher)}")
    return mesher


def _orient(v: np.ndarray, t: np.ndarray, name: str, source: str) -> np.ndarray:
    """Orient every tetrahedron positively; a mesh with both orientations is tangled."""
    from tissuesim.mesh.checks import edge_lengths, signed_volumes

    vol = signed_volumes(v, t)
    h = edge_lengths(v, t).mean(axis=1)
    flat = np.abs(vol) <= 1e-12 * h**3
    neg, pos = int((vol < 0).sum()), int((vol > 0).sum())
    if neg > pos:  # the mesher's convention is the other orientation: flip all
        t, vol, neg = t[:, [0, 1, 3, 2]], -vol, pos
    if neg or flat.any():
        raise MeshError(
            f"{source}: mesher {name!r} returned {neg} inverted and {int(flat.sum())} "
            f"degenerate (flat) tetrahedra of {len(t)}; try another size or another mesher "
            f"(one of {[m for m in MESHERS if m != name]})"
        )
    return t


def _mesh_once(surf: Surface, name: str, h: float, options: dict[str, Any]) -> tuple[Mesh, float]:
    """One run of mesher ``name`` at size ``h``, checked: the mesh and the mesher's seconds."""
    from tissuesim.mesh.checks import validate_mesh
    from tissuesim.mesh.queries.boundary import boundary_facets

    started = time.perf_counter()
    v, t = run_mesher(name, surf.points, surf.faces, h, surf.source, options)
    seconds = time.perf_counter() - started
    if len(t) == 0:
        raise MeshError(
            f"{surf.source}: mesher {name!r} produced no tetrahedra ({len(v)} points); the surface "
            f"is probably not closed or intersects itself: repair it or try mesher 'pytetwild'"
        )
    if not np.isfinite(v).all() or t.min() < 0 or t.max() >= len(v):
        raise MeshError(f"{surf.source}: mesher {name!r} returned invalid arrays; try another")
    used = np.unique(t)  # meshers may leave unused (e.g. deleted exterior) points behind
    index = np.zeros(len(v), dtype=np.int64)
    index[used] = np.arange(len(used))
    v, t = v[used], index[t]
    t = _orient(v, t, name, surf.source)
    facets = boundary_facets(t)
    source = f"{surf.source} (meshed by {name}, size {h:.4g})"
    try:
        mesh = validate_mesh(
            v,
            t,
            source=source,
            point_sets={"surface": np.unique(facets)},
            facet_sets={"surface": facets},
        )
    except MeshError as exc:
        raise MeshError(
            f"{exc} (the output of mesher {name!r}: try another size or mesher)"
        ) from exc
    return mesh, seconds


def tetrahedralize(
    surface: Any,
    size: float | None = None,
    *,
    mesher: str = "auto",
    check_volume: bool = True,
    target_elements: int | None = None,
    epsilon: float | None = None,
    envelope: float | None = None,
    coarsen: bool = False,
    smoothing: str | None = None,
    smoothing_iterations: int = DEFAULT_SMOOTHING_ITERATIONS,
) -> SurfaceMeshing:
    """Mesh the solid a triangle surface encloses with P1 tetrahedra; the mesh and its report.

    surface: a file path (STL, OBJ, PLY, ... read with meshio) or a (points, faces) pair, in
    metres. size: target edge length in metres (default 0.05 of the surface's bounding-box
    diagonal). mesher: "auto" (the first installed of pytetwild, tetgen, gmsh: pytetwild
    meshed every surface of docs/meshing.md), or one of them by name. check_volume: warn when
    the mesh's volume differs from the surface's enclosed volume by more than 5 %, and raise
    MeshError below half of it (a mesher that silently lost the solid); surfaces with flipped
    triangles are not checked (their enclosed volume is unknown).

    target_elements: a number of tetrahedra instead of a size, reached within 30 % (at most 4
    passes; else a warning and the closest mesh). epsilon: pytetwild's envelope relative to
    the bounding-box diagonal (fTetWild's -e), or envelope: its width in metres (default
    size / 20); coarsen: fTetWild's --coarsen. smoothing: "taubin" or "sinc" (VTK) smooths a
    staircase (a voxel segmentation) before meshing, keeping the enclosed volume, over
    smoothing_iterations (20). See mesh/from_surface/sizing.py and mesh/from_surface/smoothing.py.

    The mesh has the point and facet set "surface" (its boundary). The report holds mesher,
    seconds, size, n_tets, n_points, min/max dihedral angle (degrees), radius ratio min/mean,
    volume, surface_volume, volume_ratio, the surface's triangles, holes and non-manifold
    edges, the options (epsilon, envelope, coarsen, smoothing's report, target_elements) and
    the passes made. Raises InputError for a bad argument (one line naming it) or a missing
    mesher (with its install line), MeshError for a bad surface, a mesher failure, no
    tetrahedra or inverted ones.
    """
    from tissuesim.mesh.io import describe_mesh

    if not isinstance(check_volume, bool):
        raise InputError(f"check_volume must be True or False, not {short(check_volume)}")
    opts = meshing_options(
        size=size,
        epsilon=epsilon,
        envelope=envelope,
        coarsen=coarsen,
        smoothing=smoothing,
        smoothing_iterations=smoothing_iterations,
        target_elements=target_elements,
    )
    surf = read_surface(surface)
    h = None if opts.target_elements else _size(size, surf)
    name = _choose(mesher)
    if name != "pytetwild" and opts.tetwild():
        raise InputError(
            f"{' and '.join(opts.tetwild())}: options of mesher 'pytetwild' (fTetWild's envelope "
            f"and coarsening), not of {name!r}; leave them out or use mesher 'pytetwild'"
        )
    if not surf.closed:
        warnings.warn(
            f"{surf.source}: the surface is open ({surf.boundary_edges} boundary edges, a hole); "
            f"{name} {'closes it by winding number' if name == 'pytetwild' else 'may fail'}: "
            "check the volume of the mesh",
            UserWarning,
            stacklevel=2,
        )
    smoothed = None
    if opts.smoothing:
        surf, smoothed = smooth_surface(surf, opts.smoothing, opts.smoothing_iterations)
    diag = surf.diagonal

    def once(size: float) -> tuple[Mesh, float]:
        eps = opts.relative_epsilon(diag, size)
        options = {"epsilon": eps, "coarsen": opts.coarsen} if name == "pytetwild" else {}
        return _mesh_once(surf, name, size, options)

    if opts.target_elements:
        mesh, h, seconds, passes = to_count(once, opts.target_elements, surf, surf.source)
    else:
        assert h is not None
        mesh, seconds = once(h)
        passes = [{"size": h, "n_tets": mesh.n_cells, "seconds": round(seconds, 3)}]
    eps = opts.relative_epsilon(diag, h) if name == "pytetwild" else None
    info = describe_mesh(mesh)
    angles = dihedral_angles(mesh.points, mesh.cells)
    sv = abs(surf.volume)  # an inside-out surface encloses the same solid
    report = {
        "source": surf.source,
        "mesher": name,
        "seconds": round(seconds, 3),
        "size": h,
        "n_tets": mesh.n_cells,
        "n_points": mesh.n_points,
        "min_dihedral_deg": float(angles.min()),
        "max_dihedral_deg": float(angles.max()),
        "radius_ratio_min": info["quality_min"],
        "radius_ratio_mean": info["quality_mean"],
        "volume": info["total_volume"],
        "surface_volume": sv,
        "volume_ratio": info["total_volume"] / sv if sv else float("nan"),
        "surface": {
            "triangles": len(surf.faces),
            "closed": surf.closed,
            "boundary_edges": surf.boundary_edges,
            "nonmanifold_edges": surf.nonmanifold_edges,
            "misoriented_edges": surf.misoriented_edges,
            "removed_faces": surf.removed_faces,
        },
        "epsilon": eps,
        "envelope": None if eps is None else eps * diag,
        "coarsen": opts.coarsen,
        "smoothing": smoothed,
        "target_elements": opts.target_elements,
        "passes": passes,
    }
    ratio = report["volume_ratio"]
    estimate = "" if surf.closed else " (an estimate: the surface is open)"
    check_volume = check_volume and not surf.misoriented_edges
    if check_volume and ratio < MIN_VOLUME_RATIO:
        raise MeshError(
            f"{surf.source}: mesher {name!r} made {mesh.n_cells} tetrahedra holding only "
            f"{ratio:.3g} of the volume the surface encloses{estimate}: it lost most of the "
            f"solid (a hole or a self-intersection?); repair the surface, try mesher "
            f"'pytetwild', or pass check_volume=False to keep this mesh"
        )
    if check_volume and not abs(ratio - 1.0) <= VOLUME_TOLERANCE:
        warnings.warn(
            f"{surf.source}: the tetrahedral mesh's volume {report['volume']:.4g} is "
            f"{ratio:.3f} times the surface's enclosed volume {sv:.4g}{estimate}; the surface "
            "may be open, self-intersecting or nested: check the mesh",
            UserWarning,
            stacklevel=2,
        )
    return SurfaceMeshing(mesh=mesh, report=report)


def mesh_surface(
    surface: Any,
    size: float | None = None,
    *,
    mesher: str = "auto",
    check_volume: bool = True,
    target_elements: int | None = None,
    epsilon: float | None = None,
    envelope: float | None = None,
    coarsen: bool = False,
    smoothing: str | None = None,
    smoothing_iterations: int = DEFAULT_SMOOTHING_ITERATIONS,
) -> Mesh:
    """Mesh the solid a triangle surface encloses: a checked P1 tetrahedral ``Mesh``.

    ``mesh_surface("organ.stl", 0.003)`` (size: target edge length in metres, default 0.05 of
    the bounding-box diagonal; mesher "auto" = pytetwild if installed, else tetgen, else gmsh),
    or ``mesh_surface("segmentation.stl", target_elements=10_000, smoothing="taubin")`` (about
    1e4 tetrahedra, within 30 %, after smoothing the voxel staircase). See ``tetrahedralize``
    for the arguments (epsilon, envelope, coarsen, smoothing_iterations), the checks and the
    errors; it also returns the quality report.
    """
    return tetrahedralize(
        surface,
        size,
        mesher=mesher,
        check_volume=check_volume,
        target_elements=target_elements,
        epsilon=epsilon,
        envelope=envelope,
        coarsen=coarsen,
        smoothing=smoothing,
        smoothing_iterations=smoothing_iterations,
    ).mesh

"""Solid shells: a layer of hexahedra (from quadrilaterals) or wedges (from triangles) of a
given thickness on a surface, one or more cells through the thickness.

This is FEBio's shell (``FESSIShellDomain``) as a solid: each surface vertex x and its
director D span the cell's two faces, x on one side and x - D on the other, bilinear (linear)
in the surface and linear through the thickness, and the element's F is the solid's. The
director of a vertex is the mean over the faces around it of each face's unit normal at that
corner (the cross product of its two edges there) times the thickness; ``normalize`` scales
it to the full thickness (on a curved surface FEBio's mean is shorter than the thickness by
the cosine of the normals' spread).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.mesh import Mesh

__all__ = ["solid_shell", "shell_directors", "shell_cells", "read_shell_surface"]

#: where the given surface lies in the shell: its top face (the side its faces' normals point
#: to, FEBio's shell nodes), its middle surface or its bottom face
REFERENCES = {"top": 0.0, "middle": 0.5, "bottom": 1.0}


def shell_directors(
    points: np.ndarray, faces: np.ndarray, thickness: float | np.ndarray, normalize: bool = True
) -> np.ndarray:
    """(n, 3) directors of the points (zero where no face uses a point).

    faces: (k, 3) triangles or (k, 4) quadrilaterals, counter-clockwise seen from the top.
    thickness: a number, or (k, nv) one per face corner (FEBio's ``shell thickness`` data).
    Each corner contributes its unit normal (b - a) x (c - a), a the corner and b, c the next
    and previous corners, times its thickness; a point's director is their mean (FEBio's
    ``FEModel::InitShells``), scaled to the mean thickness when ``normalize``.
    """
    x = np.asarray(points, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    nv = faces.shape[1]
    h = np.broadcast_to(np.asarray(thickness, dtype=np.float64), faces.shape)
    a = x[faces]
    b = x[np.roll(faces, -1, axis=1)]
    c = x[np.roll(faces, 1, axis=1)]
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=-1, keepdims=True)
    if (length <= 0.0).any():
        k = int(np.flatnonzero((length <= 0.0).any(axis=(1, 2)))[0])
        raise MeshError(f"shell face {k} has a corner of zero area (its corners {faces[k]})")
    unit = normal / length
    total = np.zeros_like(x)
    count = np.zeros(len(x))
    thick = np.zeros(len(x))
    for j in range(nv):
        np.add.at(total, faces[:, j], unit[:, j] * h[:, j, None])
        np.add.at(count, faces[:, j], 1.0)
        np.add.at(thick, faces[:, j], h[:, j])
    used = count > 0
    directors = np.zeros_like(x)
    directors[used] = total[used] / count[used, None]
    if normalize:
        size = np.linalg.norm(directors[used], axis=1)
        if (size <= 0.0).any():
            raise MeshError("a shell point's face normals cancel: the surface folds back there")
        directors[used] *= (thick[used] / count[used] / size)[:, None]
    return directors


def shell_cells(
    points: np.ndarray,
    faces: np.ndarray,
    directors: np.ndarray,
    layers: int = 1,
    reference: str = "top",
) -> tuple[np.ndarray, np.ndarray]:
    """(points, cells) of the solid shell: ``layers + 1`` copies of the points, the first at
    the top face (rows 0..n-1), each next one ``directors / layers`` further down; cells
    (k layers, 8) hexahedra or (k layers, 6) wedges in tissuesim's (VTK's / Gmsh's) order,
    bottom face first, layer by layer from the top. On quad8 faces (k, 8): (k layers, 20)
    hexahedra20, their vertical edges' midside nodes appended after the levels (one per
    corner vertex and layer, halfway down it), for the "shell" formulation
    (``kinematics/shell.py``, FEBio's quad8 shell)."""
    if reference not in REFERENCES:
        raise MeshError(f"reference {reference!r}: expected one of {', '.join(REFERENCES)}")
    x = np.asarray(points, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    n = len(x)
    top = x + REFERENCES[reference] * directors
    levels = [top - (i / layers) * directors for i in range(layers + 1)]
    if faces.shape[1] == 8:  # quad8: hexahedra20, a node halfway down each corner's edge
        corners = np.unique(faces[:, :4])
        row = np.full(n, -1)
        row[corners] = np.arange(len(corners))
        start = (layers + 1) * n
        halves = [top[corners] - ((i + 0.5) / layers) * directors[corners] for i in range(layers)]
        cells = [
            np.concatenate(
                [
                    faces[:, :4] + (i + 1) * n,
                    faces[:, :4] + i * n,
                    faces[:, 4:] + (i + 1) * n,
                    faces[:, 4:] + i * n,
                    start + i * len(corners) + row[faces[:, :4]],
                ],
                axis=1,
            )  # fmt: skip
            for i in range(layers)
        ]
        return np.concatenate(levels + halves), np.concatenate(cells)
    cells = [np.concatenate([faces + (i + 1) * n, faces + i * n], axis=1) for i in range(layers)]
    return np.concatenate(levels), np.concatenate(cells)


def solid_shell(
    points: Sequence[Sequence[float]] | np.ndarray,
    faces: Sequence[Sequence[int]] | np.ndarray,
    thickness: float,
    layers: int = 1,
    reference: str = "middle",
    normalize: bool = True,
) -> Mesh:
    """A solid-shell mesh of a surface: hexahedra on quadrilaterals, wedges on triangles,
    hexahedra20 on quad8 quadrilaterals (corners, then the midside nodes of the edges from
    corner 0 to 1, 1 to 2, 2 to 3, 3 to 0: FEBio's quad8 shell, run with the body's
    formulation "shell", ``kinematics/shell.py``).

    points: (n, 3) surface vertices; faces: (k, 4) quadrilaterals, (k, 8) quad8 ones or (k, 3)
    triangles, counter-clockwise seen from the top (their normals point to the top face);
    thickness: the shell's thickness (> 0); layers: cells through the thickness; reference:
    where the surface lies, "middle" (the default: the surface is the wall's mid-surface),
    "top" (FEBio's shell nodes: the shell extends opposite the normals) or "bottom";
    normalize: directors of the full thickness (False: FEBio's mean of unit normals times the
    thickness, shorter on a curved surface).

    Vertex i of the surface is vertex i of the mesh's top face (rows 0..n-1; at the surface
    itself with reference "top"), the levels
    below follow in order (every vertex must belong to a face). Point sets and facet sets:
    "top" and "bottom" (and cell sets "layer0", ... with several layers); each cell's top
    face is the surface's face (cells layer by layer from the top, ``k`` per layer).
    A FEBio quad4 / tri3 shell of the same thickness is this mesh with ``layers=1,
    reference="top", normalize=False`` (``docs/guide/febio.md``, Shells).
    """
    x = np.asarray(points, dtype=np.float64)
    f = np.asarray(faces)
    if x.ndim != 2 or x.shape[1] != 3 or not np.isfinite(x).all():
        raise MeshError(f"shell points must be (n, 3) finite coordinates, got shape {x.shape}")
    if f.ndim != 2 or f.shape[1] not in (3, 4, 8) or len(f) == 0:
        raise MeshError(
            "shell faces must be (k, 3) triangles, (k, 4) quadrilaterals or (k, 8) quad8 "
            f"quadrilaterals, got shape {f.shape}"
        )
    if not np.issubdtype(f.dtype, np.integer) or f.min() < 0 or f.max() >= len(x):
        raise MeshError(f"shell faces must be vertex indices 0..{len(x) - 1}")
    if not (isinstance(layers, (int, np.integer)) and layers >= 1):
        raise MeshError(f"layers must be a whole number >= 1, got {layers!r}")
    h = float(thickness)
    if not (np.isfinite(h) and h > 0.0):
        raise MeshError(f"shell thickness must be a positive number, got {thickness!r}")
    f = f.astype(np.int64)
    unused = np.setdiff1d(np.arange(len(x)), f)
    if len(unused):
        raise MeshError(
            f"{len(unused)} shell points belong to no face (e.g. point {unused[0]}): give the "
            "surface's vertices only"
        )
    directors = shell_directors(x, f, h, normalize=normalize)
    all_points, cells = shell_cells(x, f, directors, int(layers), reference)
    n, k = len(x), len(f)
    return validate_mesh(
        all_points,
        cells,
        source="solid_shell",
        point_sets={"top": np.unique(f), "bottom": np.unique(f) + layers * n},
        facet_sets={"top": f[:, :4], "bottom": f[:, 3::-1] + layers * n},
        cell_sets={f"layer{i}": np.arange(i * k, (i + 1) * k) for i in range(layers)}
        if layers > 1
        else None,
    )


def read_shell_surface(path: str) -> tuple[np.ndarray, np.ndarray]:
    """(points, faces) of a surface file for ``solid_shell``: its triangles (welded, as
    ``mesh_surface`` reads them: STL stores each triangle's corners apart) or, where it has
    no triangles, its quadrilaterals (OBJ, PLY, VTK, Gmsh); one of the two, open or closed."""
    import meshio

    from tissuesim.mesh.from_surface.tetrahedralize import read_surface

    try:
        data = meshio.read(path)
    except Exception as exc:  # noqa: BLE001 - meshio raises many kinds; one line names the file
        raise MeshError(f"{path}: cannot read the surface ({exc})") from None
    kinds = {b.type for b in data.cells if len(b.data)}
    if "triangle" in kinds and "quad" in kinds:
        raise MeshError(f"{path}: a shell surface of triangles or of quadrilaterals, not both")
    if "quad" in kinds:
        quads = np.concatenate([b.data for b in data.cells if b.type == "quad"])
        used, faces = np.unique(quads, return_inverse=True)
        return np.asarray(data.points, dtype=np.float64)[used], faces.reshape(-1, 4)
    surface = read_surface(path)
    return surface.points, surface.faces

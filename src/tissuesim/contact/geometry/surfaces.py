"""The bodies' contact surfaces as maps from the system configuration to collision vertices.

A FEM body's surface vertices are rows of its configuration: V = c[rows], and dV/dq is a
constant 0/1 selection. A frame body's embedded surface moves with its frames by eq. (3),
V = E Z (Z: the frames' virtual nodes, z reshaped (4n, 3)), linear in z. Newton's tangent DOFs
of rigid frames enter through dz_i = T_i(z) dq_i, so for an energy B(V)

    dB/dq = J^T dB/dV,   d2B/dq2 = J^T (d2B/dV2) J + K(z, g_z),   J = (E (x) I_3) diag(T_i),

with g_z = (E (x) I_3)^T dB/dV and K the rotation chart's curvature on each rigid frame's
rotation block (``FrameType.curvature``): the chain rule the frames' own energies use
(frames/tangent_assembly.py). Affine frames have T = I and K = 0. A straight step in q moves a
rigid frame's points on arcs, not on the straight lines CCD sweeps, so such a surface is not
``linear``: Newton then checks each line-search trial with CCD from the current iterate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tissuesim.errors import InputError

__all__ = [
    "CutFemSurface",
    "FemSurface",
    "FrameSurface",
    "cut_faces",
    "fem_surface",
    "frame_surface",
]


@dataclass(frozen=True, eq=False)
class FemSurface:
    """A FEM body's contact vertices ``vertices`` (its mesh's ids), rest positions ``rest``
    (k, d), facets ``triangles`` (m, d: triangles in 3D, edges in 2D) over 0..k-1, and where
    their coordinates are in the system configuration (``config_rows``) and tangent DOFs
    (``tangent_rows``), (d k,)."""

    name: str
    material: object
    vertices: np.ndarray
    rest: np.ndarray
    triangles: np.ndarray
    config_rows: np.ndarray
    tangent_rows: np.ndarray
    linear = True

    @property
    def dim(self) -> int:
        return self.rest.shape[1]

    def positions(self, c: np.ndarray) -> np.ndarray:
        return c[self.config_rows].reshape(-1, self.dim)

    def jacobian(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(row over 0..dk-1, system tangent column, value) of dV/dq."""
        rows = np.arange(self.tangent_rows.size)
        return rows, self.tangent_rows, np.ones(rows.size)

    def curvature(self, c: np.ndarray, g_vertices: np.ndarray):
        return None


@dataclass(frozen=True, eq=False)
class CutFemSurface:
    """A cut FEM body's contact surface (``contact/cut/surface.py``): points embedded in its
    element copies, V = W X with ``embedding`` W (k, n_points) over the body's node positions
    X, ``rest`` (k, d), ``triangles`` (m, d: triangles in 3D, edges in 2D,
    ``contact/cut/surface_2d.py``), the body's ``config`` and ``tangent`` slices."""

    name: str
    material: object
    rest: np.ndarray
    triangles: np.ndarray
    embedding: sp.csr_matrix
    config: slice
    tangent: slice
    #: per point: NaN for the surface's, the area of a contact point of a piece too thin for
    #: a surface (``contact/cut/sliver_points.py``: points without faces, after the surface's)
    point_areas: np.ndarray | None = None
    #: per point: whether it is embedded in a cell a cut bounds (where the cut faces are)
    near_cut: np.ndarray | None = None
    linear = True

    @property
    def dim(self) -> int:
        return self.rest.shape[1]

    def positions(self, c: np.ndarray) -> np.ndarray:
        return self.embedding @ c[self.config].reshape(-1, self.dim)

    def jacobian(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(row over 0..dk-1, system tangent column, value) of dV/dq = W (x) I_d."""
        d, E = self.dim, self.embedding.tocoo()
        rows = (d * E.row[:, None] + np.arange(d)).ravel()
        cols = (self.tangent.start + d * E.col[:, None] + np.arange(d)).ravel()
        return rows, cols, np.repeat(E.data, d)

    def curvature(self, c: np.ndarray, g_vertices: np.ndarray):
        return None


@dataclass(frozen=True, eq=False)
class FrameSurface:
    """A frame body's embedded surface: rest points ``rest`` (k, 3), ``triangles`` (m, 3),
    ``embedding`` (k, 4 n) with V = embedding @ z.reshape(-1, 3), the body's ``config`` and
    ``tangent`` slices of the system and its frame type."""

    name: str
    material: object
    rest: np.ndarray
    triangles: np.ndarray
    embedding: sp.csr_matrix
    frame_type: object
    config: slice
    tangent: slice
    dim = 3

    @property
    def linear(self) -> bool:
        return not self.frame_type.rigid

    def positions(self, c: np.ndarray) -> np.ndarray:
        return self.embedding @ c[self.config].reshape(-1, 3)

    def jacobian(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(row over 0..3k-1, system tangent column, value) of dV/dq = (E (x) I_3) diag T."""
        ft, t = self.frame_type, self.frame_type.tangent_size
        z = c[self.config]
        n = z.size // 12
        T = ft.tangent_map(z).reshape(n, 4, 3, t)  # virtual node a, coordinate, tangent DOF
        E = self.embedding.tocoo()
        frame, node = E.col // 4, E.col % 4
        blocks = E.data[:, None, None] * T[frame, node]  # (nnz, 3, t)
        rows = 3 * E.row[:, None, None] + np.arange(3)[None, :, None]
        cols = self.tangent.start + t * frame[:, None, None] + np.arange(t)[None, None, :]
        rows, cols = np.broadcast_arrays(rows, cols)
        return rows.ravel(), cols.ravel(), blocks.ravel()

    def curvature(self, c: np.ndarray, g_vertices: np.ndarray):
        """(rows, cols, values) over the system's tangent DOFs of K(z, g_z) for rigid frames
        (None for affine ones); g_vertices: dB/dV (k, 3)."""
        if not self.frame_type.rigid:
            return None
        z = c[self.config]
        g_z = (self.embedding.T @ g_vertices).ravel()
        K = self.frame_type.curvature(z, g_z)  # (n, 3, 3)
        n = K.shape[0]
        base = self.tangent.start + 6 * np.arange(n)[:, None, None] + 3
        rows = base + np.arange(3)[None, :, None]
        cols = base + np.arange(3)[None, None, :]
        rows, cols = np.broadcast_arrays(rows, cols)
        return rows.ravel(), cols.ravel(), K.ravel()


def cut_faces(mesh, dhat: float, blade: bool = False) -> tuple[sp.csr_matrix, np.ndarray]:
    """A cut mesh's contact surface (weights over its nodes, facets): ``cut_surface`` in 3D,
    with the gap of a body an instrument in contact cuts (``blade``) or the plain one;
    ``cut_boundary`` in 2D. The rebuild and ``cut_body``'s check before a cut both build it."""
    from tissuesim.contact.cut.surface import BLADE_GAP, GAP, cut_surface
    from tissuesim.contact.cut.surface_2d import cut_boundary

    if mesh.dim == 2:
        return cut_boundary(mesh, dhat)
    return cut_surface(mesh, dhat, BLADE_GAP if blade else GAP)


def fem_surface(
    name: str,
    model,
    config_offset: int,
    tangent_offset: int,
    choice,
    dhat: float = 0.0,
    blade: bool = False,
) -> FemSurface | CutFemSurface:
    """Body ``name``'s contact surface: its boundary (triangles in 3D, edges in 2D), or a
    facet set / facets (``choice``); a cut body's is embedded in its element copies, its cut
    faces a little inside each side for a barrier of activation distance ``dhat`` (m;
    ``contact/cut/surface.py``; ``blade``: an instrument in contact cuts it, and its cut faces
    sit further in, clear of the blade's barrier)."""
    from tissuesim.contact.pairs import contact_facets

    if model.mesh.cell_levels is not None:
        from tissuesim.contact.cut.sliver_points import bare_pieces, sliver_points
        from tissuesim.contact.cut.thin_pieces import thin_surfaces

        if choice is not None:
            raise InputError(
                f"contact surface of {name!r}: the body has been cut, and its contact surface "
                "is its whole boundary with the cut faces; leave its surface out of [contact]"
            )
        W, tri = cut_faces(model.mesh, dhat, blade)
        areas, points = None, None
        if bare_pieces(model.mesh, W, tri).any():  # pieces with no surface (most cuts: none)
            # pieces thinner than the gap: a surface of their own at a smaller scale
            W, tri = thin_surfaces(model.mesh, W, tri, dhat, lambda m, d: cut_faces(m, d, blade))
            points = sliver_points(model.mesh, W, tri, dhat)
        if points is not None:  # pieces too thin for a surface: contact points
            _warn_bare_pieces(name, len(points[1]))
            areas = np.concatenate([np.full(W.shape[0], np.nan), points[1]])
            W = sp.vstack([W, points[0]], format="csr")
        n = model.mesh.n_points * model.mesh.dim
        from tissuesim.contact.cut.surface import level_stack

        bounded = np.isfinite(level_stack(model.mesh)).all(axis=2).any(axis=1)
        copied = np.zeros(model.mesh.n_points)  # nodes of cells a cut bounds
        copied[model.mesh.cells[bounded]] = 1.0
        return CutFemSurface(
            name,
            model.material,
            W @ model.mesh.points,
            tri,
            W,
            slice(config_offset, config_offset + n),
            slice(tangent_offset, tangent_offset + n),
            areas,
            abs(W) @ copied > 0.0,
        )

    d = model.mesh.dim
    tri = contact_facets(name, model.mesh, choice)
    vertices = np.unique(tri)
    local = np.full(model.mesh.n_points, -1)
    local[vertices] = np.arange(vertices.size)
    coords = (d * vertices[:, None] + np.arange(d)).ravel()
    return FemSurface(
        name,
        model.material,
        vertices,
        model.mesh.points[vertices],
        local[tri],
        config_offset + coords,
        tangent_offset + coords,
    )


def frame_surface(name: str, model, embedding, triangles, config: slice, tangent: slice, choice):
    """A frame body's embedded surface (``FrameBody.embed_surface``) as a contact surface; a
    ``choice`` of (k, 3) triangles over the surface's points restricts it."""
    tri = np.asarray(triangles, dtype=np.int64)
    if choice is not None:
        try:
            tri = np.asarray(choice)
            ok = tri.ndim == 2 and tri.shape[1] == 3 and tri.dtype.kind in "iu" and len(tri)
        except (TypeError, ValueError):
            ok = False
        if not ok or (tri.min() < 0 or tri.max() >= len(embedding.points)):
            raise InputError(
                f"contact surface of frame body {name!r}: give (k, 3) integer triangles over "
                f"its embedded surface's {len(embedding.points)} points (frame bodies have no "
                "facet sets)"
            )
    used = np.unique(tri)
    local = np.full(len(embedding.points), -1)
    local[used] = np.arange(used.size)
    return FrameSurface(
        name,
        model.material,
        embedding.points[used],
        local[tri],
        sp.csr_matrix(embedding.matrix)[used],
        model.frame_type,
        config,
        tangent,
    )


def _warn_bare_pieces(name: str, points: int) -> None:
    """Warn that a piece of a cut body is too thin for a contact surface, even one built at
    the thin pieces' smallest scale (``contact/cut/thin_pieces.py``), and is in contact by
    ``points`` points instead (``contact/cut/sliver_points.py``)."""
    import warnings

    from tissuesim.contact.cut.thin_pieces import SCALES

    smallest = f"dhat / {round(1 / min(SCALES))}" if SCALES else "dhat"
    warnings.warn(
        f"contact surface of {name!r}: a piece of the cut body is too thin for a contact "
        f"surface (its cut faces {smallest} inside it leave nothing); it is in contact by "
        f"{points} points inside it instead, which an edge narrower than an element can pass "
        "between (a smaller dhat gives it a surface)",
        stacklevel=2,
    )

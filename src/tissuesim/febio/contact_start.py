"""FEBio's contact surfaces that start touching, set apart for tissuesim's barrier.

FEBio's penalty and augmented-Lagrangian contact take a pair whose faces coincide at the start
(its usual set-up: two blocks stacked face on face); IPC's barrier needs the surfaces apart
(a zero distance is an infinite energy, and coincident faces count as crossed). So a pair
that starts closer than half the barrier's dhat (touching; overlapping by less than dhat,
which the move undoes; a deeper overlap is still refused as crossed at t = 0) has its
secondary surface moved into its own body by ``OFFSET`` dhat: every node of the secondary's
body on that surface (corners, and midside nodes of quadratic faces) along the surface's
normal, the rest of the body unchanged. The elements next to the surface get thinner by the
offset only (1e-3 of the contact surfaces' size). The converted scene then gives ``[contact] dhat``
explicitly, so the pair starts exactly where the barrier begins to act, force-free as
FEBio's, whatever obstacles the scene has; ``convert`` and ``run`` say so in one warning line
naming the contact element, its line and the offset.
"""

from __future__ import annotations

import numpy as np

from tissuesim.febio.model import FebModel

__all__ = ["separate_touching", "DHAT", "OFFSET"]

#: the barrier's dhat written for a model whose contact was set apart, per diagonal of the
#: contact surfaces' bounding box (the contact model's default without obstacles)
DHAT = 1e-3
#: the secondary surface's move, per dhat: the pair starts at dhat, where the barrier's force
#: is zero, so the start is force-free as FEBio's (at dhat / 2 the barrier pushed the stacked
#: blocks of tests/febio 2 % further than FEBio's answer; at dhat, 0.2 %)
OFFSET = 1.0


def _triangles(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """(m, 3, 3) triangles of facets (k, 3) or quadrilaterals (k, 4) split in two."""
    if facets.shape[1] == 3:
        return points[facets]
    halves = np.vstack([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]])
    return points[halves]


def _gap(points: np.ndarray, first: np.ndarray, second: np.ndarray) -> float:
    """The smallest distance between two surfaces (each one's nodes to the other's facets)."""
    from tissuesim.coupling.geometry import point_triangle_distance

    a = point_triangle_distance(points[np.unique(first)], _triangles(points, second))
    b = point_triangle_distance(points[np.unique(second)], _triangles(points, first))
    return float(min(a.min(), b.min()))


def _facet_normals(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """(k, 3) area-weighted normals in the facets' node order (a quad's by its diagonals)."""
    x = points[facets]
    if facets.shape[1] == 4:
        return 0.5 * np.cross(x[:, 2] - x[:, 0], x[:, 3] - x[:, 1])
    return 0.5 * np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])


def _inward_moves(model: FebModel, facets: np.ndarray, cells: np.ndarray, scale: float):
    """(nodes (q,), unit directions (q, 3)): the nodes of the body ``cells`` that lie on the
    surface ``facets``, each with the surface's normal there pointing into the body."""
    from tissuesim.mesh.queries.locate import TriangleSoup

    points = model.nodes
    normals = _facet_normals(points, facets)
    corner = np.zeros_like(points)
    np.add.at(corner, facets.ravel(), np.repeat(normals, facets.shape[1], axis=0))
    # into the body: towards the centroids of the cells around the surface's corners
    centroids = points[cells].mean(axis=1)
    sums, counts = np.zeros_like(points), np.zeros(len(points))
    np.add.at(sums, cells.ravel(), np.repeat(centroids, cells.shape[1], axis=0))
    np.add.at(counts, cells.ravel(), 1.0)
    ends = np.unique(facets)
    inward = sums[ends] / np.maximum(counts[ends], 1.0)[:, None] - points[ends]
    sign = -1.0 if np.einsum("ij,ij->", corner[ends], inward) < 0 else 1.0
    # every node of the body on the surface, midside and face-centre nodes too
    nodes = np.unique(cells)
    soup = TriangleSoup(_triangles(points, facets))
    tri, _, _, distance = soup.closest(points[nodes], max_distance=1e-9 * scale)
    on = np.isfinite(distance)
    nodes, tri = nodes[on], tri[on]
    owner = facets[tri % len(facets)] if facets.shape[1] == 4 else facets[tri]
    direction = corner[owner].mean(axis=1)  # a facet's corners' normals, averaged
    direction[np.isin(nodes, ends)] = corner[nodes[np.isin(nodes, ends)]]
    direction *= sign / np.linalg.norm(direction, axis=1, keepdims=True)
    return nodes, direction


def separate_touching(model: FebModel, bodies: list[dict]) -> float | None:
    """Move the secondary surface of every contact pair that starts touching (closer than
    half ``OFFSET`` dhat) into its body by ``OFFSET`` dhat, in ``model.nodes``; each move is
    one line in ``model.changes``. Returns the dhat to write in ``[contact]`` (None: nothing
    moved)."""
    # penalty contact (FEBio's own enforcement) takes surfaces that touch as they are
    pairs = [c for c in model.contacts if c["type"] != "rigid_wall" and "penalty" not in c]
    if not pairs:
        return None
    touching = np.unique(np.concatenate([model.surfaces[s][0].ravel() for c in pairs
                                         for s in c["surfaces"]]))  # fmt: skip
    scale = float(np.linalg.norm(np.ptp(model.nodes[touching], axis=0)))
    dhat = DHAT * scale
    offset = OFFSET * dhat
    moved = False
    for c in pairs:
        first, second = (model.surfaces[s][0] for s in c["surfaces"])
        gap = _gap(model.nodes, first, second)
        if gap >= 0.5 * offset:
            continue
        owner = [next((b for b in bodies if np.isin(f, b["cells"]).all()), None)
                 for f in (first, second)]  # fmt: skip
        body = owner[1]
        if body is None or owner[0] is body:
            continue  # on no body, or a body with itself: refused where the pairs are written
        nodes, direction = _inward_moves(model, second, body["cells"], scale)
        model.nodes[nodes] += offset * direction
        state = "touching" if gap == 0.0 else f"{gap:.3g} apart"
        model.changes.append(
            f"{c['node'].where()}: contact surfaces {c['surfaces'][0]!r} and "
            f"{c['surfaces'][1]!r} start {state}: tissuesim's barrier needs them apart, so the "
            f"secondary {c['surfaces'][1]!r} ({len(nodes)} nodes) is moved {offset:.3g} (model "
            f"units) into its body, the barrier's dhat (written in [contact]), so the pair starts "
            "apart with no force; the result differs from FEBio's by at most that displacement"
        )
        moved = True
    return dhat if moved else None

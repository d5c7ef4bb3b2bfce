"""How well the contact surface of a cut body holds up where cuts meet: random oblique cuts
through a 1 x 0.4 x 0.3 m box of 10 x 4 x 3 cells (720 tetrahedra), dhat = 10 mm.

Six families of 40 each (one seeded generator each, so the runs repeat): one oblique cut
(for reference), two oblique through cuts crossing, a T (the second cut ends where it meets
the first, give or take 3 cm), a cut along a mesh plane (through a layer of nodes: it parts
nodes and copies no cell) crossed by an oblique one, and three and four oblique cuts through
about one point (each case has a cell all of them cross; of four, two run about the same
way). For each: how many cut surfaces are closed and consistently oriented (each directed
edge once with its reverse), manifold, free of intersection (ipctk's exact test), how many
came within 0.3 dhat of themselves at rest (two primitives that share no vertex; IPC's
barrier pushes such pairs apart) and the closest such pair, and how many were refused
(``cut_surface`` refuses none of these now; the column stays for comparison).

    python3 benchmarks/crossing_surfaces.py      # writes benchmarks/results/crossing_surfaces.md
"""

from __future__ import annotations

from pathlib import Path

import ipctk
import numpy as np

import tissuesim as ts
from tissuesim.contact.cut.surface import cut_surface
from tissuesim.errors import InputError
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut

HERE = Path(__file__).resolve().parent
BOX = ts.box((0.0, 0.0, 0.0), (1.0, 0.4, 0.3), (10, 4, 3))
DHAT = 0.01
N = 40


def plane(point: np.ndarray, normal: np.ndarray, up_to: float = 3.0) -> PlanarCut:
    """The plane through ``point`` with ``normal``; its polygon reaches ``up_to`` along the
    in-plane direction that goes with +x (and 3 m everywhere else)."""
    n = normal / np.linalg.norm(normal)
    u = np.cross(n, [0.0, 0.0, 1.0])
    if np.linalg.norm(u) < 1e-9:  # a horizontal plane
        u = np.cross(n, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    u = u if u[0] > 0 else -u
    w = np.cross(n, u)
    corners = [point + a * u + b * w for a, b in ((-3, -3), (up_to, -3), (up_to, 3), (-3, 3))]
    return PlanarCut(point, n, np.array(corners))


def family(kind: str, seed: int) -> list[list[PlanarCut]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(N):
        n1 = np.array([1.0, 0, 0]) + 0.4 * rng.normal(size=3)
        n2 = np.array([0, 1.0, 0]) + 0.4 * rng.normal(size=3)
        p1 = np.array([0.5, 0.2, 0.15]) + 0.05 * rng.normal(size=3)
        first = plane(p1, n1)
        if kind == "one cut":
            out.append([first])
        elif kind == "along faces":  # a mesh plane (it parts nodes, copies no cell), crossed
            axis = int(rng.integers(3))
            value = rng.choice(
                {0: [0.3, 0.4, 0.5, 0.6, 0.7], 1: [0.1, 0.2, 0.3], 2: [0.1, 0.2]}[axis]
            )
            normal = np.eye(3)[axis]
            along = plane(normal * value, normal)
            oblique = np.eye(3)[(axis + 1) % 3] + 0.4 * rng.normal(size=3)
            out.append([along, plane(p1, oblique)])
        elif kind in ("three", "four"):
            axes = [0, 1, 2] if kind == "three" else [0, 1, 2, 0]
            near = [p1 + 0.01 * rng.normal(size=3) for _ in axes]
            out.append([plane(q, np.eye(3)[a] + 0.4 * rng.normal(size=3))
                        for q, a in zip(near, axes, strict=True)])  # fmt: skip
        elif kind == "crossing":
            out.append([first, plane(p1 + [0.02, 0, 0], n2)])
        else:  # a T: the second from the far side to about the first
            p2 = np.array([0.3, 0.23, 0.15]) + 0.03 * rng.normal(size=3)
            n = n2 / np.linalg.norm(n2)
            u = np.cross(n, [0.0, 0.0, 1.0])
            u /= np.linalg.norm(u)
            u = u if u[0] > 0 else -u
            end = (p1[0] - p2[0]) / u[0] + 0.03 * rng.normal()
            out.append([first, plane(p2, n2, end)])
    return out


def check(cuts: list[PlanarCut]) -> dict | None:
    vn = virtual_node_cut(BOX.points, BOX.cells, cuts)
    mesh = vn.to_mesh(BOX)
    try:
        W, tri = cut_surface(mesh, DHAT)
    except InputError:
        return None
    V = W @ mesh.points
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    directed = edges[:, 0] * len(V) + edges[:, 1]
    reverse = edges[:, 1] * len(V) + edges[:, 0]
    collision_mesh = ipctk.CollisionMesh(
        np.asfortranarray(V), ipctk.edges(tri.astype(np.int32)), tri
    )
    close = ipctk.NormalCollisions()
    close.build(collision_mesh, V, 0.3 * DHAT)
    E, F = collision_mesh.edges, collision_mesh.faces
    gaps = [np.sqrt(c.compute_distance(c.dof(V, E, F))) / DHAT for c in close]
    return {
        "several": vn.extra is not None,
        "closed": bool(np.isin(reverse, directed).all()),
        "manifold": np.unique(directed).size == directed.size,
        "intersecting": bool(ipctk.has_intersections(collision_mesh, V)),
        "closest": min(gaps, default=np.inf),
    }


def main() -> None:
    lines = [
        "# Contact surfaces where cuts meet (benchmarks/crossing_surfaces.py)",
        "",
        f"`python3 benchmarks/crossing_surfaces.py`: {N} random cases per family, the box of "
        "10 x 4 x 3 cells, dhat = 10 mm.",
        "",
        "| family | refused | cells cut by several (cases) | closed and oriented | manifold "
        "| intersecting | within 0.3 dhat at rest (cases) | closest pair (dhat) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    kinds = ("one cut", "crossing", "T", "along faces", "three", "four")
    for seed, kind in enumerate(kinds):
        results = [check(cuts) for cuts in family(kind, 11 + seed)]
        done = [r for r in results if r is not None]
        closest = min((r["closest"] for r in done), default=np.inf)
        lines.append(
            f"| {kind} | {len(results) - len(done)} | {sum(r['several'] for r in done)} "
            f"| {sum(r['closed'] for r in done)} / {len(done)} "
            f"| {sum(r['manifold'] for r in done)} | {sum(r['intersecting'] for r in done)} "
            f"| {sum(r['closest'] < 0.3 for r in done)} "
            f"| {'-' if not np.isfinite(closest) else f'{closest:.3f}'} |"
        )
        print(lines[-1], flush=True)
    out = HERE / "results" / "crossing_surfaces.md"
    out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

"""A notch cut through the cells against the same notch made with the mesh (the mesh's grid
plane moved onto it, split along faces): how the difference in tip deflection depends on the
element size where the cut crosses the body and on where in the cell it falls.

The cantilever: 1 x 0.2 x 0.2 m, E = 1 MPa, nu = 0.3, clamped at x = 0, 20 N down on its end,
quasistatic; notched from the top down to half its depth at x = x0 near the root. The mesh has
cells 0.05 m long in x except in 0.1 <= x <= 0.4, where they are h long (4 x 4 cells across,
6 tetrahedra each). The cut falls at x0 = 0.2 + f h.

    python3 benchmarks/notched_cantilever.py   # writes benchmarks/results/notched_cantilever.md
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import tissuesim as ts
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut
from tissuesim.mesh.mesh import Mesh

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e6, poisson_ratio=0.3)
DEPTH = 0.2


def notch(x0: float) -> PlanarCut:
    """The plane x = x0 from the top face down to half the depth."""
    poly = np.array([[x0, -1.0, 0.1], [x0, 2.0, 0.1], [x0, 2.0, 1.0], [x0, -1.0, 1.0]])
    return PlanarCut(np.array([x0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), poly)


def grid_lines(h: float, lo: float = 0.1, hi: float = 0.4, h_far: float = 0.05) -> np.ndarray:
    """x of the grid planes: h_far apart outside [lo, hi], h apart inside."""
    near = lo + h * np.arange(round((hi - lo) / h) + 1)
    far = np.concatenate([np.arange(0.0, lo - 1e-12, h_far), np.arange(hi, 1.0 + 1e-12, h_far)])
    return np.unique(np.round(np.concatenate([far, near, [1.0]]), 12))


def beam(xs: np.ndarray, n: int = 4) -> Mesh:
    """A box with its grid planes at xs (the generator's planes mapped one to one)."""
    box = ts.box((0.0, 0.0, 0.0), (1.0, DEPTH, DEPTH), (len(xs) - 1, n, n))
    points = box.points.copy()
    points[:, 0] = xs[np.rint(points[:, 0] * (len(xs) - 1)).astype(int)]
    return Mesh(points, box.cells, point_sets=box.point_sets, source="graded box")


def tip_deflection(mesh: Mesh) -> float:
    """Mean vertical displacement of the loaded end (m)."""
    sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=1.0)
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9))
    end = np.flatnonzero(mesh.points[:, 0] > 1.0 - 1e-9)
    sim.add_nodal_forces(end, (0.0, 0.0, -20.0 / len(end)))
    sim.step()
    return float(sim.displacement[end, 2].mean())


def compare(h: float, fraction: float) -> tuple[float, float]:
    """Tip deflections (embedded cut, conforming notch) for a cut at 0.2 + fraction h."""
    x0 = 0.2 + fraction * h
    xs = grid_lines(h)
    moved = xs.copy()
    moved[np.argmin(np.abs(xs - x0))] = x0  # the nearest plane onto the notch: made with it
    return tip_deflection(cut(beam(xs), x0)), tip_deflection(cut(beam(moved), x0))


def cut(mesh: Mesh, x0: float) -> Mesh:
    """The mesh notched at x0 by virtual nodes (along faces where a grid plane is at x0)."""
    return virtual_node_cut(mesh.points, mesh.cells, [notch(x0)]).to_mesh(mesh)


def main() -> None:
    rows = []
    for parts in (4, 8, 16, 24):
        h = DEPTH / parts
        worst = 0.0
        cells = []
        for fraction in (0.2, 0.4, 0.5, 0.6, 0.8):
            embedded, conforming = compare(h, fraction)
            diff = 100 * (embedded / conforming - 1)
            worst = max(worst, abs(diff))
            cells.append(f"{1e3 * abs(embedded):.2f} / {1e3 * abs(conforming):.2f} ({diff:+.2f} %)")
            print(parts, fraction, cells[-1], flush=True)
        rows.append(f"| depth / {parts} | " + " | ".join(cells) + f" | {worst:.2f} % |")
    head = "| cell length h at the cut | " + " | ".join(
        f"x0 = 0.2 + {f} h" for f in (0.2, 0.4, 0.5, 0.6, 0.8)
    )
    table = [
        "# Notch cut through the cells against the notch made with the mesh",
        "",
        "Tip deflection in mm, embedded cut / conforming notch (difference); "
        "`python3 benchmarks/notched_cantilever.py`.",
        "",
        head + " | largest |",
        "|" + " --- |" * 7,
        *rows,
        "",
    ]
    out = Path(__file__).parent / "results" / "notched_cantilever.md"
    out.write_text("\n".join(table))
    print("\n".join(table))


if __name__ == "__main__":
    main()

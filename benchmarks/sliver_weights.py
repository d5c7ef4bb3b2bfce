"""What weighting a sliver's contact points costs (``contact/sliver_points.weigh_points``): a
Python loop over the collisions, run after every collision build while a cut body has a piece
too thin for a contact surface. Two parallel grids of 40 x 40 vertices (3,042 triangles each)
5 mm apart with dhat = 10 mm give about 37,000 collisions; five of the vertices are made
points. Medians of 5 runs of the build and of the weighting, and their ratio.

    python3 benchmarks/sliver_weights.py
"""

from __future__ import annotations

import statistics
import time

import ipctk
import numpy as np

from tissuesim.contact.cut.sliver_points import weigh_points


def grids(n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    xs, ys = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    P = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(n * n)])
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:]
    T = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d.ravel()], 1)])
    V = np.vstack([P, P + [0.003, 0.002, 0.005]])
    return V, np.vstack([T, T + n * n]).astype(np.int32)


def main() -> None:
    V, F = grids()
    mesh = ipctk.CollisionMesh(V, ipctk.edges(F), F)
    area = np.full(len(V), np.nan)
    area[:5] = 1e-4
    builds, weighs = [], []
    for _ in range(5):
        col = ipctk.NormalCollisions()
        col.use_area_weighting = True
        start = time.perf_counter()
        col.build(mesh, V, 0.01)
        builds.append(time.perf_counter() - start)
        start = time.perf_counter()
        weigh_points(col, area)
        weighs.append(time.perf_counter() - start)
    b, w = statistics.median(builds), statistics.median(weighs)
    per = 1e6 * w / len(col)
    print(f"{len(col)} collisions: build {1e3 * b:.1f} ms, weighting {1e3 * w:.1f} ms "
          f"({per:.2f} us per collision), weighting / build {w / b:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()

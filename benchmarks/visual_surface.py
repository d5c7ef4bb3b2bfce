"""What a fine visual surface on a coarse body costs (``Simulation.add_visual_surface``).

    python3 benchmarks/visual_surface.py [--divisions 12] [--repeats 3] [--no-render]

A liver-sized ellipsoid (0.12 x 0.08 x 0.04 m) of ``divisions`` 12 (10,368 tetrahedra)
carries the true ellipsoid's surface as a UV sphere of 100,002 points and 200,000 triangles:
every point lies outside the coarse mesh (its boundary is inscribed), by up to 0.2 mm. One
thread. Per repeat (median): embedding the surface once (``mesh/queries/embedding.py``), carrying
it to a deformed state (one sparse product), writing one frame of its VTU series, and
drawing final.png with the fine surface and with the coarse one (PyVista).
Results: ``results/visual_surface.md``.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

RADII = np.array([0.06, 0.04, 0.02])


def uv_ellipsoid(nu: int = 500, nv: int = 202) -> tuple[np.ndarray, np.ndarray]:
    """The ellipsoid's surface: nu points per ring, nv - 2 rings and the two poles."""
    th = np.linspace(0, np.pi, nv)[1:-1]
    ph = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    T, P = (a.ravel() for a in np.meshgrid(th, ph, indexing="ij"))
    ring = np.column_stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)])
    pts = np.vstack([ring, [[0, 0, 1], [0, 0, -1]]]) * RADII
    rows, top, bottom = len(th), len(pts) - 2, len(pts) - 1
    idx = np.arange(rows * nu).reshape(rows, nu)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1], nxt[:-1], nxt[1:], idx[1:]
    tris = [np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    tris += [np.column_stack([np.full(nu, top), idx[0], nxt[0]])]
    tris += [np.column_stack([np.full(nu, bottom), nxt[-1], idx[-1]])]
    return pts, np.concatenate(tris)


def timed(f) -> float:
    start = time.perf_counter()
    f()
    return time.perf_counter() - start


def main() -> None:
    import tissuesim as ts
    from tissuesim.bodies.visual_surface import make_visual_surface
    from tissuesim.io.series.vtu import VTUSeriesWriter
    from tissuesim.mesh.queries.embedding import embed_points

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--divisions", type=int, default=12)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-render", action="store_true")
    args = parser.parse_args()
    mesh = ts.ellipsoid((0, 0, 0), tuple(RADII), args.divisions)
    pts, tris = uv_ellipsoid()
    visual = make_visual_surface("fine", "liver", mesh, (pts, tris))
    e = visual.embedding
    x = mesh.points * [1.02, 0.99, 0.97] + 0.001 * np.sin(40 * mesh.points)
    times: dict[str, list[float]] = {"embed": [], "carry": [], "vtu": []}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeats):
            times["embed"].append(timed(lambda: embed_points(mesh, pts)))
            times["carry"].append(timed(lambda: visual.positions(x)))
            writer = VTUSeriesWriter(tmp, None, "fine", cells=("triangle", tris), n_points=len(pts))
            u = visual.positions(x) - pts
            write = writer.write
            times["vtu"].append(timed(lambda w=write, u=u: w(0.0, pts, {"displacement": u})))
        if not args.no_render:
            times.update(render(mesh, visual, x, Path(tmp), args.repeats))
    print(
        f"{mesh.n_cells} tetrahedra, {len(pts)} surface points, {len(tris)} triangles; "
        f"{int(e.outside.sum())} points outside, by up to {e.distance.max() * 1e3:.3f} mm "
        f"({(e.distance / e.size).max():.3f} of their element)"
    )
    for key, values in times.items():
        print(f"{key:>14}: {statistics.median(values) * 1e3:9.1f} ms (median of {len(values)})")


def render(mesh, visual, x, tmp: Path, repeats: int) -> dict[str, list[float]]:
    from tissuesim.mesh.queries.boundary import boundary_facets
    from tissuesim.render.pyvista3d import Frame3D, SurfaceLayer, render_frame_png

    vals = np.linalg.norm(x - mesh.points, axis=1)
    coarse = SurfaceLayer("liver", x, boundary_facets(mesh.simplices), scalars=vals)
    fine = SurfaceLayer(
        "liver", visual.positions(x), visual.cells, scalars=visual.embedding.interpolate(vals)
    )
    out: dict[str, list[float]] = {"png coarse": [], "png fine": []}
    for _ in range(repeats):
        for key, layer in (("png coarse", coarse), ("png fine", fine)):
            frame = Frame3D([layer], title="t = 0 s")
            out[key].append(timed(lambda f=frame: render_frame_png(tmp / "p.png", f)))
    return out


if __name__ == "__main__":
    main()

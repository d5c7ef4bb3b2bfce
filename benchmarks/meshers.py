"""Robustness of the tetrahedral meshers behind ``tissuesim.mesh_surface`` on five surfaces.

Each mesher (pytetwild, tetgen, gmsh; those installed) meshes each surface through
``tissuesim.mesh.from_surface.tetrahedralize.tetrahedralize`` at its default size (0.05 of the
bounding-box diagonal), in a child process of its own (a crash or a hang is recorded, not fatal).
Recorded: did it give a mesh (or the error), tetrahedra, seconds, min dihedral angle, min radius
ratio, and the mesh's volume over the reference volume of the solid (analytic for a and b, the
closed surface's enclosed volume for c and d, the intact surface's for e). The surfaces, in metres:

- a clean: an ellipsoid (semi-axes 50, 30, 20 mm), icosphere of 5120 triangles, scaled
- b touching: two spheres (r = 20 mm) that share one vertex (a non-manifold vertex)
- c defects: the ellipsoid with 5 % of its triangles flipped and 10 duplicated
- d segmentation: marching cubes (pyvista ImageData.contour) of a noisy voxel blob, 1 mm voxels
- e hole: the ellipsoid with a cap of triangles removed (an open surface)

    python benchmarks/meshers.py                 # markdown table to stdout
    python benchmarks/meshers.py --out benchmarks/results/meshers.md

Needs pyvista (the test extra) and the meshers: pip install pytetwild tetgen gmsh.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CASES = {
    "a": "clean ellipsoid",
    "b": "two spheres touching at a vertex",
    "c": "flipped + duplicated triangles",
    "d": "segmentation (marching cubes)",
    "e": "hole (open surface)",
}
RADII = np.array([0.05, 0.03, 0.02])


def _icosphere(nsub: int = 4) -> tuple[np.ndarray, np.ndarray]:
    import pyvista as pv

    s = pv.Icosphere(radius=1.0, nsub=nsub)
    return np.asarray(s.points, dtype=float), s.faces.reshape(-1, 4)[:, 1:].astype(np.int64)


def _write(path: Path, points: np.ndarray, faces: np.ndarray) -> None:
    import meshio

    meshio.write_points_cells(path, points, [("triangle", faces)], binary=True)


def make_surfaces(directory: Path, seed: int = 0) -> dict[str, tuple[Path, float]]:
    """STL files of the five cases and their reference volumes (m^3)."""
    rng = np.random.default_rng(seed)
    p, f = _icosphere()
    ellipsoid = p * RADII
    out = {}

    def ref(pts, faces):
        x = pts[faces]
        return float(np.einsum("ki,ki->k", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6)

    out["a"] = (ellipsoid, f, 4 / 3 * np.pi * RADII.prod())
    r = 0.02
    tip = int(np.argmax(p[:, 0]))
    a_pts, b_pts = p * r, p * r + 2 * p[tip] * r  # B's min-x vertex lands on A's max-x one
    out["b"] = (np.vstack([a_pts, b_pts]), np.vstack([f, f + len(p)]), 2 * 4 / 3 * np.pi * r**3)
    bad = f.copy()
    flip = rng.choice(len(f), len(f) // 20, replace=False)
    bad[flip] = bad[flip][:, ::-1]
    bad = np.vstack([bad, f[rng.choice(len(f), 10, replace=False)]])
    out["c"] = (ellipsoid, bad, ref(ellipsoid, f))
    out["d"] = _segmentation(rng)
    centre = ellipsoid[f].mean(axis=1)
    keep = centre[:, 2] < 0.9 * RADII[2]  # remove the cap z > 0.9 c
    out["e"] = (ellipsoid, f[keep], ref(ellipsoid, f))
    files = {}
    for key, (pts, faces, volume) in out.items():
        path = directory / f"{key}.stl"
        _write(path, pts, faces)
        files[key] = (path, float(volume))
    return files


def _segmentation(rng) -> tuple[np.ndarray, np.ndarray, float]:
    """A noisy binary blob (largest component) of 1 mm voxels, contoured at 0.5."""
    import pyvista as pv
    from scipy import ndimage

    h, n = 1e-3, 72
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    level = np.sqrt((X / 0.028) ** 2 + (Y / 0.02) ** 2 + (Z / 0.016) ** 2)
    noise = ndimage.gaussian_filter(rng.standard_normal((n, n, n)), 2.0)
    mask = level + 2.5 * noise < 1.0
    mask[[0, -1]] = mask[:, [0, -1]] = mask[:, :, [0, -1]] = False  # closed: off the border
    labels, _ = ndimage.label(mask)
    sizes = np.bincount(labels.ravel())[1:]
    mask = labels == 1 + int(np.argmax(sizes))
    img = pv.ImageData(dimensions=(n, n, n), spacing=(h, h, h), origin=(x[0],) * 3)
    img.point_data["mask"] = mask.ravel(order="F").astype(float)
    s = img.contour([0.5], scalars="mask").triangulate().clean()
    faces = s.faces.reshape(-1, 4)[:, 1:].astype(np.int64)
    pts = np.asarray(s.points, dtype=float)
    x3 = pts[faces]
    volume = float(np.einsum("ki,ki->k", x3[:, 0], np.cross(x3[:, 1], x3[:, 2])).sum() / 6)
    return pts, faces, abs(volume)


def one(path: str, mesher: str, reference: float) -> dict:
    """Mesh one file with one mesher (run in a child process)."""
    import warnings

    from tissuesim.mesh.from_surface.tetrahedralize import tetrahedralize

    started = time.perf_counter()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            # pytetwild with fTetWild's own envelope (1e-3 of the diagonal), the default when
            # docs/meshing.md's table was measured (now size / 20: mesh_to_size.py)
            extra = {"epsilon": 1e-3} if mesher == "pytetwild" else {}
            r = tetrahedralize(path, mesher=mesher, check_volume=False, **extra).report
    except Exception as exc:
        return {
            "ok": False,
            "error": f"{type(exc).__name__}: {exc}",
            "s": time.perf_counter() - started,
        }
    return {
        "ok": True,
        "tets": r["n_tets"],
        "s": r["seconds"],
        "min_dihedral": r["min_dihedral_deg"],
        "radius_ratio": r["radius_ratio_min"],
        "volume_ratio": r["volume"] / reference,
        "warnings": [str(w.message) for w in caught],
        "surface": r["surface"],
    }


def _cell(res: dict) -> str:
    if not res["ok"]:
        text = res["error"]
        if "no tetrahedra" in text:
            why = "0 tets, no exception"
        elif "failed (" in text:
            why = text.split("failed (", 1)[1].split(":", 1)[-1].split(";")[0].strip(" )")[:60]
        else:
            why = text[:60]
        return f"**fails** ({why})"
    lost = " **lost the solid**" if res["volume_ratio"] < 0.5 else ""
    return (
        f"{res['tets']} tets, {res['s']:.1f} s, {res['min_dihedral']:.1f} deg, "
        f"rr {res['radius_ratio']:.2f}, V {res['volume_ratio']:.3f}{lost}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", help="also write the markdown table to this file")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per mesher run")
    parser.add_argument("--one", nargs=3, metavar=("FILE", "MESHER", "VOLUME"), help="internal")
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(one(args.one[0], args.one[1], float(args.one[2]))))
        return 0
    from tissuesim.mesh.from_surface.meshers import available_meshers

    meshers = available_meshers()
    results: dict[tuple[str, str], dict] = {}
    with tempfile.TemporaryDirectory(prefix="tissuesim-meshers-") as tmp:
        files = make_surfaces(Path(tmp))
        for key, (path, volume) in files.items():
            for mesher in meshers:
                cmd = [sys.executable, __file__, "--one", str(path), mesher, repr(volume)]
                try:
                    run = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
                    lines = run.stdout.strip().splitlines()
                    res = (
                        json.loads(lines[-1])
                        if run.returncode == 0 and lines
                        else {
                            "ok": False,
                            "error": f"crashed (exit {run.returncode}): {run.stderr[-200:]}",
                        }
                    )
                except subprocess.TimeoutExpired:
                    res = {"ok": False, "error": f"timeout: over {args.timeout:g} s"}
                results[key, mesher] = res
                print(f"{key} {mesher}: {json.dumps(res)}", file=sys.stderr)
    lines = [
        "# Tetrahedral meshers on five surfaces",
        "",
        "`python benchmarks/meshers.py`; each cell: tetrahedra, mesher seconds, min dihedral "
        "angle, min radius ratio (rr), mesh volume / reference volume (V); default size 0.05 "
        "of the bounding-box diagonal.",
        "",
        "| case | " + " | ".join(meshers) + " |",
        "| --- |" + " --- |" * len(meshers),
    ]
    for key, title in CASES.items():
        row = [_cell(results[key, m]) for m in meshers]
        lines.append(f"| {key} {title} | " + " | ".join(row) + " |")
    table = "\n".join(lines) + "\n"
    print(table)
    if args.out:
        Path(args.out).write_text(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())

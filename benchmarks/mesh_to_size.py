"""Meshing a segmentation to a size and to an element count (issue 41).

Two surfaces of one organ, an ellipsoid of semi-axes 60, 40, 30 mm (12 x 8 x 6 cm):

- smooth: an icosphere (20480 triangles) scaled to the ellipsoid;
- staircase: a voxel segmentation as an STL: the ellipsoid voxelised at 1 mm with label noise
  (its boundary moved by Gaussian noise of 1 mm amplitude, correlated over 2 voxels), the
  largest component contoured by marching cubes (VTK's flying edges through PyVista).

Part "sizes": ``tetrahedralize`` at sizes 14, 10 and 7 mm with fTetWild's fixed envelope (epsilon
1e-3 of the diagonal, the default before issue 41), the new default (envelope = size / 20) and
the staircase smoothed first (Taubin, 20 iterations). Part "options": the staircase at 14 and
10 mm with coarsening, a 1 mm envelope, more smoothing and VTK's sinc filter. Part "counts":
``target_elements`` 1e4, 2e4, 4e4 on each surface (the staircase raw and smoothed): the count
obtained, the passes it took, the time and the quality (min dihedral angle, min radius ratio,
volume over the surface's).

    python benchmarks/mesh_to_size.py --out benchmarks/results/mesh_to_size.md
    python benchmarks/mesh_to_size.py --quick          # one size, one count: a check it runs

fTetWild runs on one thread (TISSUESIM_MESH_THREADS=1 unless set), so the seconds are one
core's; its counts vary by a few % from run to run even so. Needs pyvista (the test extra).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

RADII = (0.06, 0.04, 0.03)
VOXEL = 1e-3


def staircase(
    radii: tuple[float, float, float] = RADII,
    voxel: float = VOXEL,
    noise: float = VOXEL,
    correlation: float = 2.0,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """(points (n, 3), triangles (k, 3)) of a voxelised ellipsoid with label noise, contoured.

    The mask is {d + noise * w < 0}, d the signed distance to the ellipsoid (to first order),
    w Gaussian noise smoothed over ``correlation`` voxels and scaled to unit deviation; its
    largest component, off the image border, is contoured at 0.5 (a closed staircase).
    """
    import pyvista as pv
    from scipy import ndimage

    r = np.asarray(radii, dtype=float)
    pad = 3 + int(np.ceil(3 * noise / voxel))
    n = np.ceil(2 * r / voxel).astype(int) + 2 * pad
    axes = [(np.arange(k) - (k - 1) / 2) * voxel for k in n]
    x = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    level = np.sqrt(((x / r) ** 2).sum(axis=-1))
    gradient = np.linalg.norm(x / r**2, axis=-1) / np.maximum(level, 1e-12)
    d = (level - 1.0) / np.maximum(gradient, 1e-12)
    if noise > 0:
        white = np.random.default_rng(seed).standard_normal(tuple(n))
        w = ndimage.gaussian_filter(white, correlation)
        d = d + noise * w / w.std()
    mask = d < 0
    mask[[0, -1]] = mask[:, [0, -1]] = mask[:, :, [0, -1]] = False
    labels, _ = ndimage.label(mask)
    mask = labels == 1 + int(np.argmax(np.bincount(labels.ravel())[1:]))
    image = pv.ImageData(dimensions=mask.shape, spacing=(voxel,) * 3, origin=[a[0] for a in axes])
    image.point_data["mask"] = mask.ravel(order="F").astype(float)
    s = image.contour([0.5], scalars="mask").triangulate().clean()
    return np.asarray(s.points, dtype=float), s.faces.reshape(-1, 4)[:, 1:].astype(np.int64)


def smooth(radii: tuple[float, float, float] = RADII) -> tuple[np.ndarray, np.ndarray]:
    """An icosphere of 20480 triangles scaled to the ellipsoid."""
    import pyvista as pv

    s = pv.Icosphere(radius=1.0, nsub=5)
    faces = s.faces.reshape(-1, 4)[:, 1:].astype(np.int64)
    return np.asarray(s.points, dtype=float) * np.asarray(radii), faces


def one(surface: tuple, **options) -> dict:
    """Mesh once; the figures of the report (and the warnings it gave)."""
    from tissuesim.mesh.from_surface.tetrahedralize import tetrahedralize

    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = tetrahedralize(surface, **options).report
    return {
        "options": {k: v for k, v in options.items() if k != "size" or v is not None},
        "size": r["size"],
        "envelope": r["envelope"],
        "n_tets": r["n_tets"],
        "passes": r["passes"],
        "mesher_s": r["seconds"],
        "total_s": round(time.perf_counter() - started, 2),
        "min_dihedral": r["min_dihedral_deg"],
        "radius_ratio": r["radius_ratio_min"],
        "volume_ratio": r["volume_ratio"],
        "smoothing": r["smoothing"],
        "triangles": r["surface"]["triangles"],
        "warnings": [str(w.message)[:200] for w in caught],
    }


def _quality(row: dict) -> str:
    return f"{row['min_dihedral']:.1f} / {row['radius_ratio']:.3f} / {row['volume_ratio']:.4f}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", help="write the markdown tables to this file")
    parser.add_argument("--quick", action="store_true", help="one size and one count")
    parser.add_argument("--part", choices=("sizes", "options", "counts", "all"), default="all")
    args = parser.parse_args(argv)
    os.environ.setdefault("TISSUESIM_MESH_THREADS", "1")
    from tissuesim.mesh.from_surface.smoothing import normal_variation

    surfaces = {"smooth": smooth(), "staircase": staircase()}
    lines = [
        "# Meshing a segmentation to a size and to an element count",
        "",
        f"`python benchmarks/mesh_to_size.py`: an ellipsoid of semi-axes {RADII} m, smooth "
        f"({len(surfaces['smooth'][1])} triangles) and as a 1 mm voxel segmentation with label "
        f"noise ({len(surfaces['staircase'][1])} triangles, marching cubes); pytetwild "
        f"{_version('pytetwild')} on {os.environ['TISSUESIM_MESH_THREADS']} thread(s). "
        "Quality: min dihedral angle (deg) / min radius ratio / mesh volume over the surface's.",
        "",
        "Mean angle between neighbouring triangles' normals: "
        + ", ".join(f"{k} {normal_variation(*s):.1f} deg" for k, s in surfaces.items())
        + ".",
        "",
    ]
    sizes = (0.014,) if args.quick else (0.014, 0.01, 0.007)
    counts = (10_000,) if args.quick else (10_000, 20_000, 40_000)
    if args.part in ("sizes", "all"):
        variants = [
            ("smooth", "fTetWild's envelope (epsilon 1e-3)", {"epsilon": 1e-3}),
            ("smooth", "default (envelope size / 20)", {}),
            ("staircase", "fTetWild's envelope (epsilon 1e-3)", {"epsilon": 1e-3}),
            ("staircase", "default (envelope size / 20)", {}),
            ("staircase", "taubin, default envelope", {"smoothing": "taubin"}),
        ]
        lines += [
            "## Size",
            "",
            "| surface | options | size (mm) | tetrahedra | envelope (mm) | mesher s | quality |",
            "| --- | --- | --- | --- | --- | --- | --- |",
        ]
        for key, label, options in variants:
            for size in sizes:
                row = one(surfaces[key], size=size, **options)
                print(json.dumps({"surface": key, **row}), file=sys.stderr, flush=True)
                lines.append(
                    f"| {key} | {label} | {size * 1e3:g} | {row['n_tets']} | "
                    f"{row['envelope'] * 1e3:.3g} | {row['mesher_s']:.1f} | {_quality(row)} |"
                )
        lines.append("")
    if args.part in ("options", "all"):
        variants = [
            ("coarsen", {"coarsen": True}),
            ("envelope 1 mm (a voxel)", {"envelope": 1e-3}),
            ("taubin, envelope 1 mm", {"smoothing": "taubin", "envelope": 1e-3}),
            ("taubin, 100 iterations", {"smoothing": "taubin", "smoothing_iterations": 100}),
            ("sinc (VTK)", {"smoothing": "sinc"}),
        ]
        lines += [
            "## Options on the staircase",
            "",
            "| options | size (mm) | tetrahedra | envelope (mm) | mesher s | quality "
            "| normals (deg) |",
            "| --- | --- | --- | --- | --- | --- | --- |",
        ]
        for label, options in variants:
            for size in sizes[:2]:
                row = one(surfaces["staircase"], size=size, **options)
                print(json.dumps({"surface": "staircase", **row}), file=sys.stderr, flush=True)
                sm = row["smoothing"]
                normals = "-"
                if sm:
                    before, after = (
                        sm["normal_variation_before_deg"],
                        sm["normal_variation_after_deg"],
                    )
                    normals = f"{before:.1f} -> {after:.1f}"
                lines.append(
                    f"| {label} | {size * 1e3:g} | {row['n_tets']} | {row['envelope'] * 1e3:.3g} | "
                    f"{row['mesher_s']:.1f} | {_quality(row)} | {normals} |"
                )
        lines.append("")
    if args.part in ("counts", "all"):
        variants = [
            ("smooth", "default", {}),
            ("staircase", "default", {}),
            ("staircase", "taubin", {"smoothing": "taubin"}),
        ]
        lines += [
            "## Element count (target_elements)",
            "",
            "| surface | options | requested | obtained | off | passes (size mm: tetrahedra) "
            "| mesher s | quality |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for key, label, options in variants:
            for n in counts:
                row = one(surfaces[key], target_elements=n, **options)
                print(json.dumps({"surface": key, **row}), file=sys.stderr, flush=True)
                steps = ", ".join(f"{p['size'] * 1e3:.3g}: {p['n_tets']}" for p in row["passes"])
                off = row["n_tets"] / n - 1
                lines.append(
                    f"| {key} | {label} | {n} | {row['n_tets']} | {off:+.0%} | "
                    f"{len(row['passes'])} ({steps}) | {row['mesher_s']:.1f} | {_quality(row)} |"
                )
        lines.append("")
    text = "\n".join(lines)
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    return 0


def _version(name: str) -> str:
    from importlib.metadata import version

    return version(name)


if __name__ == "__main__":
    sys.exit(main())

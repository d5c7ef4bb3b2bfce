"""Smoothing a staircase surface (a voxel segmentation exported as STL) before meshing it.

A segmentation contoured at 1 mm voxels is a staircase: its triangles' normals jump by up to 90
degrees between neighbours, and an envelope-based mesher (fTetWild keeps its boundary within
``epsilon`` of the input) spends most of its tetrahedra following the steps, whatever the
target edge length (docs/meshing.md). Two low-pass filters remove the steps without the
shrinkage of plain Laplacian smoothing:

- ``"taubin"`` (Taubin 1995, NumPy/SciPy only): alternating Laplacian steps of weight
  ``lambda = 0.5`` and ``mu = 1 / (k_pb - 1 / lambda)`` with the pass-band ``k_pb = 0.1`` (uniform
  weights: each vertex towards the mean of its neighbours);
- ``"sinc"``: VTK's ``vtkWindowedSincPolyDataFilter`` (Taubin, Zhang and Golub 1996; the same
  pass-band, normalised coordinates), when VTK is installed (``pip install vtk``, or PyVista).

Either leaves a little shrinkage (a few parts in a thousand on the staircases of the tests); the
smoothed surface is then scaled about its centroid to the enclosed volume of the input, so the
organ keeps its volume (closed, consistently oriented surfaces; an open one is left unscaled).
``normal_variation`` measures the staircase: the mean angle between the normals of triangles
that share an edge (about 35-45 degrees on a marching-cubes staircase, a few degrees on a smooth
surface of the same size).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.validate import short

__all__ = ["SMOOTHING", "DEFAULT_SMOOTHING_ITERATIONS", "normal_variation", "smooth_surface"]

#: the smoothing methods (``None`` or ``"none"``: the surface is meshed as it is)
SMOOTHING = ("taubin", "sinc")
#: iterations of either filter (Taubin: lambda/mu pairs); VTK's default for the sinc filter
DEFAULT_SMOOTHING_ITERATIONS = 20
#: the pass-band k_pb of both filters (VTK's default for the sinc filter is 0.1)
PASS_BAND = 0.1
_LAMBDA = 0.5


def smoothing_method(value: object) -> str | None:
    """The smoothing method named by ``value`` (None for none), or InputError naming it."""
    if value is None or value == "none" or value is False:
        return None
    if isinstance(value, str) and value in SMOOTHING:
        return value
    raise InputError(
        f"smoothing must be one of {', '.join(map(repr, ('none', *SMOOTHING)))}, not {short(value)}"
    )


def smoothing_iterations(value: object) -> int:
    """A whole number of smoothing iterations >= 1, or InputError naming the option."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise InputError(
            f"smoothing_iterations must be a whole number >= 1 (default "
            f"{DEFAULT_SMOOTHING_ITERATIONS}), not {short(value)}"
        )
    if value > 10_000:
        raise InputError(f"smoothing_iterations must be at most 10000, not {value}")
    return int(value)


def _edges(faces: np.ndarray) -> np.ndarray:
    e = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    return np.unique(e, axis=0)


def normal_variation(points: np.ndarray, faces: np.ndarray) -> float:
    """The mean angle (degrees) between the unit normals of triangles sharing a manifold edge.

    A measure of a staircase: near 0 on a finely triangulated smooth surface, 35-45 degrees on a
    marching-cubes contour of a voxel mask (neighbouring triangles at 45 and 90 degrees).
    """
    x = np.asarray(points, dtype=np.float64)[faces]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    e = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    owner = np.repeat(np.arange(len(faces)), 3)
    order = np.lexsort((e[:, 1], e[:, 0]))
    e, owner = e[order], owner[order]
    same = (e[1:] == e[:-1]).all(axis=1)
    # a manifold edge: exactly two triangles (the pair k, k + 1 equal, k - 1 and k + 2 not)
    before = np.r_[False, same[:-1]]
    after = np.r_[same[1:], False]
    pair = np.flatnonzero(same & ~before & ~after)
    if len(pair) == 0:
        return 0.0
    cos = np.einsum("ki,ki->k", n[owner[pair]], n[owner[pair + 1]])
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).mean())


def _taubin(points: np.ndarray, faces: np.ndarray, iterations: int) -> np.ndarray:
    import scipy.sparse as sp

    e = _edges(faces)
    n = len(points)
    a = sp.coo_matrix(
        (np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n)
    ).tocsr()
    degree = np.asarray(a.sum(axis=1)).ravel()
    mean = sp.diags(1.0 / np.maximum(degree, 1.0)) @ a  # each row: the mean of the neighbours
    mu = 1.0 / (PASS_BAND - 1.0 / _LAMBDA)
    x = np.array(points, dtype=np.float64)
    for _ in range(iterations):  # a loop over iterations, not over vertices
        x += _LAMBDA * (mean @ x - x)
        x += mu * (mean @ x - x)
    return x


def _sinc(points: np.ndarray, faces: np.ndarray, iterations: int) -> np.ndarray:
    try:
        from vtkmodules.util.numpy_support import (
            numpy_to_vtk,
            numpy_to_vtkIdTypeArray,
            vtk_to_numpy,
        )
        from vtkmodules.vtkCommonCore import vtkPoints
        from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
        from vtkmodules.vtkFiltersCore import vtkWindowedSincPolyDataFilter
    except ImportError as exc:
        raise InputError(
            f"smoothing 'sinc' needs VTK ({exc}); install it with pip install vtk (or pyvista), "
            "or use smoothing 'taubin' (NumPy only)"
        ) from None
    poly = vtkPolyData()
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(points, dtype=np.float64), deep=True))
    poly.SetPoints(pts)
    cells = vtkCellArray()
    offsets = np.arange(0, 3 * len(faces) + 1, 3, dtype=np.int64)
    cells.SetData(
        numpy_to_vtkIdTypeArray(offsets, deep=True),
        numpy_to_vtkIdTypeArray(np.ascontiguousarray(faces.ravel(), dtype=np.int64), deep=True),
    )
    poly.SetPolys(cells)
    f = vtkWindowedSincPolyDataFilter()
    f.SetInputData(poly)
    f.SetNumberOfIterations(iterations)
    f.SetPassBand(PASS_BAND)
    f.NormalizeCoordinatesOn()
    f.BoundarySmoothingOff()
    f.FeatureEdgeSmoothingOff()
    f.NonManifoldSmoothingOn()
    f.Update()
    out = vtk_to_numpy(f.GetOutput().GetPoints().GetData())
    if out.shape != np.shape(points):  # the filter keeps the points and their order
        raise RuntimeError(f"VTK's sinc filter returned {out.shape[0]} of {len(points)} points")
    return np.array(out, dtype=np.float64)


def smooth_surface(surface: Any, method: str, iterations: int) -> tuple[Any, dict]:
    """``surface`` (a ``tetrahedralize.Surface``, not imported: it imports this module) smoothed
    by ``method`` ("taubin" or "sinc") over ``iterations``, and a report
    (method, iterations, normal variation before and after in degrees, the volume before
    smoothing, its shrinkage, and whether it was restored by scaling about the centroid)."""
    method = smoothing_method(method)
    iterations = smoothing_iterations(iterations)
    before = normal_variation(surface.points, surface.faces)
    v0 = surface.volume
    smoothed = (_taubin if method == "taubin" else _sinc)(surface.points, surface.faces, iterations)
    out = replace(surface, points=smoothed)
    v1 = out.volume
    restore = surface.closed and not surface.misoriented_edges and v0 * v1 > 0
    if restore:  # the enclosed volume of the input, by a scaling about the centroid
        c = smoothed.mean(axis=0)
        out = replace(surface, points=c + (smoothed - c) * (v0 / v1) ** (1.0 / 3.0))
    report = {
        "method": method,
        "iterations": iterations,
        "normal_variation_before_deg": round(before, 3),
        "normal_variation_after_deg": round(normal_variation(out.points, out.faces), 3),
        "shrinkage": round(1.0 - v1 / v0, 6) if v0 else float("nan"),
        "volume_restored": bool(restore),
    }
    return out, report

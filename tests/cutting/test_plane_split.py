"""The closed-form split of simplices by a plane (mesh/cutting/plane_split.py) against convex hulls
of the clipped simplex, an independent computation, and the polygon test against a point loop."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from tissuesim.mesh.cutting.plane_split import positive_fraction, sections_inside


def hull_fraction(x: np.ndarray, d: np.ndarray) -> float:
    """Measure of {d >= 0} in simplex x (n+1, n) over the simplex's, by a convex hull."""
    keep = [x[i] for i in range(len(d)) if d[i] >= 0.0]
    for i in range(len(d)):
        for j in range(i + 1, len(d)):
            if d[i] * d[j] < 0.0:
                keep.append(x[i] + d[i] / (d[i] - d[j]) * (x[j] - x[i]))
    if len(keep) <= x.shape[1]:
        return 0.0
    return ConvexHull(np.array(keep)).volume / ConvexHull(x).volume


@pytest.mark.parametrize("dim", [2, 3])
def test_fractions_match_convex_hulls_of_the_clipped_simplex(dim):
    rng = np.random.default_rng(dim)
    for _ in range(400):
        x = rng.normal(size=(dim + 1, dim))
        normal = rng.normal(size=dim)
        d = (x - 0.3 * rng.normal(size=dim)) @ normal
        if np.all(d > 0) or np.all(d < 0):
            continue
        f = positive_fraction(d[None])[0]
        assert f == pytest.approx(hull_fraction(x, d), abs=1e-12)
        assert f + positive_fraction(-d[None])[0] == pytest.approx(1.0, abs=1e-12)


def test_a_tetrahedron_split_two_two_with_nearly_equal_values():
    """The divided difference's confluent case: d_a and d_b equal to 1e-14 ... 1e-3."""
    rng = np.random.default_rng(7)
    x = rng.normal(size=(4, 3))
    # vertex values of a linear function: d = x @ n + c for some n, c (any 4 values are)
    for gap in (0.0, 1e-14, 1e-9, 1e-6, 1e-5, 1e-4, 1e-3):
        d = np.array([0.4, 0.4 + gap, -0.3, -0.9])
        f = positive_fraction(d[None])[0]
        assert f == pytest.approx(hull_fraction(x, d), abs=1e-10)


def test_vertices_on_the_plane_and_whole_simplices():
    d = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [-1.0, -2.0, -1.0, -1.0]])
    assert positive_fraction(d).tolist() == [1.0, 1.0, 0.0]
    # one vertex above, one on the plane, two below: the corner at the vertex above
    d = np.array([[1.0, 0.0, -1.0, -1.0]])
    assert positive_fraction(d)[0] == pytest.approx(0.25)
    assert positive_fraction(np.array([[1.0, -3.0]]))[0] == pytest.approx(0.25)  # an edge


def test_sections_inside_agrees_with_a_point_by_point_check():
    rng = np.random.default_rng(3)
    normal = np.array([0.0, 0.0, 1.0])
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    x = rng.uniform(-0.5, 1.5, size=(300, 4, 3))
    x[..., 2] = rng.uniform(-0.2, 0.2, size=(300, 4))
    d = x[..., 2].copy()
    got = sections_inside(x, d, square, normal)
    for m in range(len(x)):
        pts = [x[m, i] for i in range(4) if d[m, i] == 0.0]
        for i in range(4):
            for j in range(i + 1, 4):
                if d[m, i] * d[m, j] < 0:
                    pts.append(x[m, i] + d[m, i] / (d[m, i] - d[m, j]) * (x[m, j] - x[m, i]))
        inside = all(-1e-12 <= p[0] <= 1 + 1e-12 and -1e-12 <= p[1] <= 1 + 1e-12 for p in pts)
        assert got[m] == inside
    assert 0 < got.sum() < len(x)  # both outcomes occur

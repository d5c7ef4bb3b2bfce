"""The curved-cut geometry (mesh/cutting/swept_cut.py): closest points on triangles against an
independent computation, distances equal to the plane's on a planar sweep, and sections on
and off what a blade swept."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import InputError
from tissuesim.mesh.cutting.planar_cut import PlanarCut
from tissuesim.mesh.cutting.swept_cut import SweptCut, closest_points


def _closest_by_parts(p, a, b, c):
    """The closest point of triangle abc to p: the projection if it falls inside, else the
    nearest of the three edges' closest points (segments clamped)."""
    n = np.cross(b - a, c - a)
    n = n / np.linalg.norm(n)
    q = p - ((p - a) @ n) * n
    M = np.column_stack([b - a, c - a])
    v, w = np.linalg.lstsq(M, q - a, rcond=None)[0]
    if v >= 0 and w >= 0 and v + w <= 1:
        return q
    best = None
    for s, e in ((a, b), (b, c), (c, a)):
        t = np.clip((p - s) @ (e - s) / ((e - s) @ (e - s)), 0.0, 1.0)
        r = s + t * (e - s)
        if best is None or np.linalg.norm(p - r) < np.linalg.norm(p - best):
            best = r
    return best


def test_closest_points_agree_with_projection_and_edges():
    rng = np.random.default_rng(3)
    tri = rng.normal(size=(6, 3, 3))
    pts = 2.0 * rng.normal(size=(40, 3))
    cp = closest_points(pts, tri[:, 0], tri[:, 1], tri[:, 2])
    for i, p in enumerate(pts):
        for k, (a, b, c) in enumerate(tri):
            assert np.allclose(cp[i, k], _closest_by_parts(p, a, b, c), atol=1e-12)


def test_a_planar_sweep_gives_the_planes_distances_and_polygon():
    edges = [np.array([[x, 0.0, 0.0], [x, 1.0, 0.3]]) for x in np.linspace(0.0, 1.0, 5)]
    swept = SweptCut.from_blades(edges)
    plane = PlanarCut.swept_segment(edges[0][0], edges[0][1], edges[-1][0], edges[-1][1])
    rng = np.random.default_rng(1)
    x = rng.uniform(-0.5, 1.5, size=(200, 3))
    d_plane = (x - plane.point) @ plane.normal
    d = swept.distances(x)
    assert np.allclose(np.abs(d), np.abs(d_plane), atol=1e-12)
    assert np.all(np.sign(d) == np.sign(d_plane)) or np.all(np.sign(d) == -np.sign(d_plane))
    # a tetrahedron the plane crosses inside the swept area is covered; one beyond it is not
    n, u = plane.normal, np.array([1.0, 0.0, 0.0])
    w = np.cross(n, u)
    for x0, expected in ((0.5, True), (1.5, False), (0.98, False)):
        centre = np.array([x0, 0.0, 0.0]) + 0.5 * np.array([0.0, 1.0, 0.3])
        tet = centre + 0.05 * np.array([n, -n + u, -n - u + w, -n - u - w])
        d = swept.distances(tet[None])
        assert d.max() > 0 > d.min()  # crossed
        assert swept.sections_inside(tet[None], d).tolist() == [expected]


def test_a_curved_sweep_bends_the_distance_with_the_surface():
    """An edge swept around a quarter circle (radius 1, its axis along z): points on the
    cylinder are at distance 0 (to the sampling's chord error), off it by their radial
    offset."""
    angles = np.linspace(0.0, np.pi / 2, 33)
    edges = [np.array([[np.cos(a), np.sin(a), 0.0], [np.cos(a), np.sin(a), 1.0]]) for a in angles]
    swept = SweptCut.from_blades(edges)
    chord = 1.0 - np.cos((angles[1] - angles[0]) / 2)  # the sampled surface's largest sag
    a = np.linspace(0.05, np.pi / 2 - 0.05, 20)
    on = np.column_stack([np.cos(a), np.sin(a), np.full(20, 0.5)])
    assert np.all(swept.gaps(on) <= chord + 1e-12)
    for r in (0.9, 1.1):
        d = swept.distances(r * on * np.array([1, 1, 0]) + np.array([0, 0, 0.5]))
        assert np.allclose(np.abs(d), abs(r - 1.0), atol=chord + 1e-12)


def test_a_sweep_of_no_area_is_refused():
    still = [np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])] * 3
    with pytest.raises(InputError, match="sweeps no area"):
        SweptCut.from_blades(still)

"""Cutting-tool geometry: swept blade triangles, point-triangle distances, segment crossings."""

import numpy as np
import pytest

from tissuesim.coupling.geometry import (
    point_triangle_distance,
    segments_hit_triangles,
    swept_blade_triangles,
)

# the unit square in the plane z = 0 as two triangles
SQUARE = np.array(
    [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
        [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    ]
)


def _areas(tri):
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def test_swept_blade_area_and_layout():
    k = 5
    before = np.column_stack([np.linspace(0.0, 2.0, k), np.zeros(k), np.zeros(k)])
    after = before + [0.0, 0.0, 0.3]  # straight blade of length 2 moving 0.3 perpendicular
    tri = swept_blade_triangles(before, after)
    assert tri.shape == (2 * (k - 1), 3, 3)
    assert _areas(tri).sum() == pytest.approx(2.0 * 0.3)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (n[:, 1] < 0).all()  # consistently oriented
    # the swept quad of segment i is triangles 2i, 2i+1
    np.testing.assert_array_equal(tri[2, 0], before[1])
    np.testing.assert_array_equal(tri[3, 2], after[1])
    # a blade standing still sweeps zero area: allowed
    still = swept_blade_triangles(before, before)
    assert _areas(still).max() == 0.0


def test_swept_blade_errors():
    with pytest.raises(ValueError, match="k >= 2 points"):
        swept_blade_triangles(np.zeros((1, 3)), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="must have the same shape"):
        swept_blade_triangles(np.zeros((3, 3)), np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"before must have shape \(k, 3\)"):
        swept_blade_triangles(np.zeros((3, 2)), np.zeros((3, 2)))


def test_segments_known_cases():
    a = np.array(
        [
            [0.5, 0.25, -1.0],  # through the square
            [0.5, 0.5, 0.5],  # parallel to it, above
            [1.01, 0.5, -1.0],  # just missing beside the edge x = 1
            [0.3, 0.6, 0.0],  # endpoint touching the square
            [0.3, 0.6, 1.0],  # ends just above it
            [1.0, 0.5, -1.0],  # through the edge x = 1: touching counts
            [0.5, 0.5, -3.0],  # aimed at the square but too short
            [0.2, 0.2, 0.0],  # lying in the plane of the square: parallel, not a hit
            [0.4, 0.4, 0.0],  # zero length, on the square: not a hit
        ]
    )
    b = np.array(
        [
            [0.5, 0.75, 1.0],
            [2.0, 0.5, 0.5],
            [1.01, 0.5, 1.0],
            [0.3, 0.6, 1.0],
            [0.3, 0.6, 1e-6],
            [1.0, 0.5, 1.0],
            [0.5, 0.5, -1.0],
            [0.8, 0.8, 0.0],
            [0.4, 0.4, 0.0],
        ]
    )
    got = segments_hit_triangles(a, b, SQUARE)
    np.testing.assert_array_equal(got, [True, False, False, True, False, True, False, False, False])
    # reversed segments give the same answers
    np.testing.assert_array_equal(segments_hit_triangles(b, a, SQUARE), got)


def test_segments_ignore_degenerate_triangles_and_match_brute_force():
    rng = np.random.default_rng(0)
    tri = rng.uniform(0, 1, (300, 3, 3))
    tri[:20, 2] = tri[:20, 0]  # degenerate: never hit
    a = rng.uniform(-0.2, 1.2, (400, 3))
    b = a + rng.normal(0, 0.3, a.shape)
    got = segments_hit_triangles(a, b, tri)
    # brute force over all pairs: the segment crosses the plane inside the triangle
    t = tri[None, 20:]  # (1, m, 3, 3)
    n = np.cross(t[..., 1, :] - t[..., 0, :], t[..., 2, :] - t[..., 0, :])
    sp = ((a[:, None] - t[..., 0, :]) * n).sum(-1)
    sq = ((b[:, None] - t[..., 0, :]) * n).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, None] + (sp / (sp - sq))[..., None] * (b - a)[:, None]
    inside = (sp * sq <= 0) & (sp != sq)
    for j in range(3):  # the three edges
        e = t[..., (j + 1) % 3, :] - t[..., j, :]
        inside &= (np.cross(e, x - t[..., j, :]) * n).sum(-1) >= 0
    expected = inside.any(axis=1)
    np.testing.assert_array_equal(got, expected)
    assert got.sum() > 20
    assert not segments_hit_triangles(a, b, tri[:20]).any()


def test_point_triangle_distance_against_brute_force():
    rng = np.random.default_rng(1)
    tri = rng.uniform(0, 1, (150, 3, 3)) * [1.0, 1.0, 0.2]
    tri[:5, 1] = tri[:5, 0]  # degenerate ones count as their edges
    tri[5:8, 2] = 0.5 * (tri[5:8, 0] + tri[5:8, 1])  # collinear
    p = rng.uniform(-0.5, 1.5, (500, 3))
    got = point_triangle_distance(p, tri)
    # brute force over all pairs: the projection onto the plane where it falls inside the
    # triangle, else the nearest edge (the only candidates for degenerate triangles)
    x, t = p[:, None, :], tri[None]
    edges = np.full((len(p), len(tri)), np.inf)
    inside = np.ones((len(p), len(tri)), dtype=bool)
    n = np.cross(t[..., 1, :] - t[..., 0, :], t[..., 2, :] - t[..., 0, :])
    n = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
    h = ((x - t[..., 0, :]) * n).sum(-1)
    proj = x - h[..., None] * n
    for j in range(3):  # the three edges
        u, v = t[..., j, :], t[..., (j + 1) % 3, :]
        e = v - u
        s = np.clip(((x - u) * e).sum(-1) / np.maximum((e * e).sum(-1), 1e-300), 0, 1)
        edges = np.minimum(edges, np.linalg.norm(u + s[..., None] * e - x, axis=-1))
        inside &= (np.cross(e, proj - u) * n).sum(-1) > 0
    expected = np.where(inside, np.abs(h), edges).min(axis=1)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)
    # exact on a plane: points above the square
    q = np.array([[0.3, 0.4, 2.0], [2.0, 0.5, 0.0], [-1.0, -1.0, -1.0]])
    np.testing.assert_allclose(point_triangle_distance(q, SQUARE), [2.0, 1.0, np.sqrt(3.0)])


def test_argument_errors():
    with pytest.raises(ValueError, match=r"triangles must have shape \(m, 3, 3\)"):
        point_triangle_distance(np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="triangles is empty"):
        point_triangle_distance(np.zeros((2, 3)), np.zeros((0, 3, 3)))
    with pytest.raises(ValueError, match="segment i runs from a"):
        segments_hit_triangles(np.zeros((2, 3)), np.zeros((3, 3)), SQUARE)
    with pytest.raises(ValueError, match="non-finite"):
        segments_hit_triangles(np.full((1, 3), np.inf), np.zeros((1, 3)), SQUARE)

"""Integration points for frame models (box, ellipsoid, closed surface, tet mesh) and surfaces."""

import math
import warnings

import meshio
import numpy as np
import pytest

from tissuesim.errors import MeshError
from tissuesim.frames.sampling import (
    IntegrationPoints,
    Surface,
    box_surface,
    ellipsoid_surface,
    read_surface,
    sample_box,
    sample_ellipsoid,
    sample_mesh,
    sample_surface,
    surface_from_mesh,
    winding_number,
)
from tissuesim.mesh import (
    boundary_facets,
    box,
    rectangle,
    signed_volumes,
    validate_mesh,
    write_mesh,
)


def weighted_centroid(ip):
    return (ip.volumes[:, None] * ip.points).sum(axis=0) / ip.volume


def outward_alignment(surface, centre):
    """(b - a) x (c - a) . (triangle centroid - centre) per triangle: > 0 when outward."""
    x = surface.points[surface.triangles]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    return np.einsum("mi,mi->m", n, x.mean(axis=1) - centre)


def l_shape_mesh():
    """Tet mesh of [0,3]x[0,3]x[0,1] without x > 1, y > 1: an L with a re-entrant edge."""
    full = box((0, 0, 0), (3, 3, 1), (3, 3, 1))
    c = full.points[full.cells].mean(axis=1)
    keep = ~((c[:, 0] > 1) & (c[:, 1] > 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the removed corner's vertices are unreferenced
        return validate_mesh(full.points, full.cells[keep], source="L-shape")


# ---------------------------------------------------------------------------- sample_box


def test_sample_box_cell_centres_exact_volumes():
    ip = sample_box((0, 0, 0), (0.4, 0.4, 2), 0.1)
    assert ip.n == 4 * 4 * 20
    assert ip.points.shape == (320, 3) and ip.volumes.shape == (320,)
    assert ip.volume == pytest.approx(0.32, rel=1e-12, abs=0)
    assert np.allclose(ip.volumes, 0.001)
    assert (ip.points > 0).all() and (ip.points < [0.4, 0.4, 2]).all()
    # centres of the 0.1 grid: coordinates are odd multiples of 0.05
    assert np.allclose(np.round(ip.points / 0.05) % 2, 1)
    assert ip.source == "box [0,0,0]-[0.4,0.4,2] spacing 0.1"


def test_sample_box_rounds_divisions_and_keeps_at_least_one():
    ip = sample_box((-1, 0, 0), (0, 1, 0.5), 0.3)  # round(3.33) = 3, round(1.67) = 2
    assert ip.n == 3 * 3 * 2
    assert ip.volume == pytest.approx(0.5, rel=1e-12, abs=0)
    one = sample_box((0, 0, 0), (1, 2, 3), 10.0)
    assert one.n == 1
    assert np.allclose(one.points, [[0.5, 1.0, 1.5]]) and one.volume == pytest.approx(6.0)


def test_masses():
    ip = sample_box((0, 0, 0), (1, 1, 1), 0.5)
    assert np.allclose(ip.masses(1000.0), 125.0)
    rho = np.arange(1.0, 9.0)
    assert np.allclose(ip.masses(rho), rho * 0.125)
    for bad in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="density must be (finite and )?> 0|finite number"):
            ip.masses(bad)
    with pytest.raises(ValueError, match="integration point 3 has -1.0"):
        ip.masses(np.where(np.arange(8) == 3, -1.0, 1.0))
    with pytest.raises(ValueError, match=r"or 8 numbers \(one per integration point\)"):
        ip.masses(np.ones(3))
    with pytest.raises(ValueError, match="density"):
        ip.masses("heavy")


def test_integration_points_validates():
    with pytest.raises(ValueError, match=r"shape \(q, 3\)"):
        IntegrationPoints(np.zeros((2, 2)), np.ones(2), "t")
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        IntegrationPoints(np.zeros((2, 3)), np.ones(3), "t")
    with pytest.raises(ValueError, match="volume 1 is 0.0"):
        IntegrationPoints(np.zeros((2, 3)), [1.0, 0.0], "t")
    with pytest.raises(ValueError, match="point 0 is not finite"):
        IntegrationPoints([[np.nan, 0, 0]], [1.0], "t")


# ---------------------------------------------------------------------------- ellipsoid


@pytest.mark.parametrize("subsamples", [1, 3, 4])
def test_sample_ellipsoid_exact_volume_points_inside(subsamples):
    c, r, h = np.array([0.5, -1.0, 2.0]), np.array([1.0, 0.6, 0.4]), 0.1
    ip = sample_ellipsoid(c, r, h, subsamples=subsamples)
    assert ip.volume == pytest.approx(4 / 3 * math.pi * 0.24, rel=1e-12, abs=0)
    assert (ip.volumes > 0).all()
    assert ((((ip.points - c) / r) ** 2).sum(axis=1) <= 1.0).all()
    # first moment: symmetric sampling puts the centroid at the centre
    assert np.abs(weighted_centroid(ip) - c).max() < 1e-2 * h
    # interior cells carry a full cell volume (the scaling factor is close to 1)
    assert ip.volumes.max() == pytest.approx(h**3, rel=0.05)
    assert "ellipsoid" in ip.source and "spacing 0.1" in ip.source


def test_sample_ellipsoid_second_moment():
    ip = sample_ellipsoid((0, 0, 0), (1.0, 1.0, 1.0), 0.1)
    # integral of x^2 over the unit ball = 4 pi / 15
    assert (ip.volumes * ip.points[:, 0] ** 2).sum() == pytest.approx(4 * math.pi / 15, rel=0.02)


# ---------------------------------------------------------------------------- surfaces


def test_box_surface_closed_outward_exact_volume():
    lo, hi = np.array([0.0, -1.0, 0.5]), np.array([1.0, 1.0, 3.5])
    s = box_surface(lo, hi, (2, 3, 4))
    assert s.triangles.dtype == np.int64
    assert len(s.triangles) == 4 * (2 * 3 + 3 * 4 + 4 * 2)
    assert len(s.points) == 3 * 4 * 5 - 1 * 2 * 3  # grid vertices minus the interior ones
    assert s.volume() == pytest.approx(1.0 * 2.0 * 3.0, rel=1e-12, abs=0)
    assert (outward_alignment(s, (lo + hi) / 2) > 0).all()
    on_face = np.isclose(s.points, lo) | np.isclose(s.points, hi)
    assert on_face.any(axis=1).all()


@pytest.mark.parametrize("refinement", [0, 1, 2, 3])
def test_ellipsoid_surface_outward_on_ellipsoid(refinement):
    c, r = np.array([1.0, 2.0, 3.0]), np.array([1.0, 0.6, 0.4])
    s = ellipsoid_surface(c, r, refinement)
    assert len(s.triangles) == 20 * 4**refinement
    assert np.allclose((((s.points - c) / r) ** 2).sum(axis=1), 1.0)
    assert (outward_alignment(s, c) > 0).all()
    assert 0 < s.volume() < 4 / 3 * math.pi * 0.24  # inscribed polyhedron


def test_ellipsoid_surface_volume_converges():
    exact = 4 / 3 * math.pi * 2.0 * 1.0 * 0.5
    v = [ellipsoid_surface((0, 0, 0), (2.0, 1.0, 0.5), k).volume() for k in range(5)]
    assert np.all(np.diff(v) > 0)
    assert v[3] == pytest.approx(exact, rel=0.02)
    assert v[4] == pytest.approx(exact, rel=0.005)


def test_surface_from_mesh_is_outward_boundary():
    m = box((0, 0, 0), (1, 2, 3), (2, 2, 3))
    s = surface_from_mesh(m)
    assert s.volume() == pytest.approx(signed_volumes(m.points, m.cells).sum(), rel=1e-12)
    assert (outward_alignment(s, (0.5, 1.0, 1.5)) > 0).all()
    interior = (m.points > [0, 0, 0]) & (m.points < [1, 2, 3])
    assert len(s.points) == m.n_points - int(interior.all(axis=1).sum())
    assert "boundary of box(" in s.source


def test_surface_from_mesh_rejects_2d():
    with pytest.raises(ValueError, match="tetrahedral"):
        surface_from_mesh(rectangle())


def test_winding_number_classifies_box_surface():
    s = box_surface((0, 0, 0), (1, 2, 3), (1, 2, 3))
    inside = np.array(
        [[0.5, 1.0, 1.5], [1e-3, 1e-3, 1e-3], [0.999, 1.999, 2.999], [0.5, 1.0, 1e-6], [0.2, 1, 2]]
    )
    outside = np.array(
        [
            [-1e-3, 1.0, 1.5],
            [1.001, 1.0, 1.5],
            [0.5, 2.5, 1.5],
            [0.5, 1.0, -10.0],
            [5.0, 5.0, 5.0],
            [2.0, 1.0, 0.0],  # in the plane of the bottom face, off the box
            [0.5, 1.0, 3.0 + 1e-6],
        ]
    )
    w_in, w_out = winding_number(s, inside), winding_number(s, outside)
    assert np.allclose(w_in, 1.0, atol=1e-9)
    assert np.allclose(w_out, 0.0, atol=1e-9)
    flipped = Surface(s.points, s.triangles[:, ::-1], "flipped")
    assert np.allclose(winding_number(flipped, inside), -1.0, atol=1e-9)


# ---------------------------------------------------------------------------- sample_surface


def test_sample_surface_of_ellipsoid_surface():
    c, r = np.array([1.0, 2.0, 3.0]), np.array([1.0, 0.6, 0.4])
    s = ellipsoid_surface(c, r, 2)
    ip = sample_surface(s, 0.2)
    assert ip.volume == pytest.approx(s.volume(), rel=1e-12, abs=0)
    assert (winding_number(s, ip.points) > 0.5).all()
    assert ((((ip.points - c) / r) ** 2).sum(axis=1) < 1.0).all()
    assert np.abs(weighted_centroid(ip) - c).max() < 0.02 * 0.2
    # agrees with the analytic ellipsoid sampler away from the faceting error
    ref = sample_ellipsoid(c, r, 0.2)
    assert ip.n == pytest.approx(ref.n, rel=0.15)


def test_sample_surface_of_aligned_box_equals_sample_box():
    s = box_surface((0, 0, 0), (0.4, 0.4, 2))
    ip = sample_surface(s, 0.1)
    ref = sample_box((0, 0, 0), (0.4, 0.4, 2), 0.1)
    assert ip.volume == pytest.approx(0.32, rel=1e-12, abs=0)
    assert ip.n == ref.n
    assert np.allclose(ip.points, ref.points) and np.allclose(ip.volumes, ref.volumes)


def test_sample_surface_of_unaligned_box_points_inside():
    lo, hi = np.array([0.0, -0.3, 0.1]), np.array([0.55, 0.4, 1.23])
    s = box_surface(lo, hi, (1, 2, 3))
    ip = sample_surface(s, 0.1, subsamples=3)
    assert ip.volume == pytest.approx(float(np.prod(hi - lo)), rel=1e-12, abs=0)
    assert ((ip.points > lo) & (ip.points < hi)).all()
    assert np.allclose(weighted_centroid(ip), (lo + hi) / 2, atol=1e-3)


def test_sample_surface_non_convex_points_stay_inside():
    m = l_shape_mesh()
    s = surface_from_mesh(m)
    assert s.volume() == pytest.approx(5.0, rel=1e-12)
    # the cell [0.9, 1.2]^2 around the re-entrant edge has inside sub-samples only along two of
    # its sides: their centroid (1.01, 1.01) is outside, so the nearest inside one is used
    ip = sample_surface(s, 0.3, subsamples=3)
    assert ip.volume == pytest.approx(5.0, rel=1e-12, abs=0)
    assert (winding_number(s, ip.points) > 0.5).all()
    assert not ((ip.points[:, 0] > 1) & (ip.points[:, 1] > 1)).any()


def test_sample_surface_rejects_open_surface():
    s = box_surface((0, 0, 0), (1, 1, 1), (1, 1, 1))
    open_ = Surface(s.points, s.triangles[1:], "open box")
    with pytest.raises(ValueError, match=r"open box: surface is not closed: 3 of .*e\.g\. edge"):
        open_.volume()
    with pytest.raises(ValueError, match="not closed"):
        sample_surface(open_, 0.1)


def test_sample_surface_rejects_inward_and_inconsistent_surfaces():
    s = box_surface((0, 0, 0), (1, 1, 1), (1, 1, 1))
    inward = Surface(s.points, s.triangles[:, ::-1], "inward box")
    assert inward.volume() == pytest.approx(-1.0)
    with pytest.raises(ValueError, match="inward box.*oriented inward; flip them"):
        sample_surface(inward, 0.1)
    tri = s.triangles.copy()
    tri[0] = tri[0, ::-1]
    with pytest.raises(ValueError, match="inconsistently oriented"):
        sample_surface(Surface(s.points, tri, "mixed"), 0.1)


def test_sample_surface_nothing_inside_says_spacing_too_coarse():
    a = box_surface((0, 0, 0), (0.1, 0.1, 0.1), (1, 1, 1))
    b = box_surface((0.9, 0.9, 0.9), (1, 1, 1), (1, 1, 1))
    two = Surface(
        np.concatenate([a.points, b.points]),
        np.concatenate([a.triangles, b.triangles + len(a.points)]),
        "two cubes",
    )
    assert two.volume() == pytest.approx(0.002)
    with pytest.raises(ValueError, match="spacing 10 is too coarse"):
        sample_surface(two, 10.0, subsamples=1)
    assert sample_surface(two, 0.05).volume == pytest.approx(0.002, rel=1e-12)


# ---------------------------------------------------------------------------- sample_mesh


def test_sample_mesh_one_point_per_tet():
    m = box((0, 0, 0), (1, 2, 3), (2, 3, 4))
    ip = sample_mesh(m)
    assert ip.n == m.n_cells
    assert ip.volume == pytest.approx(6.0, rel=1e-12, abs=0)
    assert np.allclose(ip.points, m.points[m.cells].mean(axis=1))
    assert np.allclose(ip.volumes, signed_volumes(m.points, m.cells))


def test_sample_mesh_grouped_by_grid_cells():
    h = 0.25
    m = box((0, 0, 0), (1, 1, 1), (4, 4, 4))
    ip = sample_mesh(m, h)
    assert ip.n == 64  # one group per hexahedron: its 6 tets' centroids lie inside it
    assert ip.volume == pytest.approx(1.0, rel=1e-12, abs=0)
    assert np.allclose(np.sort(ip.volumes), h**3)
    assert np.allclose(np.round(ip.points / (h / 2)) % 2, 1)  # hexahedron centres
    # second moment: midpoint rule on x^2 gives 1/3 - h^2/12 exactly, within a few % of 1/3
    second = (ip.volumes * ip.points[:, 0] ** 2).sum()
    assert second == pytest.approx(1 / 3 - h**2 / 12, rel=1e-12)
    assert second == pytest.approx(1 / 3, rel=0.03)


def test_sample_mesh_unaligned_spacing_keeps_volume_and_centroid():
    m = box((0, -1, 2), (1, 1, 3), (5, 6, 4))
    for spacing in (0.3, 0.7, 100.0):
        ip = sample_mesh(m, spacing)
        assert ip.volume == pytest.approx(2.0, rel=1e-12, abs=0)
        assert ip.n < m.n_cells
        assert np.allclose(weighted_centroid(ip), [0.5, 0.0, 2.5])
    assert sample_mesh(m, 100.0).n == 1


def test_sample_mesh_errors():
    with pytest.raises(ValueError, match="2D mesh; 3D tetrahedra are needed"):
        sample_mesh(rectangle())
    with pytest.raises(ValueError, match="spacing must be finite and > 0"):
        sample_mesh(box(), 0.0)
    with pytest.raises(ValueError, match="mesh must be a tissuesim Mesh"):
        sample_mesh(np.zeros((4, 3)))


# ---------------------------------------------------------------------------- read_surface


@pytest.mark.parametrize("ext", [".vtu", ".stl"])
def test_read_surface_round_trip(tmp_path, ext):
    s = box_surface((0, 0, 0), (1, 2, 4), (2, 2, 4))
    path = tmp_path / f"box{ext}"
    meshio.write_points_cells(str(path), s.points, [("triangle", s.triangles)])
    r = read_surface(path)
    assert r.source == str(path)
    assert len(r.triangles) == len(s.triangles)
    assert r.volume() == pytest.approx(8.0, rel=1e-12)
    assert np.allclose(np.sort(r.points[r.triangles].reshape(-1, 9), axis=0),
                       np.sort(s.points[s.triangles].reshape(-1, 9), axis=0))  # fmt: skip
    ip = sample_surface(r, 0.5)
    assert ip.volume == pytest.approx(8.0, rel=1e-12)


def test_read_surface_takes_triangles_of_volume_mesh_file(tmp_path):
    m = box((0, 0, 0), (1, 1, 1), (2, 2, 2))
    path = tmp_path / "both.vtu"
    tets_and_tris = [("tetra", m.cells), ("triangle", boundary_facets(m.cells))]
    meshio.write_points_cells(str(path), m.points, tets_and_tris)
    assert read_surface(path).volume() == pytest.approx(1.0, rel=1e-12)


def test_read_surface_errors_name_the_file(tmp_path):
    missing = tmp_path / "missing.stl"
    with pytest.raises(MeshError, match=f"{missing}: no such surface file"):
        read_surface(missing)
    tets = tmp_path / "tets.vtu"
    write_mesh(box(divisions=(1, 1, 1)), tets)
    with pytest.raises(MeshError, match=r"tets\.vtu: no triangles; cell types found: tetra \(6\)"):
        read_surface(tets)
    garbage = tmp_path / "garbage.stl"
    garbage.write_bytes(b"\x00\x01not a mesh")
    with pytest.raises(MeshError, match=r"garbage\.stl: meshio could not read"):
        read_surface(garbage)
    with pytest.raises(MeshError, match="is a directory"):
        read_surface(tmp_path)


# ---------------------------------------------------------------------------- argument checks


@pytest.mark.parametrize("spacing", [0.0, -0.1, float("nan"), float("inf"), "0.1", True, None])
def test_spacing_must_be_positive(spacing):
    s = box_surface((0, 0, 0), (1, 1, 1), (1, 1, 1))
    calls = [
        lambda: sample_box((0, 0, 0), (1, 1, 1), spacing),
        lambda: sample_ellipsoid((0, 0, 0), (1, 1, 1), spacing),
        lambda: sample_surface(s, spacing),
    ]
    for call in calls:
        with pytest.raises(ValueError, match="spacing must be .*> 0.*distance between"):
            call()


def test_bad_shapes_and_values():
    with pytest.raises(ValueError, match=r"sample_box: upper\[2\] = 0.0 must be greater"):
        sample_box((0, 0, 0), (1, 1, 0), 0.1)
    with pytest.raises(ValueError, match="sample_box: lower must be 3 finite numbers"):
        sample_box((0, 0), (1, 1, 1), 0.1)
    with pytest.raises(ValueError, match="center must be 3 finite numbers"):
        sample_ellipsoid((0, 0), (1, 1, 1), 0.1)
    with pytest.raises(ValueError, match=r"semi_axes must all be > 0, got \[1,1,0\]"):
        sample_ellipsoid((0, 0, 0), (1, 1, 0), 0.1)
    with pytest.raises(ValueError, match="semi_axes must all be > 0"):
        ellipsoid_surface((0, 0, 0), (1, -1, 1))
    with pytest.raises(ValueError, match="subsamples must be an integer >= 1, got 0"):
        sample_ellipsoid((0, 0, 0), (1, 1, 1), 0.1, subsamples=0)
    with pytest.raises(ValueError, match="subsamples must be an integer >= 1, got 2.5"):
        sample_surface(box_surface((0, 0, 0), (1, 1, 1)), 0.1, subsamples=2.5)
    with pytest.raises(ValueError, match="refinement must be an integer >= 0, got -1"):
        ellipsoid_surface((0, 0, 0), (1, 1, 1), -1)
    with pytest.raises(ValueError, match="box_surface: divisions must be 3 integers >= 1"):
        box_surface((0, 0, 0), (1, 1, 1), (0, 1, 1))
    with pytest.raises(ValueError, match="box_surface: upper"):
        box_surface((0, 0, 0), (1, 1, 1 - 2), (1, 1, 1))
    with pytest.raises(ValueError, match="surface must be a Surface"):
        sample_surface(box(), 0.1)


def test_surface_validates_arrays():
    pts = np.eye(3)
    with pytest.raises(ValueError, match=r"points must be an \(n, 3\) array"):
        Surface(pts[:, :2], [[0, 1, 2]], "s")
    with pytest.raises(ValueError, match=r"triangles must have shape \(m, 3\)"):
        Surface(pts, [[0, 1]], "s")
    with pytest.raises(ValueError, match=r"ids must lie in \[0, 2\], got ids from 0 to 3"):
        Surface(pts, [[0, 1, 3]], "s")
    with pytest.raises(ValueError, match="integer vertex ids"):
        Surface(pts, [[0, 1, 1.5]], "s")
    s = Surface(pts, [[0.0, 1.0, 2.0]], "s")
    assert s.triangles.dtype == np.int64

"""Structured generators: counts, orientation, conformity, side sets, argument checks."""

import numpy as np
import pytest

from tissuesim.errors import MeshError
from tissuesim.mesh import box, facet_normals, rectangle, signed_volumes
from tissuesim.mesh.queries.boundary import all_facets, facet_table


def assert_conforming(mesh, n_boundary):
    _, _, _, counts = facet_table(mesh.cells)
    assert set(np.unique(counts)) <= {1, 2}
    assert (counts == 1).sum() == n_boundary


@pytest.mark.parametrize("pattern", ["right", "left", "alternate", "cross"])
def test_rectangle_counts_volume_conforming(pattern):
    nx, ny = 4, 3
    m = rectangle((-1.0, 2.0), (1.0, 3.5), (nx, ny), pattern=pattern)
    extra = nx * ny if pattern == "cross" else 0
    assert m.points.shape == ((nx + 1) * (ny + 1) + extra, 2)
    assert m.cells.shape == ((4 if pattern == "cross" else 2) * nx * ny, 3)
    assert m.points.dtype == np.float64 and m.cells.dtype == np.int64
    vol = signed_volumes(m.points, m.cells)
    assert (vol > 0).all()
    assert vol.sum() == pytest.approx(2.0 * 1.5)
    assert_conforming(m, 2 * (nx + ny))
    assert "rectangle(" in m.source and "divisions=(4, 3)" in m.source


def test_alternate_uses_both_diagonals():
    m = rectangle(divisions=(2, 2), pattern="alternate")
    r = rectangle(divisions=(2, 2), pattern="right")
    assert not np.array_equal(np.sort(m.cells, axis=1), np.sort(r.cells, axis=1))


@pytest.mark.parametrize("pattern", ["mirrored", "uniform"])
def test_box_counts_volume_conforming(pattern):
    nx, ny, nz = 2, 3, 4
    m = box((0, 0, 0), (2.0, 1.0, 0.5), (nx, ny, nz), pattern=pattern)
    assert m.points.shape == ((nx + 1) * (ny + 1) * (nz + 1), 3)
    assert m.cells.shape == (6 * nx * ny * nz, 4)
    vol = signed_volumes(m.points, m.cells)
    assert (vol > 0).all()
    assert vol.sum() == pytest.approx(1.0)
    assert_conforming(m, 4 * (nx * ny + ny * nz + nx * nz))


def _mirror_map(mesh, axis: int):
    """The cells of ``mesh`` reflected about its mid-plane normal to ``axis``, as sorted vertex
    tuples (None when the points do not map onto points)."""
    lo, hi = mesh.points[:, axis].min(), mesh.points[:, axis].max()
    P = mesh.points.copy()
    P[:, axis] = lo + hi - P[:, axis]
    index = {tuple(np.round(p, 12)): i for i, p in enumerate(mesh.points)}
    image = [index.get(tuple(np.round(p, 12))) for p in P]
    if None in image:
        return None
    return {tuple(sorted(np.asarray(image)[c])) for c in mesh.cells}


def test_the_default_box_is_mirror_symmetric_about_its_mid_planes():
    """A centred press must meet no mesh-made lateral force: the default split is mirrored
    (even divisions: exactly symmetric); the uniform Kuhn split is not."""
    m = box((0, 0, 0), (2.0, 1.0, 0.5), (4, 2, 2))
    u = box((0, 0, 0), (2.0, 1.0, 0.5), (4, 2, 2), pattern="uniform")
    for axis in range(3):
        assert _mirror_map(m, axis) == {tuple(sorted(c)) for c in m.cells}
        assert _mirror_map(u, axis) != {tuple(sorted(c)) for c in u.cells}
    assert "pattern='uniform'" in u.source and "pattern" not in m.source
    with pytest.raises(MeshError, match="pattern must be 'mirrored' or 'uniform', got 'crossed'"):
        box(pattern="crossed")


def test_rectangle_side_sets():
    m = rectangle((0, 0), (2, 1), (4, 2))
    for name, axis, value in [("left", 0, 0), ("right", 0, 2), ("bottom", 1, 0), ("top", 1, 1)]:
        ids = m.point_sets[name]
        np.testing.assert_array_equal(ids, np.flatnonzero(m.points[:, axis] == value))
        f = m.facet_sets[name]
        assert len(f) == (4 if axis == 1 else 2)
        assert np.isin(f, ids).all()
        normal = facet_normals(m.points, f)
        expected = np.zeros(2)
        expected[axis] = 1.0 if value > 0 else -1.0
        np.testing.assert_allclose(normal, np.broadcast_to(expected, normal.shape), atol=1e-12)
    for alias, name in [("xmin", "left"), ("xmax", "right"), ("ymin", "bottom"), ("ymax", "top")]:
        np.testing.assert_array_equal(m.facet_sets[alias], m.facet_sets[name])


def test_box_side_sets_outward():
    m = box(divisions=(2, 2, 3))
    for axis, (lo, hi) in enumerate([("xmin", "xmax"), ("ymin", "ymax"), ("zmin", "zmax")]):
        for name, value, sign in [(lo, 0.0, -1.0), (hi, 1.0, 1.0)]:
            np.testing.assert_array_equal(
                m.point_sets[name], np.flatnonzero(m.points[:, axis] == value)
            )
            n = facet_normals(m.points, m.facet_sets[name])
            np.testing.assert_allclose(n[:, axis], sign)
        other = [k for k in range(3) if k != axis]
        assert len(m.facet_sets[lo]) == 2 * np.prod(np.array([2, 2, 3])[other])


def test_kuhn_faces_match_between_neighbours():
    # every interior facet is shared by exactly two cells, with opposite orientation
    m = box(divisions=(2, 2, 2))
    facets, first, inverse, counts = facet_table(m.cells)
    interior = np.flatnonzero(counts[inverse] == 2)
    f = facets[interior]
    order = np.argsort(inverse[interior], kind="stable")
    a, b = f[order[0::2]], f[order[1::2]]
    na = np.cross(*(m.points[a[:, 1:]] - m.points[a[:, :1]]).transpose(1, 0, 2))
    nb = np.cross(*(m.points[b[:, 1:]] - m.points[b[:, :1]]).transpose(1, 0, 2))
    np.testing.assert_allclose(na, -nb, atol=1e-12)
    assert all_facets(m.cells).shape == (m.n_cells, 4, 3)


@pytest.mark.parametrize(
    "kwargs, word",
    [
        ({"divisions": (0, 2)}, "divisions"),
        ({"divisions": (2.5, 2)}, "divisions"),
        ({"divisions": (2,)}, "divisions"),
        ({"lower": (1, 0), "upper": (0, 1)}, "upper[0]"),
        ({"lower": (0, np.nan)}, "lower"),
        ({"pattern": "diagonal"}, "pattern"),
    ],
)
def test_rectangle_bad_arguments(kwargs, word):
    with pytest.raises(MeshError, match=word.replace("[", r"\[")):
        rectangle(**kwargs)


def test_box_bad_arguments():
    with pytest.raises(MeshError, match="divisions"):
        box(divisions=(1, 1))
    with pytest.raises(MeshError, match=r"upper\[2\]"):
        box(upper=(1, 1, 0))

"""Boundary facets, measures, normals and selections."""

import numpy as np
import pytest

from tissuesim.errors import MeshError
from tissuesim.mesh import (
    boundary_facets,
    box,
    facet_measures,
    facet_normals,
    rectangle,
    select,
)


@pytest.mark.parametrize("mesh", [rectangle(divisions=(3, 4), pattern="cross"), box()])
def test_boundary_normals_point_outward(mesh):
    f = boundary_facets(mesh.cells)
    assert f.dtype == np.int64 and f.shape[1] == mesh.dim
    # facet centroid minus the centroid of its own cell points along the outward normal
    n = facet_normals(mesh.points, f)
    for k in range(len(f)):  # test-only loop: find each facet's cell
        owners = mesh.cells[np.isin(mesh.cells, f[k]).sum(axis=1) == mesh.dim]
        assert len(owners) == 1
        cell = owners[0]
        out = mesh.points[f[k]].mean(axis=0) - mesh.points[cell].mean(axis=0)
        assert out @ n[k] > 0
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    assert facet_measures(mesh.points, f).sum() == pytest.approx(4.0 if mesh.dim == 2 else 6.0)


def test_facet_measures_values():
    p = np.array([[0.0, 0, 0], [3, 0, 0], [0, 4, 0]])
    assert facet_measures(p, [[0, 1, 2]])[0] == pytest.approx(6.0)
    np.testing.assert_allclose(facet_normals(p, [[0, 1, 2]]), [[0, 0, 1]])
    assert facet_measures(p[:, :2], [[1, 2]])[0] == pytest.approx(5.0)


def test_vertex_selections():
    m = rectangle((0, 0), (2, 1), (4, 2))
    np.testing.assert_array_equal(select.vertices_on_plane(m, 0, 0.0), m.point_sets["left"])
    ids = select.vertices_on_plane(m, 1, 1.0 + 1e-9)
    assert ids.dtype == np.int64 and len(ids) == 5
    np.testing.assert_array_equal(select.vertices_in_box(m, (0, 0), (0.5, 0.5)), [0, 1, 5, 6])
    np.testing.assert_array_equal(select.vertices_tagged(m, "top"), m.point_sets["top"])
    assert len(select.boundary_vertices(m)) == 12
    with pytest.raises(MeshError, match=r"plane x = 3.*bounding box \[0, 2\] x \[0, 1\]"):
        select.vertices_on_plane(m, 0, 3.0)
    with pytest.raises(MeshError, match="no vertices in the box"):
        select.vertices_in_box(m, (0.1, 0.1), (0.2, 0.2))
    with pytest.raises(MeshError, match=r"no set named 'front'.*'left'"):
        select.vertices_tagged(m, "front")
    with pytest.raises(MeshError, match="axis"):
        select.vertices_on_plane(m, 2, 0.0)


def test_facet_selections():
    m = box(divisions=(2, 2, 2))
    f = select.facets_on_plane(m, 2, 1.0)
    assert f.shape == (8, 3)
    np.testing.assert_allclose(facet_normals(m.points, f)[:, 2], 1.0)
    np.testing.assert_array_equal(select.facets_tagged(m, "zmax"), m.facet_sets["zmax"])
    assert len(select.facets_in_box(m, (0, 0, 0), (1, 1, 0))) == 8
    assert len(select.facets_in_box(m, (0, 0, 0), (0.5, 0.5, 0.5))) == 6
    assert len(select.all_boundary_facets(m)) == 48
    with pytest.raises(MeshError, match="z = 0.5"):
        select.facets_on_plane(m, 2, 0.5)  # interior plane: no boundary facets
    with pytest.raises(MeshError, match="no facet set or point set named 'top'"):
        select.facets_tagged(m, "top")

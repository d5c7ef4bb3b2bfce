"""The ellipsoid generator: orientation, conformity, volume convergence, surface sets."""

import numpy as np
import pytest

from tissuesim.errors import MeshError
from tissuesim.mesh import box, ellipsoid, facet_normals, signed_volumes
from tissuesim.mesh.generators.ellipsoids import _cube_to_ball
from tissuesim.mesh.queries.boundary import boundary_facets, facet_table

RADII = (1.0, 0.7, 0.5)
CENTER = (0.3, -1.0, 2.0)


@pytest.mark.parametrize("n", range(2, 13))
def test_positive_conforming_and_inscribed(n):
    m = ellipsoid(CENTER, RADII, n)
    assert m.points.shape == ((n + 1) ** 3, 3) and m.cells.shape == (6 * n**3, 4)
    assert (signed_volumes(m.points, m.cells) > 0).all()
    counts = facet_table(m.cells)[3]
    assert counts.max() == 2 and (counts == 1).sum() == 12 * n * n  # closed, no hanging faces
    rho = np.sqrt((((m.points - CENTER) / RADII) ** 2).sum(axis=1))
    surface = m.point_sets["surface"]
    np.testing.assert_allclose(rho[surface], 1.0, atol=1e-12)
    assert (rho[np.setdiff1d(np.arange(m.n_points), surface)] < 1.0).all()
    assert "ellipsoid(" in m.source and f"divisions={n}" in m.source


def test_volume_converges():
    exact = 4.0 / 3.0 * np.pi * np.prod(RADII)
    err = {}
    for n in (4, 8, 12):
        m = ellipsoid(CENTER, RADII, n)
        err[n] = signed_volumes(m.points, m.cells).sum() / exact - 1.0
    # inscribed: always below; measured -6.2%, -1.6%, -0.72%: second order in 1/n
    assert -0.07 < err[4] < err[8] < err[12] < 0.0
    assert abs(err[8]) < 0.03 and abs(err[12]) < 0.008
    assert err[8] / err[12] == pytest.approx((12 / 8) ** 2, rel=0.1)


def test_surface_sets_are_the_outward_boundary():
    m = ellipsoid(CENTER, RADII, 6)
    f = m.facet_sets["surface"]
    assert len(f) == len(boundary_facets(m.cells))
    np.testing.assert_array_equal(np.unique(f), m.point_sets["surface"])
    centroid = m.points[f].mean(axis=1) - CENTER
    assert (np.einsum("ki,ki->k", facet_normals(m.points, f), centroid) > 0).all()


def test_mirrored_pattern_beats_plain_box_pattern():
    # at the cube corners the map flattens tets; the mirrored Kuhn pattern keeps them fatter
    def worst(points, cells):
        x = points[cells]
        i, j = np.triu_indices(4, 1)
        rms = np.sqrt(((x[:, j] - x[:, i]) ** 2).sum(axis=2).mean(axis=1))
        return (signed_volumes(points, cells) / (rms**3 / (6 * np.sqrt(2)))).min()

    m = ellipsoid(divisions=8)
    b = box((-1, -1, -1), (1, 1, 1), (8, 8, 8), pattern="uniform")  # same grid, plain Kuhn
    assert worst(m.points, m.cells) > 5 * worst(_cube_to_ball(b.points), b.cells)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"radii": (1, 0, 1)}, "radii must all be > 0"),
        ({"radii": (1, 1)}, "radii must be 3 finite numbers"),
        ({"center": (0, np.nan, 0)}, "center must be 3 finite numbers"),
        ({"divisions": 0}, "divisions must be an integer >= 1"),
        ({"divisions": 2.5}, "divisions must be an integer >= 1"),
        ({"divisions": True}, "divisions must be an integer >= 1"),
    ],
)
def test_bad_arguments(kwargs, match):
    with pytest.raises(MeshError, match=match):
        ellipsoid(**kwargs)

"""The penalty contact's facets (contact/penalty/faces.py): tri3, quad4, tri6 and quad8 shape
functions (partition of unity, one at their own node, derivatives against central
differences), FEBio's sample rules integrating a facet's area, and a quadratic mesh's facets
given by their corners lifted to their midside nodes."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.contact.penalty.faces import (
    Facets,
    area_jacobians,
    sample_points,
    shape,
    shape_derivatives,
    with_midsides,
)
from tissuesim.errors import InputError
from tissuesim.mesh import box

NODES = {
    3: [[0, 0], [1, 0], [0, 1]],
    4: [[-1, -1], [1, -1], [1, 1], [-1, 1]],
    6: [[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]],
    8: [[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0]],
}


@pytest.mark.parametrize("kind", [3, 4, 6, 8])
def test_shape_functions_interpolate_and_their_derivatives_match_finite_differences(kind):
    width = 4 if kind <= 4 else 8
    nodes = np.array(NODES[kind], float)
    k = np.full(len(nodes), kind)
    np.testing.assert_allclose(shape(nodes[:, 0], nodes[:, 1], k, width)[:, :kind],
                               np.eye(kind), atol=1e-14)  # fmt: skip
    rs = np.random.default_rng(1).uniform(0.05, 0.3, (5, 2)) * (1 if kind in (3, 6) else 3)
    kk = np.full(len(rs), kind)
    H = shape(rs[:, 0], rs[:, 1], kk, width)
    np.testing.assert_allclose(H.sum(axis=1), 1.0, atol=1e-14)
    assert np.all(H[:, kind:] == 0.0)
    Hr, Hs, Hrr, Hss, Hrs = shape_derivatives(rs[:, 0], rs[:, 1], kk, width)
    e = 1e-6

    def at(dr, ds, f=0):
        return (shape if f == 0 else lambda *a: shape_derivatives(*a)[f - 1])(
            rs[:, 0] + dr, rs[:, 1] + ds, kk, width
        )

    np.testing.assert_allclose(Hr, (at(e, 0) - at(-e, 0)) / (2 * e), atol=1e-8)
    np.testing.assert_allclose(Hs, (at(0, e) - at(0, -e)) / (2 * e), atol=1e-8)
    np.testing.assert_allclose(Hrr, (at(e, 0, 1) - at(-e, 0, 1)) / (2 * e), atol=1e-7)
    np.testing.assert_allclose(Hss, (at(0, e, 2) - at(0, -e, 2)) / (2 * e), atol=1e-7)
    np.testing.assert_allclose(Hrs, (at(0, e, 1) - at(0, -e, 1)) / (2 * e), atol=1e-7)
    if kind > 4:
        assert np.abs(Hrr).max() > 0.1  # quadratic: curvature terms present


@pytest.mark.parametrize(("kind", "rule"), [(3, "gauss"), (4, "gauss"), (6, "gauss"),
                                            (8, "gauss"), (3, "nodal"), (4, "nodal")])  # fmt: skip
def test_the_rules_integrate_a_curved_facets_area(kind, rule):
    """A facet bent into a cylinder-like shape x -> (x, y, 0.1 x^2): the Gauss rules integrate
    its area as a fine midpoint sum does (to their order); the nodal rules sum to a flat
    facet's area."""
    width = 4 if kind <= 4 else 8
    ref = np.array(NODES[kind], float)
    curved = kind > 4
    X = np.column_stack([ref, 0.1 * ref[:, 0] ** 2 if curved else np.zeros(kind)])
    X = np.vstack([X, np.repeat(X[-1:], width - kind, axis=0)])
    f = Facets.of(np.arange(width)[None], "t", kind=np.array([kind]))
    pts = sample_points(f, rule)
    area = float(np.sum(pts.weight * area_jacobians(X, f, pts)))
    m = 400  # midpoint sum on the reference facet
    i, j = (a.ravel() for a in np.meshgrid(np.arange(m), np.arange(m)))
    r, s = (i + 0.5) / m, (j + 0.5) / m
    cell = np.full(len(r), 4.0 / m**2)
    if kind in (3, 6):  # the cells under the hypotenuse, the ones it halves by half
        keep = i + j <= m - 1
        r, s, cell = r[keep], s[keep], np.where(i[keep] + j[keep] == m - 1, 0.5, 1.0) / m**2
    else:
        r, s = 2 * r - 1, 2 * s - 1
    fine = Facets.of(np.arange(width)[None].repeat(len(r), 0), "t", kind=np.full(len(r), kind))
    Hr, Hs, *_ = shape_derivatives(r, s, fine.kind, width)
    J = np.linalg.norm(np.cross(Hr @ X, Hs @ X), axis=1)
    assert area == pytest.approx(float(np.sum(J * cell)), rel=2e-4 if curved else 1e-9)


def test_a_quadratic_meshs_corner_facets_get_their_midside_nodes():
    for element, order, kind in (("hex20", 2, 8), ("tet", 2, 6)):
        mesh = box((0, 0, 0), (1, 1, 1), (2, 2, 2), element=element, order=order)
        corners = np.asarray(mesh.facet_sets["zmax"])[:, : 4 if kind == 8 else 3]
        f = with_midsides(mesh, Facets.of(corners, "t"))
        assert np.all(f.kind == kind)
        P = mesh.points[f.nodes]
        c = {8: [(0, 1), (1, 2), (2, 3), (3, 0)], 6: [(0, 1), (1, 2), (2, 0)]}[kind]
        for j, (a, b) in enumerate(c):  # straight edges: each midside node halfway
            np.testing.assert_allclose(P[:, kind // 2 + j], 0.5 * (P[:, a] + P[:, b]), atol=1e-12)
    linear = box((0, 0, 0), (1, 1, 1), (2, 2, 2), element="hex")
    f = Facets.of(linear.facet_sets["zmax"], "t")
    assert with_midsides(linear, f) is f
    mesh = box((0, 0, 0), (1, 1, 1), (2, 2, 2), element="hex20")
    with pytest.raises(InputError, match="no face of the body's hexahedron20 cells"):
        with_midsides(mesh, Facets.of(np.array([[0, 1, 2, 3]]) * 0 + [[0, 2, 4, 6]], "t"))

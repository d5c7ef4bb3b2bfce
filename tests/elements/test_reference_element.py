"""Reference simplex: quadrature exactness and the P1/P2 shape functions."""

from math import factorial

import numpy as np
import pytest

from tissuesim.mesh.cells.reference import facet_quadrature, quadrature, shape_functions


def exact_monomial(powers) -> float:
    """int over the reference simplex of prod xi_j^p_j = prod p_j! / (sum p + d)!"""
    num = np.prod([factorial(p) for p in powers])
    return num / factorial(sum(powers) + len(powers))


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("degree", [1, 2, 4, 5])
def test_quadrature_is_exact_to_its_degree(dim, degree):
    xi, w = quadrature(dim, degree)
    assert np.all(w > 0)
    assert (xi >= 0).all() and (xi.sum(axis=1) <= 1 + 1e-14).all()
    for powers in np.ndindex(*(degree + 1,) * dim):
        if sum(powers) > degree:
            continue
        got = float(w @ np.prod(xi ** np.array(powers), axis=1))
        assert got == pytest.approx(exact_monomial(powers), rel=1e-12, abs=1e-15)


def test_the_degree_two_rules_are_not_exact_to_degree_three():
    # a check that can fail: the 3- and 4-point rules integrate some cubic wrongly
    for dim, powers in ((2, (3, 0)), (3, (3, 0, 0))):
        xi, w = quadrature(dim, 2)
        got = float(w @ np.prod(xi ** np.array(powers), axis=1))
        assert abs(got - exact_monomial(powers)) > 1e-6


def test_facet_rule_is_one_dimension_lower():
    xi, w = facet_quadrature(3, 5)
    assert xi.shape[1] == 2 and w.sum() == pytest.approx(0.5)


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("order", [1, 2])
def test_shape_functions_interpolate_and_sum_to_one(dim, order):
    # nodes: corners, then the midpoints of mesh/quadratic.EDGES
    from tissuesim.mesh.cells.quadratic import EDGES

    corners = np.concatenate([np.zeros((1, dim)), np.eye(dim)])
    nodes = corners if order == 1 else np.concatenate([corners, corners[EDGES[dim]].mean(axis=1)])
    N, dN = shape_functions(dim, order, nodes)
    np.testing.assert_allclose(N, np.eye(len(nodes)), atol=1e-14)
    rng = np.random.default_rng(0)
    xi = rng.dirichlet(np.ones(dim + 1), 20)[:, 1:]
    N, dN = shape_functions(dim, order, xi)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-13)
    np.testing.assert_allclose(dN.sum(axis=1), 0.0, atol=1e-13)
    # they reproduce the coordinates (isoparametric) and their gradients the identity
    np.testing.assert_allclose(N @ nodes, xi, atol=1e-13)
    grad_x = np.einsum("ai,qaj->qij", nodes, dN)
    np.testing.assert_allclose(grad_x, np.broadcast_to(np.eye(dim), (20, dim, dim)), atol=1e-13)


@pytest.mark.parametrize("dim", [2, 3])
def test_shape_gradients_match_differences(dim):
    rng = np.random.default_rng(1)
    xi = rng.dirichlet(np.ones(dim + 1), 5)[:, 1:] * 0.9
    _, dN = shape_functions(dim, 2, xi)
    eps = 1e-6
    for j in range(dim):
        e = np.zeros(dim)
        e[j] = eps
        fd = (shape_functions(dim, 2, xi + e)[0] - shape_functions(dim, 2, xi - e)[0]) / (2 * eps)
        np.testing.assert_allclose(dN[:, :, j], fd, atol=1e-8)

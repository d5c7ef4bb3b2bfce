"""FEBio's special cases of the closest-point projection (contact/penalty/special_cases.py):
a point behind a concave valley (or pit) of the secondary surface, whose projection lands on
no facet, is projected onto the valley's edge (or the pit's node) and gets contact; the gap's
gradient and Hessian against central differences; the energy continuous across the valley;
the FEBio converter's flag per contact type."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.contact.penalty.faces import Facets
from tissuesim.contact.penalty.pair import PenaltyContact, PenaltySide
from tissuesim.contact.penalty.special_cases import Topology
from tissuesim.febio.condition_sections import _penalty_settings

RNG = np.random.default_rng(11)
H = 0.5  # the pit's slope: z = H (|x| + |y|)


def _pit() -> tuple[np.ndarray, np.ndarray]:
    """A 3 x 3 grid of nodes at z = H (|x| + |y|): four quads around a pit at the centre
    node, valleys along the axes, normals up (into the pit)."""
    xy = np.array([[x, y] for y in (-1.0, 0.0, 1.0) for x in (-1.0, 0.0, 1.0)])
    nodes = np.column_stack([xy, H * np.abs(xy).sum(axis=1)])
    quads = np.array([[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]])
    return nodes, quads


def _pair(point: np.ndarray, special: bool, **options) -> tuple[PenaltyContact, list]:
    """The pit (body 0) and one primary triangle (body 1) sampled at its corners: the first
    is ``point``, the others far out of reach."""
    nodes, quads = _pit()
    tri = np.array([point, point + [100.0, 0, 0], point + [0, 100.0, 0]])
    sides = (
        PenaltySide(1, Facets.of([[0, 1, 2]], "tri"), np.ones(1)),
        PenaltySide(0, Facets.of(quads, "pit"), np.ones(4)),
    )
    pair = PenaltyContact("p", *sides, penalty=100.0, rule="nodal", special_cases=special,
                          **options)  # fmt: skip
    rest = [nodes, tri]
    pair.setup(rest)
    return pair, rest


def _dofs(rest):
    n0 = len(rest[0]) * 3
    dofs = [np.arange(n0).reshape(-1, 3), n0 + np.arange(len(rest[1]) * 3).reshape(-1, 3)]
    return dofs, n0 + len(rest[1]) * 3


#: behind the valley along +x (an edge projection) and behind the pit (the centre node)
BEHIND = {"edge": np.array([0.5, 0.0, 0.25 - 0.1]), "node": np.array([0.0, 0.0, -0.1])}


def test_topology_finds_interior_edges_and_boundary_nodes():
    """The pit's four axis edges are interior; every node but the centre is on the
    boundary."""
    nodes, quads = _pit()
    topo = Topology.of(Facets.of(quads, "pit"))
    edges = {tuple(sorted(topo.nodes[e])) for e in topo.edge_nodes}
    assert edges == {(1, 4), (3, 4), (4, 5), (4, 7)}
    assert np.flatnonzero(~topo.boundary).tolist() == [4]


@pytest.mark.parametrize("where", ["edge", "node"])
def test_a_point_behind_a_valley_gets_contact_only_with_special_cases(where):
    """Behind the valley (or pit) the point's projection is on no facet: no contact without
    the special cases; with them, the gap is its distance to the edge (node)."""
    x = BEHIND[where]
    for special in (False, True):
        pair, rest = _pair(x, special)
        dofs, n = _dofs(rest)
        value, grad, _ = pair.evaluate(rest, dofs, n, 1)
        if not special:
            assert value == 0.0 and not grad.any()
            continue
        if where == "edge":  # the closest point of the edge (0,0,0)-(1,0,H)
            e = np.array([1.0, 0.0, H])
            q = e * (e @ x) / (e @ e)
        else:
            q = np.zeros(3)
        g = np.linalg.norm(q - x)
        W = pair.passes[0].weights[0]
        assert value == pytest.approx(W * 100.0 * g * g / 2, rel=1e-12)
        # the point is pushed out along q - x
        f = -grad[27:30]
        np.testing.assert_allclose(f / np.linalg.norm(f), (q - x) / g, atol=1e-12)


@pytest.mark.parametrize("where", ["edge", "node"])
@pytest.mark.parametrize("augmented", [False, True])
def test_special_gradient_and_hessian_match_central_differences(where, augmented):
    """The pit perturbed (still a pit), the point behind it: the pair's gradient and Hessian
    against central differences of its energy and gradient (augmented: a multiplier)."""
    pair, rest = _pair(BEHIND[where], True)
    if augmented:
        pair.passes[0].multipliers[:] = 3.0
    positions = [r + 0.005 * RNG.standard_normal(r.shape) for r in rest]
    positions[1][1:] = rest[1][1:]  # the far corners stay far
    found = pair._search(pair.passes[0], positions)
    assert len(found[4].rows) == 1  # the point is a special case
    assert np.all(np.diff(found[0]) > 0)  # points in order (friction.py searches them)
    dofs, n = _dofs(rest)
    n0 = len(rest[0]) * 3
    flat = np.concatenate([p.ravel() for p in positions])

    def split(v):
        return [v[:n0].reshape(-1, 3), v[n0:].reshape(-1, 3)]

    value, grad, hess = pair.evaluate(positions, dofs, n, 2)
    assert value > 0
    e = 1e-6
    active = np.flatnonzero(np.abs(grad) > 0)
    assert len(active) >= 6
    scale = np.abs(hess).max()  # the differences' noise: ~1e-16 |grad| / e
    for i in active:
        d = np.zeros(n)
        d[i] = e
        vp, gp, _ = pair.evaluate(split(flat + d), dofs, n, 1)
        vm, gm, _ = pair.evaluate(split(flat - d), dofs, n, 1)
        assert grad[i] == pytest.approx((vp - vm) / (2 * e), rel=1e-6, abs=1e-9)
        np.testing.assert_allclose(hess[:, i].toarray().ravel(), (gp - gm) / (2 * e),
                                   rtol=1e-5, atol=1e-7 * scale)  # fmt: skip
    np.testing.assert_allclose(hess.toarray(), hess.toarray().T, atol=1e-10)


def _path_energies(special: bool, depth: float) -> tuple[np.ndarray, float, float]:
    """The pair's energy as the point moves straight across the valley along +x (y from
    -0.4 to 0.4 at x = 0.5, z = 0.2: ``depth`` under the valley's line), its step and the
    point's weight."""
    ys = np.linspace(-0.4, 0.4, 801)
    pair, rest = _pair(BEHIND["edge"], special)  # FEBio's search tolerance, 0.01
    dofs, n = _dofs(rest)
    out = []
    for y in ys:
        tri = rest[1].copy()
        tri[0] = [0.5, y, H * 0.5 - depth]
        out.append(pair.evaluate([rest[0], tri], dofs, n, 0)[0])
    return np.array(out), ys[1] - ys[0], pair.passes[0].weights[0]


def test_a_point_past_the_rim_keeps_its_facet_within_the_search_tolerance():
    """Just past a boundary edge (no edge or node takes it: the rim's nodes are on the
    boundary) the point keeps its facet within the search tolerance, FEBio's band, and
    beyond the band it is out of contact."""
    for dx, touching in ((0.002, True), (0.05, False)):
        x = np.array([1.0 + dx, 0.5, H * 1.5 - 0.01])  # behind the last facet's rim x = 1
        pair, rest = _pair(x, True)
        found = pair._search(pair.passes[0], rest)
        assert len(found[4].rows) == 0
        assert (0 in found[0]) is touching


def test_the_energy_is_continuous_across_the_valley():
    """Sampled across the valley (facet, edge, facet), the energy's second differences stay
    at the size of a smooth function's (h^2 E''); without the special cases the point drops
    out of contact behind the valley and the energy jumps."""
    E, h, W = _path_energies(True, 0.05)
    assert np.all(E > 0)
    second = np.abs(np.diff(E, 2))
    # E = W eps g^2 / 2 with |dg/dy| <= 1 and curvature of g ~ 1 / g: E'' <= W eps (1 + 1)
    assert second.max() <= 4 * W * 100.0 * h * h
    jumps = np.abs(np.diff(E))
    assert jumps.max() <= 2 * W * 100.0 * 0.2 * h  # |E'| <= W eps g |dg/dy|, g <= 0.2
    E0, _, _ = _path_energies(False, 0.05)
    assert np.any(E0 == 0) and np.abs(np.diff(E0)).max() > 10 * jumps.max()


@pytest.mark.parametrize(
    ("kind", "special"),
    [
        ("sliding-node-on-facet", False),  # dy04 off FEBio's norm with them
        ("sliding-facet-on-facet", False),  # co13 off FEBio's norm with them
        ("tied-facet-on-facet", True),
        ("tied-node-on-facet", True),
        ("sticky", True),
        ("sliding-elastic", False),
        ("tied-elastic", False),
    ],
)
def test_the_converter_sets_special_cases_for_febios_closest_point_contacts(kind, special):
    """FEBio's HandleSpecialCases(true) contacts convert with special_cases on (but the
    sliding ones: co13 and dy04 drifted from FEBio's norm with them); the ray-casting
    sliding-elastic and tied-elastic without."""
    assert _penalty_settings(kind, None, {}).get("special_cases", False) is special


def test_a_surface_without_interior_edges_takes_no_edge_projection():
    """A secondary surface of one facet (FEBio's co19: a single quad) has no interior edge: a
    point past its rim is left alone (its nodes are all boundary nodes), no error."""
    quad = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    point = np.array([1.5, 0.5, -0.05])
    tri = np.array([point, point + [100.0, 0, 0], point + [0, 100.0, 0]])
    sides = (
        PenaltySide(1, Facets.of([[0, 1, 2]], "tri"), np.ones(1)),
        PenaltySide(0, Facets.of([[0, 1, 2, 3]], "quad"), np.ones(1)),
    )
    pair = PenaltyContact("p", *sides, penalty=100.0, rule="nodal", special_cases=True)
    rest = [quad, tri]
    pair.setup(rest)
    dofs, n = _dofs(rest)
    value, grad, _ = pair.evaluate(rest, dofs, n, 2)
    assert value == 0.0 and not np.any(grad)
    inside = [quad, np.array([[0.5, 0.5, -0.05], [100.5, 0.5, 0], [0.5, 100.5, 0]])]
    assert pair.evaluate(inside, dofs, n, 0)[0] > 0.0  # the facet itself still holds

"""Penalty / augmented-Lagrangian contact (contact/penalty/, FEBio's sliding contacts): the gap's
exact derivatives and the pair's energy against finite differences, the force balance, a
closed form for the penetration (pressure / penalty), the augmented Lagrangian converging to
the contact of one block, Newton's quadratic convergence, the scene table and its errors."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.penalty.faces import Facets
from tissuesim.contact.penalty.pair import PenaltyContact, PenaltySide
from tissuesim.contact.penalty.projection import gap_derivatives, project, projection_jacobian
from tissuesim.errors import InputError, SceneError
from tissuesim.materials import NeoHookean
from tissuesim.mesh import box
from tissuesim.scene.loader import build_scene

RNG = np.random.default_rng(7)


#: facet nodes in the plane z = 0 per kind (corners, then midsides), in faces.py's order
_FLAT = {
    3: [[0, 0], [1, 0], [0, 1]],
    4: [[0, 0], [1, 0], [1, 1], [0, 1]],
    6: [[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]],
    8: [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5]],
}


def _stencil_gap(y, Hs, kind, width, order):
    S, X = y[:12].reshape(4, 3), y[12:].reshape(width, 3)
    x = (Hs @ S)[None]
    t = np.array([kind])
    rs = project(x, X[None], t)
    return gap_derivatives(x, Hs[None], X[None], rs, t, order)


@pytest.mark.parametrize("kind", [4, 3, 8, 6])
def test_gap_gradient_and_hessian_match_finite_differences(kind):
    """A warped facet of each kind (quad4, tri3, and the curved quad8, tri6) and a point
    behind it: g > 0, dg/dy and d2g/dy2 over the stencil (4 sampled nodes, then the facet's,
    padded to 4 or 8 by its last node) against central differences of g and dg/dy."""
    rng = np.random.default_rng(7 + kind)  # its own: the same facet whatever ran before
    width = 4 if kind <= 4 else 8
    flat = np.array(_FLAT[kind], float)
    X = np.column_stack([flat, np.zeros(kind)]) + 0.15 * rng.standard_normal((kind, 3))
    X = np.vstack([X, np.repeat(X[-1:], width - kind, axis=0)])
    S = np.array([[0, 0, -0.3], [1, 0, -0.3], [1, 1, -0.3], [0, 1, -0.3]], float)
    S += 0.1 * rng.standard_normal((4, 3))
    Hs = np.array([0.3, 0.2, 0.4, 0.1]) if kind in (4, 8) else np.array([0.3, 0.2, 0.2, 0.3])
    y = np.concatenate([S.ravel(), X.ravel()])
    g, _, _, dg, d2g = _stencil_gap(y, Hs, kind, width, 2)
    assert g[0] > 1e-3  # behind the facet
    n = y.size
    e, fd, fh = 1e-6, np.zeros(n), np.zeros((n, n))
    for i in range(n):
        d = np.zeros(n)
        d[i] = e
        gp = _stencil_gap(y + d, Hs, kind, width, 1)
        gm = _stencil_gap(y - d, Hs, kind, width, 1)
        fd[i] = (gp[0][0] - gm[0][0]) / (2 * e)
        fh[:, i] = (gp[3].ravel() - gm[3].ravel()) / (2 * e)
    used = slice(0, 12 + 3 * kind)  # the padding's repeated nodes carry nothing
    np.testing.assert_allclose(dg.ravel()[used], fd[used], atol=1e-8)
    np.testing.assert_allclose(d2g[0][used, used], fh[used, used], atol=1e-7)
    np.testing.assert_allclose(d2g[0], d2g[0].T, atol=1e-12)
    assert np.abs(d2g[0]).max() > 1e-3  # a Hessian with curvature, not a zero one


@pytest.mark.parametrize("kind", [4, 3, 8, 6])
def test_the_projections_natural_coordinates_derivative_matches_finite_differences(kind):
    """dr/dy of the closest point's (r, s) over the stencil (a warped facet, a point behind
    it: the gap's and the curvature's terms both count), against central differences of the
    projection (FEBio's node-on-facet friction measures slip by it: friction.py)."""
    rng = np.random.default_rng(11)  # its own: the module's RNG sequence stays the others'
    width = 4 if kind <= 4 else 8
    flat = np.array(_FLAT[kind], float)
    X = np.column_stack([flat, np.zeros(kind)]) + 0.15 * rng.standard_normal((kind, 3))
    X = np.vstack([X, np.repeat(X[-1:], width - kind, axis=0)])
    S = np.array([[0, 0, -0.3], [1, 0, -0.3], [1, 1, -0.3], [0, 1, -0.3]], float)
    S += 0.1 * rng.standard_normal((4, 3))
    Hs = np.array([0.3, 0.2, 0.4, 0.1]) if kind in (4, 8) else np.array([0.3, 0.2, 0.2, 0.3])
    t = np.array([kind])

    def rs_of(y):
        x = (Hs @ y[:12].reshape(4, 3))[None]
        return project(x, y[12:].reshape(1, width, 3), t)[0]

    y = np.concatenate([S.ravel(), X.ravel()])
    x = (Hs @ S)[None]
    g, D = projection_jacobian(x, Hs[None], X[None], rs_of(y)[None], t)
    assert g[0] > 1e-3
    e, fd = 1e-6, np.zeros((2, y.size))
    for i in range(y.size):
        d = np.zeros(y.size)
        d[i] = e
        fd[:, i] = (rs_of(y + d) - rs_of(y - d)) / (2 * e)
    used = slice(0, 12 + 3 * kind)
    np.testing.assert_allclose(D[0][:, used], fd[:, used], atol=1e-8)
    assert np.abs(D[0]).max() > 0.1


def _blocks(dz: float = 0.02, element: str = "hex"):
    lower = box((0, 0, 0), (1, 1, 0.5), (3, 3, 2), element=element)
    upper = box((0.2, 0.15, 0.5 - dz), (0.8, 0.75, 1.0), (2, 2, 2), element=element)
    return lower, upper


def _overlapping_pair(**options):
    """(pair, perturbed positions, DOFs, n, split): two hex blocks overlapping by 2 % (upper's
    bottom quads into lower's top) in a penalty pair of ``options``, every vertex moved a
    little (seeded)."""
    lower, upper = _blocks()
    rest = [lower.points, upper.points]
    sides = (
        PenaltySide(1, Facets.of(upper.facet_sets["zmin"], "u"), np.ones(4)),
        PenaltySide(0, Facets.of(lower.facet_sets["zmax"], "l"), np.full(9, 2.0)),
    )
    pair = PenaltyContact("p", *sides, penalty=50.0, **options)
    pair.setup(rest)
    positions = [r + 0.01 * RNG.standard_normal(r.shape) for r in rest]
    n0 = lower.n_points * 3
    dofs = [np.arange(n0).reshape(-1, 3), n0 + np.arange(upper.n_points * 3).reshape(-1, 3)]

    def split(v):
        return [v[:n0].reshape(-1, 3), v[n0:].reshape(-1, 3)]

    return pair, positions, dofs, n0 + upper.n_points * 3, split


@pytest.mark.parametrize(
    "options",
    [
        {"rule": "gauss"},
        {"rule": "nodal", "two_pass": True},
        {"rule": "gauss", "augmented": True},
        {"rule": "gauss", "augmented": True, "tied": True, "two_pass": True},
        {"rule": "nodal", "tied": True},
        {"rule": "gauss", "tension": True},
    ],
)
def test_pair_energy_gradient_and_hessian_match_finite_differences(options):
    """Two hex blocks overlapping by 2 % (upper's bottom quads into lower's top), perturbed:
    the pair's gradient and Hessian against central differences of its energy and gradient
    (augmented: with non-zero multipliers, some on points out of contact)."""
    augmented = options.pop("augmented", False)
    pair, positions, dofs, n, split = _overlapping_pair(**options)
    if augmented:
        for p in pair.passes:
            p.multipliers = RNG.uniform(0.0, 2.0, p.multipliers.shape)
    flat = np.concatenate([p.ravel() for p in positions])
    value, grad, hess = pair.evaluate(positions, dofs, n, 2)
    assert value > 0 and np.abs(grad).max() > 0
    e = 1e-7
    active = np.flatnonzero(np.abs(grad) > 0)
    for i in active[:: max(1, len(active) // 12)]:
        d = np.zeros(n)
        d[i] = e
        vp, gp, _ = pair.evaluate(split(flat + d), dofs, n, 1)
        vm, gm, _ = pair.evaluate(split(flat - d), dofs, n, 1)
        assert grad[i] == pytest.approx((vp - vm) / (2 * e), rel=1e-5, abs=1e-9)
        np.testing.assert_allclose(hess[:, i].toarray().ravel(), (gp - gm) / (2 * e), atol=1e-5)


@pytest.mark.parametrize("two_pass", [False, True])
def test_the_current_area_weights_coupling_matches_finite_differences(two_pass):
    """With current-area weights that follow the state (FEBio's sliding-elastic, lagged to the
    converged state), the pair's gradient sum_i w_i(x) f_i(x) changes with x through the
    weights too: its Hessian at fixed weights plus area_coupling's term against central
    differences of the gradient with the weights re-taken at each perturbed state."""
    from tissuesim.contact.penalty.area_coupling import area_coupling
    from tissuesim.contact.penalty.faces import area_jacobians

    pair, positions, dofs, n, split = _overlapping_pair(area="current", two_pass=two_pass)
    flat = np.concatenate([p.ravel() for p in positions])

    def following(at):  # the weights taken at the state, as the converged lag leaves them
        for p in pair.passes:
            p.weights = p.points.weight * area_jacobians(at[p.sampled.body], p.sampled.facets,
                                                         p.points)  # fmt: skip
        return pair.evaluate(at, dofs, n, 2)

    _, grad, hess = following(positions)
    C = area_coupling(pair, positions, dofs, n)
    assert C is not None and abs(C).max() > 1e-3 * abs(hess).max()
    total = (hess + C).toarray()
    e = 1e-7
    active = np.flatnonzero(np.abs(grad) > 0)
    for i in active[:: max(1, len(active) // 12)]:
        d = np.zeros(n)
        d[i] = e
        gp = following(split(flat + d))[1]
        gm = following(split(flat - d))[1]
        np.testing.assert_allclose(total[:, i], (gp - gm) / (2 * e), atol=2e-6)
    pair.area = "reference"
    assert area_coupling(pair, positions, dofs, n) is None  # weights that never move


def _pressed(penalty=1e4, augmented=False, two_pass=False, steps=3, integration="gauss"):
    """Upper block (0.6 x 0.6 x 0.5, nu = 0) on lower (1 x 1 x 0.5, base fixed), upper's top
    moved down 0.01 per step, laterally held."""
    lower, upper = _blocks(dz=0.0)
    mat = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    sim.add_body("lower", lower, mat)
    sim.add_body("upper", upper, mat)
    sim.fix(np.flatnonzero(lower.points[:, 2] < 1e-9), body="lower", name="table")
    top = np.flatnonzero(upper.points[:, 2] > 1 - 1e-9)
    sim.grasp(top, lambda t: np.array([0.0, 0.0, -0.01 * t]), body="upper", name="press")
    sim.add_penalty_contact(
        "upper", "lower", primary_facets="zmin", secondary_facets="zmax", penalty=penalty,
        augmented=augmented, tolerance=1e-6, max_augmentations=50, two_pass=two_pass,
        integration=integration, name="contact",
    )  # fmt: skip
    for _ in range(steps):
        record = sim.step()
    return sim, record


def _column(penalty=None, augmented=False, single=False, press=-0.02, element="hex",
            order=1, **options):  # fmt: skip
    """A 1 x 1 column (nu = 0) pressed 0.02 down at its top, base fixed: two blocks of
    matching facets in penalty contact at z = 0.5, or (``single``) one block."""
    mat = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    kw = {"element": element, "order": order}
    if single:
        blocks = {"upper": box((0, 0, 0), (1, 1, 1.0), (2, 2, 4), **kw)}
    else:
        blocks = {
            "lower": box((0, 0, 0), (1, 1, 0.5), (2, 2, 1), **kw),
            "upper": box((0, 0, 0.5), (1, 1, 1.0), (2, 2, 3), **kw),
        }
    for name, mesh in blocks.items():
        sim.add_body(name, mesh, mat)
    base = blocks.get("lower", blocks["upper"])
    sim.fix(np.flatnonzero(base.points[:, 2] < 1e-9), body=next(iter(blocks)), name="table")
    top = np.flatnonzero(blocks["upper"].points[:, 2] > 1 - 1e-9)
    sim.grasp(top, lambda t: np.array([0.0, 0.0, press * t]), body="upper", name="press")
    if not single:
        sim.add_penalty_contact("upper", "lower", primary_facets="zmin",
                                secondary_facets="zmax", penalty=penalty, augmented=augmented,
                                tolerance=1e-8, max_augmentations=60, name="contact",
                                **options)  # fmt: skip
    sim.step()
    return sim, blocks


def test_forces_balance_and_the_penetration_is_the_pressure_over_the_penalty():
    """The contact's force on 'upper' equals the press's and the table's reactions (an
    offset block on a larger one). In a column of matching facets (nu = 0: uniform uniaxial
    stress), upper's bottom sits below lower's top by (force / area) / penalty everywhere:
    FEBio's penalty law t = eps g."""
    sim, _ = _pressed(penalty=2e3)
    f = sim.forces()
    assert f["contact"][2] > 1.0
    np.testing.assert_allclose(f["contact"], -np.asarray(f["press"]), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(f["table"], -np.asarray(f["press"]), rtol=1e-9, atol=1e-9)
    sim, blocks = _column(penalty=5e3)
    force = sim.forces()["contact"][2]
    bottom = sim.body_positions("upper")[blocks["upper"].points[:, 2] < 0.5 + 1e-9, 2]
    lower_top = sim.body_positions("lower")[blocks["lower"].points[:, 2] > 0.5 - 1e-9, 2]
    assert np.ptp(bottom) < 1e-9 and np.ptp(lower_top) < 1e-9
    assert lower_top[0] - bottom[0] == pytest.approx(force / 1.0 / 5e3, rel=1e-7)


def test_the_augmented_lagrangian_closes_the_gap_and_matches_one_block():
    """Augmented to a multiplier change of 1e-8, the column's force is one block's (exact
    contact) to 1e-7, where the penalty alone is 4 % softer."""
    exact = _column(single=True)[0].forces()["press"][2]
    plain = _column(penalty=2e3)[0].forces()["press"][2]
    sim, _ = _column(penalty=2e3, augmented=True)
    assert abs(plain / exact - 1) > 0.03
    assert sim.forces()["press"][2] == pytest.approx(exact, rel=1e-7)
    assert sim.system.penalty_contacts[0].augmentations > 3


@pytest.mark.parametrize(("element", "order", "kind"), [("hex20", 2, 8), ("tet", 2, 6)])
def test_quadratic_facets_hold_the_contact_of_one_quadratic_block(element, order, kind):
    """On 20-node hexahedra and 10-node tetrahedra the contact's facets are quad8 / tri6
    (FEBio's quadratic surface elements, 3 x 3 / 3 points); augmented, the column's force is
    one quadratic block's to 1e-7 and the contact's force balances the press's."""
    exact = _column(single=True, element=element, order=order)[0].forces()["press"][2]
    sim, _ = _column(penalty=2e3, augmented=True, element=element, order=order)
    pair = sim.system.penalty_contacts[0]
    assert np.all(pair.primary.facets.kind == kind) and pair.primary.facets.nodes.shape[1] == 8
    assert len(pair.passes[0].weights) == len(pair.primary.facets.kind) * (9 if kind == 8 else 3)
    assert sim.forces()["press"][2] == pytest.approx(exact, rel=1e-7)
    np.testing.assert_allclose(sim.forces()["contact"], -np.asarray(sim.forces()["press"]),
                               rtol=1e-7, atol=1e-9)  # fmt: skip


def test_newton_converges_quadratically_with_penalty_contact():
    """The last Newton iterations of a contact step converge with order about 2 (the exact
    Hessian of the gap)."""
    sim, record = _pressed(penalty=2e3, steps=2)
    norms = [n for n in record.residual_norms[-1] if n > 1e-10]
    assert len(norms) >= 3
    # the order estimate log(r_k+1 / r_k) / log(r_k / r_k-1) of the last three residuals
    a, b, c = norms[-3:]
    assert np.log(c / b) / np.log(b / a) > 1.6, norms


def test_a_tied_pair_carries_tension_as_one_block():
    """FEBio's tied contact: the column pulled up 2 % holds together; tied with a penalty,
    its force is one block's in series with the penalty's spring (1 %: the law's small
    non-linearity), augmented one block's to 1e-7 (and with a
    sliding contact instead, nothing holds the upper block: no force)."""
    exact = _column(single=True, press=0.02)[0].forces()["press"][2]
    plain = _column(penalty=2e3, press=0.02, tied=True)[0].forces()["press"][2]
    tied, _ = _column(penalty=2e3, press=0.02, tied=True, augmented=True)
    sliding = _column(penalty=2e3, press=0.02)[0].forces()["press"][2]
    # the tie is a spring of eps per area in series with the column (stiffness exact / 0.02)
    series = 0.02 / (0.02 / exact + 1.0 / 2e3)
    assert exact > 1.0 and plain == pytest.approx(series, rel=1e-2)
    assert tied.forces()["press"][2] == pytest.approx(exact, rel=1e-7)
    assert abs(sliding) < 1e-9 * exact


def test_a_pair_in_tension_holds_the_column_pulled_apart():
    """FEBio's sliding-elastic with tension = 1: the column pulled up 2 % stays together, its
    points in tension: the normal penalty in series with the column (as the plain tie, whose
    vector gap is the normal one here: the pull is along the normal), tensile tractions in
    forces(); without tension nothing holds. The pair's energy in tension: its value and
    gradient against differences are in the parametrised test above."""
    exact = _column(single=True, press=0.02)[0].forces()["press"][2]
    tied = _column(penalty=2e3, press=0.02, tied=True)[0].forces()["press"][2]
    sim, _ = _column(penalty=2e3, press=0.02, tension=True)
    pulled = sim.forces()["press"][2]
    assert exact > 1.0 and pulled == pytest.approx(tied, rel=1e-6)
    assert sim.forces()["contact"][2] == pytest.approx(-pulled, rel=1e-6)  # it pulls down
    sliding = _column(penalty=2e3, press=0.02)[0].forces()["press"][2]
    assert abs(sliding) < 1e-9 * exact
    with pytest.raises(InputError, match="tension"):
        _column(penalty=2e3, press=0.02, tension=True, friction=0.3)


def test_two_pass_and_nodal_integration_carry_the_same_load():
    """In the column (matching facets, uniform pressure): two passes at half the penalty
    carry the press as one pass does (FEBio's two passes add), and FEBio's node-on-facet points
    as the Gauss points; on the offset block the contact balances the press in each."""
    ref = _column(penalty=4e3)[0].forces()["press"][2]
    two = _column(penalty=2e3, two_pass=True)[0].forces()["press"][2]
    nodes = _column(penalty=4e3, integration="nodes")[0].forces()["press"][2]
    assert two == pytest.approx(ref, rel=1e-8)
    assert nodes == pytest.approx(ref, rel=1e-8)
    for kwargs in ({"two_pass": True}, {"integration": "nodes"}):
        sim, _ = _pressed(penalty=2e3, **kwargs)
        f = sim.forces()
        np.testing.assert_allclose(f["contact"], -np.asarray(f["press"]), rtol=1e-8, atol=1e-9)


SCENE = """
[simulation]
integrator = "quasistatic"
time_step = 1.0
[[bodies]]
name = "lower"
mesh = { generator = "box", lower = [0, 0, 0], upper = [1, 1, 0.5], divisions = [3, 3, 2], \
element = "hex" }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.0 }
fix = { tagged = "zmin" }
[[bodies]]
name = "upper"
mesh = { generator = "box", lower = [0.2, 0.15, 0.5], upper = [0.8, 0.75, 1.0], \
divisions = [2, 2, 2], element = "hex" }
material = { model = "neo_hookean", youngs_modulus = 1000.0, poisson_ratio = 0.0 }
[[graspers]]
body = "upper"
vertices = { tagged = "zmax" }
displacement = ["0", "0", "-0.01 * t"]
name = "press"
[[penalty_contact]]
name = "contact"
primary = "upper"
secondary = "lower"
primary_facets = "zmin"
secondary_facets = "zmax"
penalty = 2000.0
"""


def test_the_scene_table_runs_as_the_python_call():
    import tomllib

    scene = build_scene(tomllib.loads(SCENE))
    for _ in range(3):
        scene.simulation.step()
    sim, _ = _pressed(penalty=2e3)
    assert scene.simulation.forces()["contact"] == pytest.approx(sim.forces()["contact"])


@pytest.mark.parametrize(
    "change, message",
    [
        ("penalty = 2000.0", 'penalty = 2000.0\nintegration = "node"'),
        ("penalty = 2000.0", "pennalty = 2000.0"),
        ("penalty = 2000.0", "penalty = -1.0"),
        ('primary = "upper"', 'primary = "uper"'),
    ],
)
def test_bad_scene_tables_give_one_line(change, message):
    import tomllib

    text = SCENE.replace(change, message)
    with pytest.raises(SceneError) as info:
        build_scene(tomllib.loads(text), source="s.toml")
    said = str(info.value)
    assert "\n" not in said and "penalty_contact[1]" in said


def test_python_call_errors():
    lower, upper = _blocks()
    sim = ts.Simulation(integrator="quasistatic")
    mat = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    sim.add_body("lower", lower, mat)
    sim.add_body("upper", upper, mat)
    with pytest.raises(InputError, match="give penalty"):
        sim.add_penalty_contact("upper", "lower")
    with pytest.raises(InputError, match="integration"):
        sim.add_penalty_contact("upper", "lower", penalty=1.0, integration="node")
    with pytest.raises(InputError, match="not a FEM body"):
        sim.add_penalty_contact("upper", "nothing", penalty=1.0)


def _stick_and_pull(**options):
    """The column's upper block 0.005 above the lower, lowered 0.02 onto it, then raised
    to 0.02 above its start (quasistatic steps of 0.25 s)."""
    mat = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    sim = ts.Simulation(integrator="quasistatic", time_step=0.25)
    lower = box((0, 0, 0), (1, 1, 0.5), (2, 2, 1), element="hex")
    upper = box((0, 0, 0.505), (1, 1, 1.0), (2, 2, 3), element="hex")
    sim.add_body("lower", lower, mat)
    sim.add_body("upper", upper, mat)
    sim.fix(np.flatnonzero(lower.points[:, 2] < 1e-9), body="lower", name="table")
    top = np.flatnonzero(upper.points[:, 2] > 1 - 1e-9)

    def motion(t):
        return np.array([0.0, 0.0, -0.02 * t if t <= 1 else -0.02 + 0.04 * (t - 1)])

    sim.grasp(top, motion, body="upper", name="press")
    sides = {"primary_facets": "zmin", "secondary_facets": "zmax"}
    sim.add_penalty_contact("upper", "lower", **sides, penalty=1e5, integration="nodes",
                            name="contact", **options)  # fmt: skip
    forces = []
    for _ in range(8):
        sim.step()
        forces.append(sim.forces()["press"][2])
    return forces


def test_a_sticky_pair_holds_once_touched_and_lets_go_past_its_traction():
    """FEBio's sticky contact: the upper block, lowered onto the lower one, sticks and is
    pulled back in tension (the press pulls: force > 0) where a sliding pair lets go (0); with
    a small max_traction it lets go too."""
    sticky = _stick_and_pull(sticky=True, snap_tolerance=1e-3)
    sliding = _stick_and_pull()
    weak = _stick_and_pull(sticky=True, snap_tolerance=1e-3, max_traction=1.0)
    assert sticky[3] < -1.0 and sliding[3] == pytest.approx(sticky[3], rel=1e-3)  # pressed
    assert sticky[-1] > 1.0  # stuck, pulled: tension through the contact
    assert abs(sliding[-1]) < 1e-6 and abs(weak[-1]) < 1e-6  # vs ~10 N stuck


def test_auto_penalty_is_youngs_modulus_times_facet_area_over_element_volume():
    """FEBio's auto penalty per facet, E A / V of the element behind it: the column's upper
    block (elements 0.5 x 0.5 x 1/6) 1000 x 6, the lower (0.5 x 0.5 x 0.5) 1000 x 2; a facet
    that bounds no element is refused in one line."""
    sim, _ = _column(penalty=1.0, auto_penalty=True)
    pair = sim.system.penalty_contacts[0]
    np.testing.assert_allclose(pair.primary.scale, 6000.0, rtol=1e-12)
    np.testing.assert_allclose(pair.secondary.scale, 2000.0, rtol=1e-12)
    lower, upper = _blocks()
    bad = ts.Simulation(integrator="quasistatic")
    mat = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    bad.add_body("lower", lower, mat)
    bad.add_body("upper", upper, mat)
    bad.add_penalty_contact("upper", "lower", primary_facets=np.array([[0, 1, 5, 7]]),
                            secondary_facets="zmax", auto_penalty=True)  # fmt: skip
    with pytest.raises(InputError, match="bounds no element") as info:
        bad.step()
    assert "\n" not in str(info.value)


def test_auto_penalty_takes_each_regions_modulus():
    """The lower block made of two regions (its bottom layer E = 3000, its top layer, the one
    behind the contact facets, E = 1000): the auto penalty of its facets is 1000 x A / V, not
    the body's largest modulus."""
    lower = box((0, 0, 0), (1, 1, 0.5), (2, 2, 2), element="hex")
    upper = box((0, 0, 0.5), (1, 1, 1.0), (2, 2, 3), element="hex")
    centres = lower.points[np.asarray(lower.cells)].mean(axis=1)
    top = np.flatnonzero(centres[:, 2] > 0.25)
    soft = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)
    stiff = NeoHookean(youngs_modulus=3000.0, poisson_ratio=0.0)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    sim.add_body("lower", lower, stiff, regions={"top": (top, soft)})
    sim.add_body("upper", upper, NeoHookean(youngs_modulus=500.0, poisson_ratio=0.0))
    sim.fix(np.flatnonzero(lower.points[:, 2] < 1e-9), body="lower", name="table")
    sim.add_penalty_contact("upper", "lower", primary_facets="zmin", secondary_facets="zmax",
                            penalty=1.0, auto_penalty=True)  # fmt: skip
    sim.step()
    pair = sim.system.penalty_contacts[0]
    # lower's elements 0.5 x 0.5 x 0.25: A / V = 4; upper's 0.5 x 0.5 x 1/6: A / V = 6
    np.testing.assert_allclose(pair.secondary.scale, 1000.0 * 4, rtol=1e-12)
    np.testing.assert_allclose(pair.primary.scale, 500.0 * 6, rtol=1e-12)

"""The derivatives of a run's observations with respect to its parameters
(identification/sensitivity.py) against central differences of whole runs: a law's parameter, a
prescribed motion's scalar and a load's magnitude; P1, P2, hex8 and hex20; quasistatics and
Backward Euler; reactions and displacements. And what is refused. (Friction:
test_sensitivities_friction.py.)"""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.mesh import select

STEPS = 3


def build(p, integrator="quasistatic", element="tet", order=1, constant_load=False):
    mesh = ts.box((0, 0, 0), (1.0, 0.3, 0.3), (4, 1, 1), element=element, order=order)
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                        integrator=integrator, time_step=0.05, density=1000.0)  # fmt: skip
    sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
    tip = select.vertices_on_plane(mesh, 0, 1.0)
    sim.add_dirichlet(tip, lambda X, t: np.column_stack(
        [0 * X[:, 0], 0 * X[:, 0], np.full(len(X), -p["depth"] * t)]), name="press")  # fmt: skip
    ramp = (lambda t: 1.0) if constant_load else (lambda t: t)  # constant: Newmark's a_0 != 0
    sim.add_body_force(lambda X, t: np.tile([0.0, -p["g"] * 1000.0 * ramp(t), 0.0], (len(X), 1)))
    return sim


def central(run, params: dict, k: str, rel: float = 1e-5):
    """The central difference of whole runs ``run(params)`` in parameter k."""
    d = rel * params[k]
    return (run({**params, k: params[k] + d}) - run({**params, k: params[k] - d})) / (2 * d)


def observed(sim, mid):
    return np.concatenate(
        [sim.forces()["press"], sim.forces()["wall"], sim.body_displacement()[mid].ravel()]
    )


@pytest.mark.parametrize(
    ("integrator", "element", "order"),
    [
        ("quasistatic", "tet", 1),
        ("backward_euler", "tet", 1),
        ("quasistatic", "hex", 1),
        ("backward_euler", "tet", 2),
        ("quasistatic", "hex20", 2),
        ("newmark", "tet", 1),
        ("newmark", "hex", 1),
    ],
)
def test_sensitivities_match_central_differences_of_whole_runs(integrator, element, order):
    params = {"E": 5e4, "depth": 0.5, "g": 2.0}
    kw = {"integrator": integrator, "element": element, "order": order}
    mesh = build(params, **kw).bodies["body"].mesh
    mid = select.vertices_on_plane(mesh, 0, 0.5)[:2]
    obs = [ts.Reaction("press"), ts.Reaction("wall"), ts.Displacement(mid)]
    r = ts.sensitivities(lambda p: build(p, **kw), params, obs, STEPS)
    assert r.values.shape == (STEPS, 12) and r.jacobian.shape == (STEPS, 12, 3)

    def run(p):
        sim = build(p, **kw)
        for _ in range(STEPS):
            sim.step()
        return observed(sim, mid)

    np.testing.assert_allclose(r.values[-1], run(params), rtol=1e-12, atol=1e-12)
    for j, k in enumerate(params):
        fd = central(run, params, k)
        assert np.abs(fd).max() > 0
        # relative to the largest derivative of its kind (forces, displacements)
        for part in (slice(0, 6), slice(6, 12)):
            scale = max(np.abs(fd[part]).max(), 1e-300)
            assert np.abs(r.jacobian[-1][part, j] - fd[part]).max() <= 1e-6 * scale, (k, part)


def test_runs_it_cannot_differentiate_are_refused_in_one_line():
    with pytest.raises(InputError, match="no support or prescribed set"):
        ts.sensitivities(build, {"E": 5e4, "depth": 0.1, "g": 1.0}, [ts.Reaction("nope")], 1)
    with pytest.raises(InputError, match="'depth' is 0: give it a scale"):
        ts.sensitivities(build, {"E": 5e4, "depth": 0.0, "g": 1.0}, [ts.Reaction("press")], 1)


def test_a_parameter_at_zero_is_differenced_by_its_scale():
    """FEBio's f_diff_scale (|b| + |a|): a press depth of 0 with a scale of 0.1."""
    params = {"E": 5e4, "depth": 0.0, "g": 1.0}
    r = ts.sensitivities(build, params, [ts.Reaction("press")], 2, scales={"depth": 0.1})

    def run(p):
        sim = build(p)
        for _ in range(2):
            sim.step()
        return np.asarray(sim.forces()["press"])

    fd = (run({**params, "depth": 1e-6}) - run({**params, "depth": -1e-6})) / 2e-6
    assert np.abs(fd).max() > 0
    assert np.abs(r.jacobian[-1][:, 1] - fd).max() <= 1e-6 * np.abs(fd).max()


@pytest.mark.parametrize("element", ["tet", "hex"])
def test_a_follower_pressure_on_an_open_surface_is_differentiated(element):
    """The lagged follower load settles on the follower force, whose own (skew) stiffness
    enters the step's derivative: a block's top face pressed by p, its modulus and p."""

    def pressed(p):
        mesh = ts.box((0, 0, 0), (1.0, 0.3, 0.3), (4, 1, 1), element=element)
        sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                            integrator="quasistatic", time_step=0.5)  # fmt: skip
        sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
        sim.add_follower_pressure(mesh.facet_sets["zmax"], lambda t: p["p"] * t)
        return sim

    params = {"E": 5e4, "p": 300.0}
    mesh = pressed(params).bodies["body"].mesh
    tip = select.vertices_on_plane(mesh, 0, 1.0)
    obs = [ts.Reaction("wall"), ts.Displacement(tip)]
    r = ts.sensitivities(pressed, params, obs, 2)

    def run(q):
        sim = pressed(q)
        for _ in range(2):
            sim.step()
        return np.concatenate([sim.forces()["wall"], sim.body_displacement()[tip].ravel()])

    for j, k in enumerate(params):
        fd = central(run, params, k)
        for part in (slice(0, 3), slice(3, None)):
            scale = np.abs(fd[part]).max()
            assert np.abs(r.jacobian[-1][part, j] - fd[part]).max() <= 1e-5 * scale, (k, part)


def test_fibre_laws_are_taken():
    """(Laws with internal variables: test_sensitivities_history.py.)"""

    def fibres(p):
        mesh = ts.box((0, 0, 0), (1.0, 0.3, 0.3), (2, 1, 1), element="hex")
        law = ts.HolzapfelGasserOgden(c=5e3, k1=p["k1"], k2=5.0, gamma=30.0, k=2.5e5)
        sim = ts.Simulation(mesh, law, integrator="quasistatic", time_step=0.5)
        sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
        sim.add_dirichlet(select.vertices_on_plane(mesh, 0, 1.0), lambda X, t: np.full(
            len(X), 0.1 * t)[:, None], components=[0], name="pull")  # fmt: skip
        return sim

    r = ts.sensitivities(fibres, {"k1": 2e4}, [ts.Reaction("pull", component=0)], 2)

    def force(k1):
        sim = fibres({"k1": k1})
        for _ in range(2):
            sim.step()
        return sim.forces()["pull"][0]

    fd = (force(2e4 * (1 + 1e-5)) - force(2e4 * (1 - 1e-5))) / (2 * 2e4 * 1e-5)
    assert r.jacobian[-1][0, 0] == pytest.approx(fd, rel=1e-6)


@pytest.mark.parametrize("integrator", ["quasistatic", "backward_euler"])
def test_rest_positions_as_parameters(integrator):
    """A parameter that moves rest vertices (the bar's free end drawn longer): the press's
    reaction's derivative and a midpoint's displacement (from its moved rest position) against
    central differences of whole runs; Backward Euler's first prediction starts from the
    moved rest positions."""

    def longer(p):
        mesh = ts.box((0, 0, 0), (1.0, 0.3, 0.3), (4, 1, 1))
        end = mesh.points[:, 0] > 0.99
        mesh.points[end, 0] += p["extra"]
        mesh.points[:, 0] += p["shift"] * mesh.points[:, 0]
        sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=5e4, poisson_ratio=0.3),
                            integrator=integrator, time_step=0.5, density=1000.0)  # fmt: skip
        sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
        sim.add_dirichlet(np.flatnonzero(end), lambda X, t: np.full(len(X), -0.2 * t)[:, None],
                          components=[2], name="press")  # fmt: skip
        return sim

    mid = [3]  # a vertex at x = 0.25 (rest), moved by "shift"
    obs = [ts.Reaction("press", component=2), ts.Displacement(mid)]
    params = {"extra": 0.1, "shift": 0.05}
    r = ts.sensitivities(longer, params, obs, 2)

    def observed(q):
        sim = longer(q)
        for _ in range(2):
            sim.step()
        return np.concatenate([[sim.forces()["press"][2]], sim.body_displacement()[mid].ravel()])

    for j, k in enumerate(params):
        fd = central(observed, params, k, rel=1e-5)
        assert abs(fd[0]) > 1.0
        assert np.abs(fd[1:]).max() > 1e-3
        for part in (slice(0, 1), slice(1, None)):  # the force, the displacement
            scale = np.abs(fd[part]).max()
            assert np.abs(r.jacobian[-1][part, j] - fd[part]).max() <= 1e-6 * scale, (k, part)


def test_newmark_from_its_initial_acceleration():
    """Newmark's first step starts from M^-1 f(t_0): with a load on from t = 0 the run's
    derivative goes through the initial acceleration's (a load's magnitude, Young's modulus)."""
    params = {"E": 5e4, "depth": 0.3, "g": 2.0}
    kw = {"integrator": "newmark", "constant_load": True}
    mesh = build(params, **kw).bodies["body"].mesh
    mid = select.vertices_on_plane(mesh, 0, 0.5)[:2]
    r = ts.sensitivities(lambda p: build(p, **kw), params, [ts.Displacement(mid)], STEPS)

    def run(p):
        sim = build(p, **kw)
        for _ in range(STEPS):
            sim.step()
        return sim.body_displacement()[mid].ravel()

    for j, k in enumerate(params):
        fd = central(run, params, k)
        assert np.abs(r.jacobian[-1][:, j] - fd).max() <= 1e-6 * np.abs(fd).max(), k


def indented(p, element="tet", mode="barrier", moving=False):
    """A block pressed against a sphere by p["depth"] over the run: its table rising (the
    sphere fixed, at a height p["gap"] above the block), or with ``moving`` the sphere driven
    down into it (the table fixed). The modulus, the depth and the gap are parameters."""
    mesh = ts.box((0, 0, 0), (1.0, 1.0, 0.4), (3, 3, 2), element=element)
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                        integrator="quasistatic", time_step=0.5)  # fmt: skip
    bottom = select.vertices_on_plane(mesh, 2, 0.0)
    rise = 0.0 if moving else p["depth"]
    sim.add_dirichlet(bottom, lambda X, t: np.tile([0.0, 0.0, rise * t], (len(X), 1)),
                      name="table")  # fmt: skip
    sim.set_contact(dhat=0.01, stiffness=2e5, mode=mode)
    probe = ts.sphere((0.5, 0.5, 0.4 + 0.3 + p["gap"]), 0.3)
    if moving:
        sim.add_obstacle("probe", probe, translation=lambda t: (0.0, 0.0, -p["depth"] * t))
    else:
        sim.add_obstacle("probe", probe)
    return sim


def _contact_run(params, element, mode, moving, marker):
    sim = indented(params, element, mode, moving)
    for _ in range(2):
        sim.step()
    f = sim.forces()
    return np.concatenate([f["probe"], f["table"], sim.body_displacement()[marker].ravel()])


@pytest.mark.parametrize(("element", "mode"), [("tet", "barrier"), ("hex", "accurate")])
def test_barrier_contact_is_differentiated(element, mode):
    """A block pressed against an instrument: its force, the table's and a marker's
    displacement against central differences of whole runs, in the block's modulus, the
    press's depth and the instrument's place."""
    params = {"E": 5e4, "depth": 0.06, "gap": 0.012}
    mesh = indented(params, element).bodies["body"].mesh
    marker = np.flatnonzero(
        np.isclose(mesh.points[:, 2], 0.4) & np.isclose(mesh.points[:, 0], 1 / 3)
    )[:1]
    obs = [ts.ContactForce("probe"), ts.Reaction("table"), ts.Displacement(marker)]
    r = ts.sensitivities(lambda q: indented(q, element, mode), params, obs, 2)

    def run(q):
        return _contact_run(q, element, mode, False, marker)

    forward = run(params)  # a symmetric block's sideways forces are round-off (1e-8 N)
    np.testing.assert_allclose(r.values[-1], forward, rtol=1e-9, atol=1e-9 * abs(forward[2]))
    assert r.values[-1][2] < 0.0  # the probe presses the block down
    for j, k in enumerate(params):
        fd = central(run, params, k)
        for part in (slice(0, 3), slice(3, 6), slice(6, None)):
            scale = np.abs(fd[part]).max()
            assert scale > 0
            assert np.abs(r.jacobian[-1][part, j] - fd[part]).max() <= 1e-5 * scale, (k, part)


def test_a_moving_instrument_is_differentiated_with_its_offset_held():
    """A probe driven into the block ends each step within 0.01 dhat of its target (the
    augmented Lagrangian of contact/barrier/kinematic.py stops there): the derivative holds
    that offset, whole runs move it a little with the parameters (measured: 3e-4 of the largest
    derivative)."""
    params = {"E": 5e4, "depth": 0.06, "gap": 0.012}
    mesh = indented(params).bodies["body"].mesh
    marker = np.flatnonzero(
        np.isclose(mesh.points[:, 2], 0.4) & np.isclose(mesh.points[:, 0], 1 / 3)
    )[:1]
    obs = [ts.ContactForce("probe"), ts.Displacement(marker)]
    r = ts.sensitivities(lambda q: indented(q, moving=True), params, obs, 2)

    def run(q):
        return _contact_run(q, "tet", "barrier", True, marker)[[0, 1, 2, 6, 7, 8]]

    fd = np.column_stack([central(run, params, k) for k in params])
    for part in (slice(0, 3), slice(3, None)):  # of the largest derivative of its kind
        scale = np.abs(fd[part]).max()
        assert np.abs(r.jacobian[-1][part] - fd[part]).max() <= 2e-3 * scale, part


def test_contact_it_cannot_differentiate_is_refused_in_one_line():
    params = {"E": 5e4, "depth": 0.06, "gap": 0.012}
    with pytest.raises(InputError, match="interactive contact step is a prediction"):
        ts.sensitivities(lambda q: indented(q, mode="interactive"), params,
                         [ts.ContactForce("probe")], 1)  # fmt: skip
    with pytest.raises(InputError, match="no obstacle of that name"):
        ts.sensitivities(indented, params, [ts.ContactForce("nope")], 1)


def platen(p, free=False):
    """A block under a rigid platen glued to its top: pressed p["depth"] down and tilted by
    p["tilt"] about x over the run, or (``free``) loaded by p["load"] N down and free to sink
    and tilt (its x, y and rz held)."""
    mesh = ts.box((0, 0, 0), (1.0, 1.0, 0.4), (2, 2, 2))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3),
                        integrator="quasistatic", time_step=0.5)  # fmt: skip
    sim.fix(select.vertices_on_plane(mesh, 2, 0.0), name="table")
    top = select.vertices_on_plane(mesh, 2, 0.4)
    if free:
        sim.add_rigid_body("plate", vertices={"body": top}, fixed=("x", "y", "rz"),
                           force=lambda t: (0.0, 0.3 * p["load"] * t, -p["load"] * t))  # fmt: skip
    else:
        sim.add_rigid_body("plate", vertices={"body": top}, fixed=("x", "y", "ry", "rz"),
                           prescribed={"z": lambda t: -p["depth"] * t,
                                       "rx": lambda t: p["tilt"] * t})  # fmt: skip
    return sim


@pytest.mark.parametrize("free", [False, True])
def test_a_rigid_platen_is_differentiated(free):
    """Its force and moment (RigidForce: FEBio's fem.rigidbody('plate').Fz), the table's
    reaction and a side vertex's displacement against central differences of whole runs, in
    the block's modulus and the platen's motion (prescribed) or load (free: its own DOFs
    solved with the block's, tilted by the load's lateral part)."""
    params = {"E": 5e4, "load": 800.0} if free else {"E": 5e4, "depth": 0.05, "tilt": 0.1}
    mesh = platen(params, free).bodies["body"].mesh
    side = np.flatnonzero(np.isclose(mesh.points[:, 2], 0.2) & np.isclose(mesh.points[:, 0], 1.0))
    obs = [ts.RigidForce("plate", "Fz"), ts.RigidForce("plate", "Mx"), ts.Reaction("table"),
           ts.Displacement(side[:1])]  # fmt: skip
    r = ts.sensitivities(lambda q: platen(q, free), params, obs, 2)

    def run(q):
        sim = platen(q, free)
        for _ in range(2):
            sim.step()
        f = sim.forces()
        pieces = [[f["plate"][2]], [f["plate.moment"][0]], f["table"]]
        return np.concatenate(pieces + [sim.body_displacement()[side[:1]].ravel()])

    np.testing.assert_allclose(r.values[-1], run(params), rtol=1e-9, atol=1e-9)
    fd = np.column_stack([central(run, params, k) for k in params])
    parts = (slice(0, 1), slice(1, 2), slice(2, 5), slice(5, None))
    for part in parts[2:] if free else parts:  # a free platen's held force: the load's
        scale = np.abs(fd[part]).max()
        assert scale > 0, part
        assert np.abs(r.jacobian[-1][part] - fd[part]).max() <= 1e-6 * scale, part


def test_rigid_bodies_in_dynamic_runs_are_refused_in_one_line():
    def swinging(p):
        sim = platen(p)
        sim.integrator = "backward_euler"
        return sim

    with pytest.raises(InputError, match="rigid bodies are taken quasistatic"):
        ts.sensitivities(swinging, {"E": 5e4, "depth": 0.1, "tilt": 0.1},
                         [ts.Reaction("table")], 1)  # fmt: skip


def stacked(p):
    """A block pressed by its top, p["depth"] over the run, onto a fixed one below it (two FEM
    bodies in frictionless barrier contact); the upper block's modulus is E."""
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    law = ts.NeoHookean(youngs_modulus=5e4, poisson_ratio=0.3)
    sim.add_body("low", ts.box((0, 0, 0), (1, 1, 0.3), (3, 3, 1)), law)
    top = ts.box((0.23, 0.19, 0.305), (0.77, 0.81, 0.605), (2, 2, 1))
    sim.add_body("high", top, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3))
    sim.fix("low", select.vertices_on_plane(sim.bodies["low"].mesh, 2, 0.0), name="table")
    lid = select.vertices_on_plane(sim.bodies["high"].mesh, 2, 0.605)
    sim.add_dirichlet(lid, lambda X, t: np.tile([0.0, 0.0, -p["depth"] * t], (len(X), 1)),
                      body="high", name="press")  # fmt: skip
    sim.set_contact(dhat=0.01, stiffness=2e5, mode="barrier")
    return sim


def pressed_pair_matches_whole_runs(build, params: dict, body: str, marker, tol: float):
    """The press's and table's reactions and a marker's displacement on ``body`` after two
    steps of ``build(params)``: their sensitivities against central differences of whole
    runs, within ``tol`` of the largest derivative of each kind."""
    obs = [ts.Reaction("press"), ts.Reaction("table"), ts.Displacement(marker, body)]
    r = ts.sensitivities(build, params, obs, 2)

    def run(q):
        sim = build(q)
        for _ in range(2):
            sim.step()
        f = sim.forces()
        u = sim.body_displacement(body)[marker].ravel()
        return np.concatenate([f["press"], f["table"], u])

    fd = np.column_stack([central(run, params, k) for k in params])
    for part in (slice(0, 3), slice(3, 6), slice(6, None)):  # of the largest of its kind
        scale = np.abs(fd[part]).max()
        assert scale > 0
        assert np.abs(r.jacobian[-1][part] - fd[part]).max() <= tol * scale, part


def test_two_bodies_in_barrier_contact_are_differentiated():
    params = {"E": 3e4, "depth": 0.03}
    low = stacked(params).bodies["low"].mesh
    marker = np.flatnonzero(np.isclose(low.points[:, 2], 0.3))[4:5]
    pressed_pair_matches_whole_runs(stacked, params, "low", marker, 1e-5)


def test_the_parameter_copies_share_the_base_models_sparsity_analysis():
    from tissuesim.sweep import cache

    cache.install()
    cache.clear()
    params = {"E": 2e4, "depth": 0.05, "g": 9.81}
    ts.sensitivities(build, params, [ts.Reaction("press", component=2)], steps=1)
    counts = cache.pattern_stats()
    assert counts["misses"] == 1 and counts["hits"] == 2 * len(params)  # the 6 copies'
    assert cache.stats()["hits"] == 2 * len(params)  # and the generated mesh
    cache.clear()


def penalty_pressed(p, **options):
    """Hexahedral blocks, the upper one pressed p["depth"] over the run onto the lower one (base
    fixed) through FEBio's penalty contact (upper's bottom quads on lower's top), its
    penalty p["penalty"]."""
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    lower = ts.box((0, 0, 0), (1, 1, 0.5), (3, 3, 2), element="hex")
    upper = ts.box((0.2, 0.15, 0.5), (0.8, 0.75, 1.0), (2, 2, 2), element="hex")
    sim.add_body("lower", lower, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3))
    sim.add_body("upper", upper, ts.NeoHookean(youngs_modulus=1500.0, poisson_ratio=0.2))
    sim.fix(np.flatnonzero(lower.points[:, 2] < 1e-9), body="lower", name="table")
    top = np.flatnonzero(upper.points[:, 2] > 1 - 1e-9)
    sim.add_dirichlet(top, lambda X, t: np.tile([0.0, 0.0, -p["depth"] * t], (len(X), 1)),
                      body="upper", name="press")  # fmt: skip
    sim.add_penalty_contact("upper", "lower", primary_facets="zmin", secondary_facets="zmax",
                            penalty=p["penalty"], name="contact", **options)  # fmt: skip
    return sim


@pytest.mark.parametrize("area", ["reference", "current"])
def test_penalty_contact_is_differentiated(area):
    """FEBio's penalty contact (no augmentation, no friction) is an energy of the state (its
    gradient and Hessian exact: tests/contact/test_penalty_contact.py): its Hessian joins the
    step's; with current-area weights (FEBio's sliding-elastic, lagged to the converged state)
    their own derivative joins too (area_coupling.py). The press's and table's reactions and a
    marker on the lower block follow the lower block's modulus, the depth and the penalty
    itself as whole runs do (central differences, 1e-6; measured 4e-9 with current areas, and
    9e-4 with the weights held instead)."""
    params = {"E": 1000.0, "depth": 0.02, "penalty": 2e4}
    build = lambda q: penalty_pressed(q, area=area)  # noqa: E731
    lower = build(params).bodies["lower"].mesh
    marker = np.flatnonzero(np.isclose(lower.points[:, 2], 0.5))[5:6]
    pressed_pair_matches_whole_runs(build, params, "lower", marker, 1e-6)


def test_penalty_contact_with_lagged_terms_is_refused_in_one_line():
    params = {"E": 1000.0, "depth": 0.02, "penalty": 2e4}
    for options, what in (({"augmented": True}, "augmented"), ({"friction": 0.3}, "friction")):
        with pytest.raises(InputError, match=f"penalty contact 'contact' is {what}: its lagged"):
            ts.sensitivities(lambda q, o=options: penalty_pressed(q, **o), params,
                             [ts.Reaction("press")], 1)  # fmt: skip


def walled(p):
    """A block pressed p["depth"] down onto a rigid wall (FEBio's rigid wall: a penalty on
    its bottom facets' vertices below the plane z = 0), its modulus E."""
    mesh = ts.box((0, 0, 0.001), (0.5, 0.5, 0.301), (2, 2, 2), element="hex")
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    sim.add_body("block", mesh, ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3))
    top = select.vertices_on_plane(mesh, 2, 0.301)
    sim.add_dirichlet(top, lambda X, t: np.tile([0.0, 0.0, -p["depth"] * t], (len(X), 1)),
                      name="press")  # fmt: skip
    sim.add_dirichlet(select.vertices_on_plane(mesh, 0, 0.0), components=[0], name="side")
    sim.add_dirichlet(select.vertices_on_plane(mesh, 1, 0.0), components=[1], name="table")
    sim.add_rigid_wall("block", [0.0, 0.0, 1.0, 0.0], penalty=p["penalty"], name="wall")
    return sim


def test_a_rigid_wall_is_differentiated():
    """FEBio's rigid wall (a penalty pair of the system's with fixed nodal areas): a block
    pressed onto it follows its modulus, the depth and the wall's penalty as whole runs do."""
    params = {"E": 1000.0, "depth": 0.02, "penalty": 5e5}
    mesh = walled(params).bodies["block"].mesh
    marker = select.vertices_on_plane(mesh, 2, 0.001)[:1]
    pressed_pair_matches_whole_runs(walled, params, "block", marker, 1e-6)

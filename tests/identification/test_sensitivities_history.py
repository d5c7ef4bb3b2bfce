"""Derivatives through laws with internal variables (identification/history.py): a bar pulled
and held (the force relaxes), its law a Prony series on Neo-Hookean, FEBio's reactive
viscoelasticity, or elastic damage; quasistatic and Backward Euler; the law's own parameters
(relaxation time and weight, modulus), the pull's depth; every step's reaction, a marker's
displacement and an element's stress, against central differences of whole runs."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.identification.observations import ElementData
from tissuesim.materials.reactive.damage import ElasticDamage
from tissuesim.materials.reactive.reactive_viscoelastic import ReactiveViscoelastic
from tissuesim.mesh import select

STEPS = 4


def law(kind: str, p: dict):
    elastic = ts.NeoHookean(youngs_modulus=p["E"], poisson_ratio=0.3)
    if kind == "prony":
        return ts.Viscoelastic(elastic, g=[p["g"]], tau=[p["tau"]])
    if kind in ("reactive", "recruited"):
        relaxation = {"model": "exponential", "tau": p["tau"]}
        bond = ts.NeoHookean(youngs_modulus=p["g"] * p["E"], poisson_ratio=0.3)
        recruitment = None
        if kind == "recruited":  # brf rises steeply with the strain a generation forms at
            recruitment = {"model": "power", "mu0": 1.0, "mu1": p["m"], "alpha": 1.0}
        return ReactiveViscoelastic(elastic, bond=bond, relaxation=relaxation,
                                    recruitment=recruitment)  # fmt: skip
    damage = {"model": "weibull", "alpha": 2.0, "mu": p["tau"] * 1e4}
    return ElasticDamage(elastic, damage=damage, criterion="von_mises_stress")


def pulled(p, kind="prony", integrator="quasistatic", regions=False, damping=None):
    """A bar pulled by p["depth"] over the first two steps, then held two (damage: pulled
    over all four); with ``regions`` its far half has the history law, its near half stays
    Neo-Hookean."""
    mesh = ts.box((0, 0, 0), (1.0, 0.3, 0.3), (4, 1, 1))
    tissue = law(kind, p)
    sim = ts.Simulation(integrator=integrator, time_step=0.25, density=1000.0)
    if regions:
        far = np.flatnonzero(mesh.points[mesh.cells].mean(axis=1)[:, 0] > 0.5)
        near = np.setdiff1d(np.arange(mesh.n_cells), far)
        elastic = ts.NeoHookean(youngs_modulus=4e4, poisson_ratio=0.3)
        sim.add_body("body", mesh, elastic, regions={"near": (near, elastic), "far": (far, tissue)})
    else:
        sim.add_body("body", mesh, tissue)
    sim.fix(select.vertices_on_plane(mesh, 0, 0.0), name="wall")
    end = select.vertices_on_plane(mesh, 0, 1.0)
    ramp = 1.0 if kind == "damage" else 0.5
    sim.add_dirichlet(end, lambda X, t: np.full(len(X), p["depth"] * min(t, ramp) / ramp)[:, None],
                      components=[0], name="pull")  # fmt: skip
    if damping is not None:  # Rayleigh's (alpha 1/s, beta s)
        sim.set_damping(mass=damping[0], stiffness=damping[1])
    return sim


def observed(sim, marker):
    return [ts.Reaction("pull", component=0), ts.Displacement(marker, component=1),
            ElementData("sx", cells=[5])]  # fmt: skip


def whole(p, marker, **kw):
    """Every step's observations of a whole run: (steps, 3)."""
    sim = pulled(p, **kw)
    rows = []
    for _ in range(STEPS):
        sim.step()
        stress = ElementData("sx", cells=[5]).values(sim, sim.state.x)
        rows.append([sim.forces()["pull"][0], sim.body_displacement()[marker[0], 1], stress[0]])
    return np.array(rows)


def check(params, **kw):
    mesh = pulled(params, **kw).bodies["body"].mesh
    marker = select.vertices_on_plane(mesh, 0, 0.5)[:1]
    r = ts.sensitivities(lambda q: pulled(q, **kw), params, observed(None, marker), STEPS)
    forward = whole(params, marker, **kw)
    np.testing.assert_allclose(r.values, forward, rtol=1e-9, atol=1e-12)
    if kw.get("kind") == "damage":  # damage grows: the force falls while the pull grows
        assert r.values[-1, 0] < r.values[-2, 0]
    else:  # the held pull relaxes
        assert r.values[-1, 0] < 0.9 * r.values[1, 0]
    fd = np.zeros_like(r.jacobian)
    for j, k in enumerate(params):
        d = 1e-5 * params[k]
        fd[:, :, j] = (whole({**params, k: params[k] + d}, marker, **kw)
                       - whole({**params, k: params[k] - d}, marker, **kw)) / (2 * d)  # fmt: skip
    theta = np.array(list(params.values()))
    for col in range(3):  # each observation over the steps and parameters, per relative change
        scaled = fd[:, col] * theta
        err = np.abs(r.jacobian[:, col] - fd[:, col]) * theta
        scale = np.abs(scaled).max()
        assert scale > 0, col
        assert err.max() <= 1e-6 * scale, (col, err.max(axis=0) / scale)


@pytest.mark.parametrize("integrator", ["quasistatic", "backward_euler"])
def test_a_prony_series_is_differentiated_through_its_history(integrator):
    check({"E": 5e4, "g": 1.5, "tau": 0.4, "depth": 0.1}, integrator=integrator)


def test_a_region_with_history_beside_an_elastic_one():
    check({"E": 5e4, "g": 1.5, "tau": 0.4, "depth": 0.1}, regions=True)


def test_reactive_viscoelasticity_is_differentiated():
    check({"E": 5e4, "g": 1.5, "tau": 0.4, "depth": 0.1}, kind="reactive")


def test_bond_recruitment_is_differentiated_at_febios_fixed_point():
    """The forming bonds' brf lagged within each step to FEBio's fixed point: the lag's
    derivative joins the step's (Model.lag_coupling), the recruitment's slope a parameter."""
    check({"E": 5e4, "g": 1.5, "tau": 0.4, "depth": 0.1, "m": 20.0}, kind="recruited")


def test_growing_damage_is_differentiated():
    check({"E": 5e4, "g": 1.0, "tau": 1.0, "depth": 0.2}, kind="damage")


@pytest.mark.parametrize("damping", [(2.0, 0.0), (0.0, 0.01), (1.0, 0.005)])
def test_rayleigh_damping_is_differentiated(damping):
    """Backward Euler with Rayleigh damping C = alpha M + beta K(x_n) (energies/damping.py)
    on the Prony bar: the damping's term joins the step's Hessian, and its dependence on the
    parameters and on the step's start x_n (C(x_n) (x - x_n) / h) is taken by the copies
    with x_n moved along its own derivative; every step's observations against whole runs to
    1e-6 (they had been refused)."""
    check({"E": 5e4, "g": 1.5, "tau": 0.4, "depth": 0.1}, integrator="backward_euler",
          damping=damping)  # fmt: skip


def test_a_relaxation_test_fits_its_prony_series():
    """Synthetic relaxation data (the bar pulled, then held; 1 % noise, seeded): the
    modulus, the relaxation weight and time recovered from the force curve alone, within 5 %
    (measured: printed by the assertion's message when it fails)."""
    truth = {"E": 5e4, "g": 1.5, "tau": 0.4, "depth": 0.1}

    def build(q):
        return pulled({**q, "depth": 0.1})

    observations = [ts.Reaction("pull", component=0)]
    steps = 12  # pulled over 2, held 10 (3 s: 7.5 tau)
    clean = ts.sensitivities(build, truth, observations, steps).values
    noise = 1 + 0.01 * np.random.default_rng(4).standard_normal(clean.shape)
    fit = ts.identify(build, {"E": 3e4, "g": 0.8, "tau": 0.8}, observations, clean * noise, steps,
                      bounds={"E": (1e3, 1e6), "g": (0.05, 20.0), "tau": (0.01, 10.0)})  # fmt: skip
    for k in ("E", "g", "tau"):
        assert fit.parameters[k] == pytest.approx(truth[k], rel=0.05), (k, fit.parameters)
    assert fit.runs <= 15

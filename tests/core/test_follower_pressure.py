"""A follower pressure on a closed surface (energies/pressure.py): its energy, gradient and
Hessian against finite differences, a cube squeezed from all sides against the closed form of
the neo-Hookean law under a Cauchy (follower) pressure, which surfaces take the energy and which
the lag (tests/core/test_follower_pressure_open.py), and the facets refused."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import tissuesim as ts
from tissuesim.energies.accumulator import Accumulator
from tissuesim.energies.pressure import FollowerPressure
from tissuesim.errors import InputError
from tissuesim.mesh import select
from tissuesim.model import Model


def test_energy_gradient_and_hessian_match_finite_differences():
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.5, 0.5), (2, 1, 1))
    model = Model(mesh, ts.make_material("neo_hookean", youngs_modulus=1.0, poisson_ratio=0.3),
                  np.ones(mesh.n_cells), backend="numpy")  # fmt: skip
    load = FollowerPressure(select.all_boundary_facets(mesh), lambda t: 7.0)
    energy = load.energy(0.0)
    rng = np.random.default_rng(3)
    x = mesh.points.ravel() + 0.05 * rng.standard_normal(mesh.points.size)

    def evaluate(y, order):
        acc = Accumulator(model.pattern, order)
        energy.accumulate(y, acc)
        return acc

    acc = evaluate(x, 2)
    at_rest = evaluate(mesh.points.ravel(), 0)
    assert at_rest.value == pytest.approx(7.0 * 0.25, rel=1e-12)  # p V exactly at rest
    H = model.pattern.matrix(acc.hessian).toarray()
    assert np.allclose(H, H.T, atol=1e-12)
    dx = rng.standard_normal(x.size)
    h = 1e-6
    hi, lo = evaluate(x + h * dx, 1), evaluate(x - h * dx, 1)
    assert (hi.value - lo.value) / (2 * h) == pytest.approx(acc.gradient @ dx, rel=1e-7)
    np.testing.assert_allclose((hi.gradient - lo.gradient) / (2 * h), H @ dx, atol=1e-7)


def squeezed_cube(p: float) -> float:
    """The mean volume ratio J of a unit cube under follower pressure p from all sides,
    ramped over 4 quasistatic steps (supports that only stop rigid motion)."""
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, integrator="quasistatic", time_step=0.25)
    P = mesh.points
    corner = lambda x, y, z: np.flatnonzero(np.all(np.isclose(P, (x, y, z)), axis=1))  # noqa: E731
    sim.add_dirichlet(corner(0, 0, 0), None, name="o")
    sim.add_dirichlet(corner(1, 0, 0), None, (1, 2), name="a")
    sim.add_dirichlet(corner(0, 1, 0), None, (2,), name="b")
    sim.add_follower_pressure(select.all_boundary_facets(mesh), lambda t: p * t)
    for _ in range(4):
        sim.step()
    J = sim.cell_fields()["J"]
    assert np.ptp(J) < 1e-6 * J.mean()  # homogeneous
    return float(J.mean())


def test_a_cube_squeezed_from_all_sides_takes_the_cauchy_pressure():
    """Hydrostatic F = J^(1/3) I: the neo-Hookean Cauchy stress is (mu (J^(2/3) - 1) +
    lambda ln J) / J, which a follower pressure p balances at -p. A dead pressure (the same p
    per reference area) balances J^(-1/3) of it instead, so the two differ visibly."""
    E, nu, p = 1e4, 0.3, 3e3
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    follower = brentq(lambda J: mu * (J ** (2 / 3) - 1) + lam * np.log(J) + p * J, 0.2, 1.0)
    dead = brentq(lambda J: mu * (J ** (2 / 3) - 1) + lam * np.log(J) + p * J ** (1 / 3), 0.2, 1)
    assert abs(follower - dead) > 0.01
    assert squeezed_cube(p) == pytest.approx(follower, rel=1e-6)


def test_closed_triangles_take_the_energy_other_surfaces_the_lag_and_bad_facets_are_refused():
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2))
    sim = ts.Simulation(mesh, ts.make_material("neo_hookean", youngs_modulus=1e4,
                                               poisson_ratio=0.3))  # fmt: skip
    sim.add_follower_pressure(mesh.facet_sets["zmax"], 100.0, name="top")
    sim.add_follower_pressure(select.all_boundary_facets(mesh)[:, ::-1][1:], 100.0, name="open")
    sim.add_follower_pressure(select.all_boundary_facets(mesh)[:, ::-1], 100.0)  # inward given
    top, opened, closed = sim.bodies["body"].pressures
    assert not top.closed and not opened.closed and closed.closed
    assert type(top.energy(0.0)).__name__ == "LaggedPressureEnergy"
    assert type(closed.energy(0.0)).__name__ == "PressureEnergy"
    np.testing.assert_array_equal(closed.facets, select.all_boundary_facets(mesh))  # outward
    with pytest.raises(InputError, match="not a boundary triangle"):
        sim.add_follower_pressure([[0, 1, 13]], 100.0)
    with pytest.raises(InputError, match=r"facets must be \(k, 3\)"):
        sim.add_follower_pressure(np.zeros((0, 3), dtype=int), 100.0)
    with pytest.raises(InputError, match="given twice"):
        sim.add_follower_pressure(np.repeat(mesh.facet_sets["zmax"][:1], 2, axis=0), 100.0)
    hexes = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (2, 2, 2), element="hex")
    on_hexes = ts.Simulation(hexes, ts.make_material("neo_hookean", youngs_modulus=1e4,
                                                     poisson_ratio=0.3))  # fmt: skip
    on_hexes.add_follower_pressure(select.all_boundary_facets(hexes), 100.0)  # closed: lagged
    assert not on_hexes.bodies["body"].pressures[0].closed
    with pytest.raises(InputError, match=r"facets must be \(k, 4\)"):
        on_hexes.add_follower_pressure(mesh.facet_sets["zmax"], 100.0)
    quadratic = ts.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (1, 1, 1), element="hex27")
    with pytest.raises(InputError, match="hexahedron27 cells"):  # hexahedron20's: quad8 faces
        ts.Simulation(quadratic, ts.make_material("neo_hookean", youngs_modulus=1e4,
                      poisson_ratio=0.3)).add_follower_pressure([[0, 1, 2]], 1.0)  # fmt: skip
    from tissuesim.mesh.cutting.virtual_nodes import PlanarCut

    plane = np.array([[0.5, -1, -1], [0.5, 2, -1], [0.5, 2, 2], [0.5, -1, 2]], dtype=float)
    with pytest.raises(InputError, match="follower pressure"):
        sim.cut_body(PlanarCut(np.array([0.5, 0, 0]), np.array([1.0, 0, 0]), plane))


def test_a_scene_takes_a_pressure_table_and_names_its_errors():
    from tissuesim.errors import SceneError
    from tissuesim.scene.loader import build_scene

    scene = {
        "mesh": {"generator": "box", "lower": [0, 0, 0], "upper": [1, 1, 1],
                 "divisions": [2, 2, 2]},
        "material": {"model": "neo_hookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3},
        "simulation": {"integrator": "quasistatic", "time_step": 0.25},
        "dirichlet": [{"vertices": {"where": "x + y + z < 1e-9"}},
                      {"vertices": {"where": "abs(x - 1) + y + z < 1e-9"},
                       "components": [1, 2]},
                      {"vertices": {"where": "x + abs(y - 1) + z < 1e-9"},
                       "components": [2]}],
        "pressure": [{"facets": {"boundary": True}, "pressure": "3000 * t"}],
    }  # fmt: skip
    sim = build_scene(scene).simulation
    for _ in range(4):
        sim.step()
    assert np.mean(sim.cell_fields()["J"]) == pytest.approx(squeezed_cube(3e3), rel=1e-9)
    with pytest.raises(SceneError, match=r"pressure\]?\[?1?.*depends on t only"):
        build_scene({**scene, "pressure": [{"facets": {"boundary": True}, "pressure": "x"}]})
    # an open surface is lagged: a block on rollers pressed through its top face alone ends at
    # the uniaxial closed form (test_follower_pressure_open.py: s = 0.8094864, a = 1.0637637)
    rollers = [{"vertices": {"where": f"{axis} < 1e-9"}, "components": [k]}
               for k, axis in enumerate("xyz")]  # fmt: skip
    top = {"facets": {"where": "z > 0.999"}, "pressure": "4000 * t", "name": "top"}
    sim = build_scene({**scene, "dirichlet": rollers, "pressure": [top]}).simulation
    for _ in range(2):  # to t = 0.5: p = 2000 Pa
        sim.step()
    P = sim.mesh.points
    np.testing.assert_allclose(sim.state.x.reshape(-1, 3), P * [1.0637637, 1.0637637, 0.8094864],
                               atol=1e-7)  # fmt: skip

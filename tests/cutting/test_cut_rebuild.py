"""A cut body's rebuild reuses what its model had (``FemBody.apply_cut``): the copies keep
their parent cells' shape gradients and rest volumes, the sparsity pattern is renewed only in
the rows the cut touched (``assembly/pattern_renewal.py``), the mass matrix is summed node pair
by node pair, the facet sets come from the copies of their facets. Each must be exactly what
building the cut model afresh gives."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.energies.mass import MassMatrix
from tissuesim.kinematics.p1 import shape_gradients
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut
from tissuesim.mesh.queries.boundary import boundary_facets, match_facets

NO_EXTRA = (np.zeros(0, np.int64), np.zeros(0, np.int64))  # forces the generic pattern


def plane_x(x0: float) -> PlanarCut:
    return PlanarCut(
        np.array([x0, 0.0, 0.0]),
        np.array([1.0, 0.0, 0.0]),
        np.array([[x0, -1, -1], [x0, 1, -1], [x0, 1, 1], [x0, -1, 1]], dtype=float),
    )


def down(x0: float, z: float) -> PlanarCut:
    """A blade at x = x0 swept down from above the beam to height z."""
    return PlanarCut.swept_segment((x0, -1.0, 1.0), (x0, 2.0, 1.0), (x0, -1.0, z), (x0, 2.0, z))


def assert_rebuilt_exactly(sim: ts.Simulation, name: str = "body") -> None:
    model = sim.bodies[name].model
    k, mesh = model.kinematics, model.mesh
    fresh = SparsityPattern.from_stencils(k.n_dofs, [k.cell_stencil])
    p = model.pattern
    for field in ("indptr", "indices", "diagonal"):
        a, b = getattr(p, field), getattr(fresh, field)
        assert a.dtype == b.dtype and np.array_equal(a, b), field
    assert p.scatters[0].dtype == fresh.scatters[0].dtype
    assert np.array_equal(p.scatters[0], fresh.scatters[0])
    for field in ("vptr", "count", "cols"):
        assert np.array_equal(getattr(p.blocks, field), getattr(fresh.blocks, field)), field
    assert np.array_equal(p.blocks.scatters[0], fresh.blocks.scatters[0])
    grads, volume = shape_gradients(mesh.points, mesh.cells)
    assert np.array_equal(k.grads, grads)
    fraction = 1.0 if mesh.cell_fractions is None else mesh.cell_fractions
    assert np.array_equal(k.weights, volume * fraction)
    state = sim.bodies[name].cut_state
    if state is not None and state.vn is not None:  # facet sets: the copies' boundary facets
        facets = boundary_facets(mesh.cells)
        origin = state.vn.origin[facets]
        for key, ids in state.original.facet_sets.items():
            expected = facets[match_facets(np.asarray(ids), origin) >= 0]
            assert np.array_equal(mesh.facet_sets[key], expected), key
    generic = SparsityPattern.from_stencils(k.n_dofs, [k.cell_stencil], NO_EXTRA)
    mass = MassMatrix.build(k, model.density, generic, model.mass_kind)
    assert np.array_equal(model.mass.data, mass.data)
    assert np.array_equal(model.mass.lumped, mass.lumped)


def beam(mass: str = "consistent") -> ts.Simulation:
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.2, 0.2), (10, 2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e6, poisson_ratio=0.3)
    sim = ts.Simulation(
        mesh, material, density=1000.0, integrator="backward_euler", time_step=0.01,
        gravity=(0.0, 0.0, -9.81), mass=mass,
    )  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9), name="wall")
    return sim


@pytest.fixture
def renewed(monkeypatch) -> list:
    """How many patterns were renewed rather than built afresh."""
    import tissuesim.model

    done = []
    renew = tissuesim.model.renew_pattern

    def counted(*args):
        pattern = renew(*args)
        done.append(pattern is not None)
        return pattern

    monkeypatch.setattr(tissuesim.model, "renew_pattern", counted)
    return done


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_a_blade_going_on_and_a_second_cut_rebuild_exactly(mass, renewed):
    sim = beam(mass)
    sim.step()
    for z in (0.14, 0.07, -0.01):  # a blade going down: cells cut earlier keep their copies
        sim.cut_body(down(0.27, z), name="blade")
        assert_rebuilt_exactly(sim)
        sim.step()
    sim.cut_body(down(0.73, -1.0), name="second")
    assert_rebuilt_exactly(sim)
    assert len(renewed) >= 3 and all(renewed)  # each cut that changed the mesh


def test_a_cut_along_faces_and_one_through_cells_rebuild_exactly(renewed):
    sim = beam()
    sim.cut_body(down(0.5, -1.0), name="faces")  # along a layer of faces: nodes parted only
    assert_rebuilt_exactly(sim)
    sim.cut_body(down(0.73, -1.0), name="second")
    assert_rebuilt_exactly(sim)
    assert len(renewed) == 2 and all(renewed)


def test_an_organ_cut_twice_rebuilds_exactly():
    mesh = ts.ellipsoid((0.0, 0.0, 0.03), (0.06, 0.04, 0.03), 6)
    material = ts.make_material("neo_hookean", youngs_modulus=5e3, poisson_ratio=0.45)
    sim = ts.Simulation(integrator="backward_euler", time_step=1 / 30, gravity=(0, 0, -9.81))
    sim.add_body("organ", mesh, material, density=1000.0)
    sim.fix(np.flatnonzero(mesh.points[:, 2] < 0.004), body="organ", name="support")
    sim.step()
    sim.cut_body(plane_x(0.011), body="organ")
    assert_rebuilt_exactly(sim, "organ")
    sim.step()
    sim.cut_body(plane_x(-0.021), body="organ", name="second")
    assert_rebuilt_exactly(sim, "organ")


def test_a_strip_cut_in_2d_rebuilds_exactly():
    mesh = ts.rectangle((0.0, 0.0), (1.0, 0.4), (10, 4))
    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="backward_euler",
                        time_step=0.01, gravity=(0.0, -9.81))  # fmt: skip
    sim.fix(np.flatnonzero(mesh.points[:, 0] < 1e-9), name="wall")
    sim.step()
    sim.cut_body(plane_x(0.47))
    assert_rebuilt_exactly(sim)

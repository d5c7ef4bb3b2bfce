"""FEBio's rigid wall (contact/penalty/rigid_wall.py): its energy's gradient and Hessian
against central differences, FEBio's nodal areas, a block pressed onto the wall (penetration =
pressure / penalty, the forces in balance), the plane moved by its offset, the augmented
Lagrangian closing the gap, the scene table and its errors."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.penalty.faces import Facets
from tissuesim.contact.penalty.rigid_wall import RigidWall, node_areas
from tissuesim.errors import InputError, SceneError
from tissuesim.materials import NeoHookean
from tissuesim.mesh import box
from tissuesim.scene.loader import build_scene

RNG = np.random.default_rng(3)
MAT = NeoHookean(youngs_modulus=1000.0, poisson_ratio=0.0)


@pytest.mark.parametrize("augmented", [False, True, "penalty at 0"])
def test_energy_gradient_and_hessian_match_finite_differences(augmented):
    """Twelve nodes about a tilted, moved plane (some behind it, some not), with multipliers
    (augmented) or without, or with multipliers and a penalty curve at 0 (the multipliers'
    force alone): the gradient against central differences of the energy, the Hessian
    against central differences of the gradient (the nodes 3 DOFs each, shuffled)."""
    k = 12
    x = RNG.standard_normal((k, 3))
    normal = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    wall = RigidWall("w", 0, np.arange(k), RNG.uniform(0.1, 1.0, k), normal, 0.2, 50.0,
                     offset=lambda t: 0.1 * t, clock=lambda: 2.0)  # fmt: skip
    if augmented:
        wall.multipliers = RNG.uniform(0.0, 20.0, k)
    t = wall.multipliers + wall.penalty * wall.gaps(x)
    assert (t > 0).sum() >= 3 and (t < 0).sum() >= 3 and np.abs(t).min() > 1e-3  # off kinks
    if augmented == "penalty at 0":
        wall.multipliers[::2] = 0.0
        wall.scale = lambda t: 0.0
    dofs = RNG.permutation(3 * k).reshape(k, 3)
    n = 3 * k

    def at(y, order):
        return wall.evaluate([y[dofs]], [dofs], n, order)

    y = np.zeros(n)
    y[dofs.ravel()] = x.ravel()
    value, grad, hess = at(y, 2)
    e, fd, fh = 1e-6, np.zeros(n), np.zeros((n, n))
    for i in range(n):
        d = np.zeros(n)
        d[i] = e
        fd[i] = (at(y + d, 0)[0] - at(y - d, 0)[0]) / (2 * e)
        fh[:, i] = (at(y + d, 1)[1] - at(y - d, 1)[1]) / (2 * e)
    assert value != 0 and np.abs(grad).max() > 1.0
    np.testing.assert_allclose(grad, fd, rtol=1e-7, atol=1e-7 * np.abs(grad).max())
    np.testing.assert_allclose(hess.toarray(), fh, rtol=1e-6, atol=1e-6 * max(np.abs(fh).max(), 1))


def test_node_areas_are_febios_nodal_rule():
    """A unit square as 2 x 2 quadrilaterals: corner, edge and centre nodes carry 1/16, 1/8
    and 1/4 (FE_QUAD4NI: detJ at the corner, weight 1); as triangles, a third of each
    triangle's area per corner (FE_TRI3NI); both sum to the area."""
    hexes = box((0, 0, 0), (1, 1, 1), (2, 2, 1), element="hex")
    nodes, w = node_areas(hexes.points, Facets.of(hexes.facet_sets["zmin"], "t"))
    xy = hexes.points[nodes, :2]
    inner = np.sum(np.isclose(xy, 0.5), axis=1)  # 0 corner, 1 edge, 2 centre
    np.testing.assert_allclose(w, np.array([1 / 16, 1 / 8, 1 / 4])[inner], rtol=1e-12)
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    nodes, w = node_areas(square, Facets.of(tris, "t"))
    np.testing.assert_allclose(w, [1 / 3, 1 / 6, 1 / 3, 1 / 6], rtol=1e-12)


def _block(penalty=5e3, press=-0.02, steps=1, **options):
    """A unit cube (nu = 0) on a wall at z = 0 (plane (0, 0, 2, 0): any length of normal), its
    top pressed ``press`` down in ``steps`` quasistatic steps of 1 / steps."""
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0 / steps)
    mesh = box((0, 0, 0), (1, 1, 1), (2, 2, 3), element="hex")
    sim.add_body("block", mesh, MAT)
    top = np.flatnonzero(mesh.points[:, 2] > 1 - 1e-9)
    sim.grasp(top, lambda t: np.array([0.0, 0.0, press * t]), body="block", name="press")
    sim.add_rigid_wall("block", (0, 0, 2, 0), facets="zmin", penalty=penalty, name="floor",
                       **options)  # fmt: skip
    bottom = np.flatnonzero(mesh.points[:, 2] < 1e-9)
    out = []
    for _ in range(steps):
        sim.step()
        out.append((sim.forces()["floor"][2], sim.body_positions("block")[bottom, 2]))
    return sim, out


def test_a_pressed_block_sinks_by_pressure_over_penalty():
    """The wall carries the press (balance to round-off); the bottom face sinks uniformly by
    the pressure (force / unit area) over the penalty: FEBio's t = eps g."""
    sim, [(force, z)] = _block(penalty=5e3)
    f = sim.forces()
    assert force > 5.0
    np.testing.assert_allclose(f["floor"], -np.asarray(f["press"]), rtol=1e-9, atol=1e-9)
    assert np.ptp(z) < 1e-12
    assert -z[0] == pytest.approx(force / 5e3, rel=1e-9)


def test_the_offset_moves_the_plane_along_its_normal():
    """A wall rising 0.01 t (offset, m) under a block held at the top: at each step's end
    time the bottom sits at offset(t) - force / penalty."""
    _, out = _block(penalty=4e3, press=0.0, steps=2, offset=lambda t: 0.01 * t)
    for t, (force, z) in zip((0.5, 1.0), out, strict=True):
        assert force > 1.0
        assert z[0] == pytest.approx(0.01 * t - force / 4e3, rel=1e-9)


def test_a_penalty_scale_multiplies_the_penalty_at_the_step_time():
    """penalty_scale(t) = t: at t = 0.5 and 1 the bottom sinks by force / (penalty t)."""
    _, out = _block(penalty=5e3, steps=2, penalty_scale=lambda t: t)
    for t, (force, z) in zip((0.5, 1.0), out, strict=True):
        assert force > 1.0
        assert -z[0] == pytest.approx(force / (5e3 * t), rel=1e-9)


def test_the_augmented_lagrangian_closes_the_gap():
    """Augmented to a multiplier change of 1e-9 the penetration falls from 3e-3 to under
    1e-9 of it, and the force is the block's pressed with its bottom held at z = 0."""
    _, [(plain, z_plain)] = _block(penalty=5e3)
    sim, [(force, z)] = _block(penalty=5e3, augmented=True, tolerance=1e-9, max_augmentations=60)
    assert -z_plain[0] > 3e-3
    assert np.abs(z).max() < 1e-6 * -z_plain[0]
    assert sim.system.penalty_contacts[0].augmentations > 3
    exact = ts.Simulation(integrator="quasistatic", time_step=1.0)
    mesh = box((0, 0, 0), (1, 1, 1), (2, 2, 3), element="hex")
    exact.add_body("block", mesh, MAT)
    top = np.flatnonzero(mesh.points[:, 2] > 1 - 1e-9)
    exact.grasp(top, lambda t: np.array([0.0, 0.0, -0.02 * t]), body="block", name="press")
    bottom = np.flatnonzero(mesh.points[:, 2] < 1e-9)
    exact.grasp(bottom, lambda t: np.zeros(3), body="block", name="held")  # held in x, y too
    exact.step()
    # nu = 0: the held bottom's lateral reaction is nil, the same state as the wall's
    assert force == pytest.approx(exact.forces()["held"][2], rel=1e-7)
    assert plain < force


SCENE = """
[simulation]
integrator = "quasistatic"
time_step = 0.5
[mesh]
generator = "box"
lower = [0, 0, 0]
upper = [1, 1, 1]
divisions = [2, 2, 3]
element = "hex"
[material]
model = "neo_hookean"
youngs_modulus = 1000.0
poisson_ratio = 0.0
[[graspers]]
vertices = { tagged = "zmax" }
displacement = ["0", "0", "0"]
name = "press"
[[rigid_wall]]
name = "floor"
facets = "zmin"
plane = [0, 0, 2, 0]
penalty = 4000.0
offset = "0.01 * t"
penalty_scale = "1 + t"
"""


def test_the_scene_table_runs_as_the_python_call():
    scene = build_scene(tomllib.loads(SCENE))
    for _ in range(2):
        scene.simulation.step()
    _, out = _block(penalty=4e3, press=0.0, steps=2, offset=lambda t: 0.01 * t,
                    penalty_scale=lambda t: 1 + t)  # fmt: skip
    assert scene.simulation.forces()["floor"][2] == pytest.approx(out[-1][0], rel=1e-9)


@pytest.mark.parametrize(
    "change, message",
    [
        ("penalty = 4000.0", "penalty = -1.0"),
        ("penalty = 4000.0", "penalty = 4000.0\npenalti = 1.0"),
        ("plane = [0, 0, 2, 0]", "plane = [0, 0, 1]"),
        ('offset = "0.01 * t"', 'offset = "0.01 * x"'),
        ('facets = "zmin"', 'facets = "zmin"\nbody = "nobody"'),
        ('facets = "zmin"', "facets = 3"),
        ('penalty_scale = "1 + t"', 'penalty_scale = "x"'),
        ('penalty_scale = "1 + t"', "penalty_scale = [1]"),
    ],
)
def test_bad_scene_tables_give_one_line(change, message):
    text = SCENE.replace(change, message)
    with pytest.raises(SceneError) as info:
        build_scene(tomllib.loads(text), source="s.toml")
    said = str(info.value)
    assert "\n" not in said and "rigid_wall[1]" in said


def test_python_call_errors():
    sim = ts.Simulation(integrator="quasistatic")
    sim.add_body("block", box((0, 0, 0), (1, 1, 1), (1, 1, 1), element="hex"), MAT)
    for args, kwargs, match in [
        (("block", (0, 0, 0, 1)), {"penalty": 1.0}, "normal"),
        (("block", (0, 0, 1)), {"penalty": 1.0}, "four numbers"),
        (("block", (0, 0, 1, 0)), {"penalty": 0.0}, "penalty"),
        (("block", (0, 0, 1, 0)), {"penalty": 1.0, "offset": "t"}, "offset"),
        (("block", (0, 0, 1, 0)), {"penalty": 1.0, "max_augmentations": -1}, "max_aug"),
        (("block", (0, 0, 1, 0)), {"penalty": 1.0, "penalty_scale": 2.0}, "penalty_scale"),
        (("other", (0, 0, 1, 0)), {"penalty": 1.0}, "not a FEM body"),
    ]:
        with pytest.raises(InputError, match=match):
            sim.add_rigid_wall(*args, **kwargs)

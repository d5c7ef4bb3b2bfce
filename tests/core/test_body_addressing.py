"""One way to address bodies: every per-body call takes ``body=`` (optional with one body);
the body-first form of ``fix`` and ``grasp`` is still accepted; one-body properties name the
method to use when there are several bodies."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError


def one_body():
    sim = ts.Simulation(integrator="quasistatic", gravity=(0.0, -9.81))
    mesh = ts.rectangle((0.0, 0.0), (1.0, 0.2), (10, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim.add_body("beam", mesh, material, density=100)
    return sim, mesh


def two_bodies():
    sim = ts.Simulation(integrator="quasistatic", gravity=(0.0, -9.81))
    material = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    for name, y in (("a", 0.0), ("b", 1.0)):
        sim.add_body(name, ts.rectangle((0.0, y), (1.0, y + 0.2), (10, 2)), material, density=100)
    return sim


def clamped(mesh):
    return np.flatnonzero(mesh.points[:, 0] < 1e-9)


def test_fix_with_one_body_needs_no_body_and_agrees_with_the_other_forms():
    tips = []
    for form in ("short", "keyword", "body_first"):
        sim, mesh = one_body()
        if form == "short":
            name = sim.fix(clamped(mesh), name="wall")
        elif form == "keyword":
            name = sim.fix(clamped(mesh), body="beam", name="wall")
        else:
            name = sim.fix("beam", clamped(mesh), name="wall")
        assert name == "wall"
        sim.step()
        tips.append(sim.positions[np.argmax(mesh.points[:, 0])].copy())
        assert sim.forces()["wall"][1] > 0.0  # the wall holds the beam up
    assert tips[0][1] < -1e-4  # it sagged
    np.testing.assert_array_equal(tips[0], tips[1])
    np.testing.assert_array_equal(tips[0], tips[2])


def test_grasp_takes_body_as_a_keyword_or_first():
    for form in ("keyword", "body_first"):
        sim = two_bodies()
        lower = sim.bodies["a"].mesh
        sim.fix(clamped(lower), body="a")
        top = np.flatnonzero(lower.points[:, 1] > 0.2 - 1e-9)
        top = top[lower.points[top, 0] > 0.9]
        if form == "keyword":
            sim.grasp(top, (0.0, 0.01), body="a", name="hand")
        else:
            sim.grasp("a", top, (0.0, 0.01), name="hand")
        sim.fix(clamped(sim.bodies["b"].mesh), body="b")
        sim.step()
        np.testing.assert_allclose(sim.body_displacement("a")[top], [[0.0, 0.01]] * top.size)
        assert "hand" in sim.forces()


def test_fix_with_several_bodies_and_no_body_says_which_to_name():
    sim = two_bodies()
    with pytest.raises(InputError, match=r"name one with body="):
        sim.fix(np.array([0]))
    with pytest.raises(InputError, match=r"named twice"):
        sim.fix("a", np.array([0]), body="b")
    with pytest.raises(InputError, match=r"fix\(vertices, body=\.\.\., name=\.\.\.\) takes 1"):
        sim.fix()


@pytest.mark.parametrize(
    ("prop", "method"),
    [
        ("positions", "body_positions"),
        ("displacement", "body_displacement"),
        ("velocity", "body_velocity"),
        ("mesh", "body"),
    ],
)
def test_one_body_properties_name_the_method_for_several(prop, method):
    sim = two_bodies()
    with pytest.raises(InputError, match=rf"sim\.{prop} is for .* use sim\.{method}\(body=") as e:
        getattr(sim, prop)
    assert "['a', 'b']" in str(e.value)


def test_body_displacement_and_velocity_per_body():
    sim = two_bodies()
    sim.fix(clamped(sim.bodies["a"].mesh), body="a")
    sim.fix(clamped(sim.bodies["b"].mesh), body="b")
    sim.step()
    for name in ("a", "b"):
        mesh = sim.bodies[name].mesh
        np.testing.assert_array_equal(
            sim.body_displacement(name), sim.body_positions(name) - mesh.points
        )
        assert sim.body_velocity(name).shape == mesh.points.shape
        assert sim.body_displacement(name)[:, 1].min() < -1e-4

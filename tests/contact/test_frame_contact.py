"""Contact of frame bodies (contact/geometry/surfaces.py): the embedded surface's barrier energy
through rigid and affine frame DOFs against finite differences (gradient, and the Hessian with the
rotation chart's curvature, by second differences of the energy along the retraction), and
frame bodies that fall onto a floor and onto a FEM block without ever intersecting."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts

ipctk = pytest.importorskip("ipctk")

from tissuesim.contact.obstacles import plane  # noqa: E402
from tissuesim.frames.placement import grid_frames  # noqa: E402
from tissuesim.frames.sampling import box_surface, sample_box  # noqa: E402

SOFT = ts.make_material("stvk", youngs_modulus=1e4, poisson_ratio=0.3)
BLOCK = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)


def frame_block(sim: ts.Simulation, z0: float, frame_type: str = "rigid", name: str = "cube"):
    """A 0.2 m cube of 8 frames, bottom face at z0, its box surface embedded."""
    lo, hi = np.array([0.0, 0.0, z0]), np.array([0.2, 0.2, z0 + 0.2])
    body = sim.add_frame_body(
        name,
        grid_frames(lo + 0.05, hi - 0.05, (2, 2, 2)),
        sample_box(lo, hi, 0.05),
        SOFT,
        density=500.0,
        frame_type=frame_type,
    )
    sim.embed_surface(box_surface(lo, hi, (3, 3, 3)), body=name)
    return body


def _perturbed(sim, rng, size=2e-3):
    """The system configuration moved by a random tangent step (rotations included)."""
    s = sim.system
    return s.retract(sim.state.x, size * rng.standard_normal(s.n_dofs))


@pytest.mark.parametrize("frame_type", ["rigid", "affine"])
def test_frame_contact_energy_gradient_and_hessian_match_finite_differences(frame_type):
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
    sim.add_body("base", ts.box((-0.1, -0.1, -0.2), (0.3, 0.3, 0.0), (3, 3, 2)), BLOCK)
    frame_block(sim, 0.004, frame_type)
    sim.set_contact(dhat=0.01)
    s, rng = sim.system, np.random.default_rng(7)
    c = _perturbed(sim, rng)
    value, grad, _ = s.contact.evaluate(c, 1)
    exact = s.contact.evaluate(c, 2, project=False)[2].toarray()
    assert value > 0
    frame_dofs = s.tangent_slices[1]
    assert np.abs(grad[frame_dofs]).max() > 0  # the frames feel the barrier

    def energy(dq):
        return s.contact.evaluate(s.retract(c, dq), 0)[0]

    h = 1e-6
    for _ in range(5):
        d = np.zeros(s.n_dofs)
        d[frame_dofs] = rng.standard_normal(frame_dofs.stop - frame_dofs.start)
        fd = (energy(h * d) - energy(-h * d)) / (2 * h)
        assert fd == pytest.approx(grad @ d, rel=1e-5)

    # the barrier's Hessian through the frames against differences of the gradient of
    # f(dq) = B(V(retract(c, dq))) in the fixed chart at c: grad f = (dV/d dq)^T dB/dV, with
    # dV/d dq by central differences of the (smooth) vertex positions
    contact, eps = s.contact, 1e-7

    def chart_gradient(dq):
        V = contact.vertices(s.retract(c, dq))
        col = contact._collisions(V)
        g_V = contact.barrier.gradient(col, contact.mesh, V)
        J = np.empty((g_V.size, s.n_dofs))
        for j in range(s.n_dofs):
            e = np.zeros(s.n_dofs)
            e[j] = eps
            plus = contact.vertices(s.retract(c, dq + e))
            J[:, j] = (plus - contact.vertices(s.retract(c, dq - e))).ravel() / (2 * eps)
        return J.T @ g_V

    h = 1e-6
    for _ in range(2):
        d = rng.standard_normal(s.n_dofs)
        fd = (chart_gradient(h * d) - chart_gradient(-h * d)) / (2 * h)
        assert np.linalg.norm(fd - exact @ d) <= 1e-4 * np.linalg.norm(exact @ d)


@pytest.mark.parametrize("frame_type", ["rigid", "affine"])
def test_the_frame_chain_rule_is_exact_for_a_smooth_vertex_energy(frame_type):
    """W(V) = sum_i k/2 |v_i - a|^2 + (b . v_i)^4 / 4 mapped through the surfaces' Jacobians
    and the rotation chart's curvature (``ContactModel._to_dofs``): its gradient and Hessian
    over the tangent DOFs against differences of W(V(retract(c, dq)))."""
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
    sim.add_body("base", ts.box((-0.1, -0.1, -0.2), (0.3, 0.3, 0.0), (2, 2, 1)), BLOCK)
    frame_block(sim, 0.004, frame_type)
    sim.set_contact(dhat=0.01)
    s, rng = sim.system, np.random.default_rng(11)
    contact = s.contact
    k, a, b = 3.0, np.array([0.1, -0.2, 0.3]), np.array([1.0, 2.0, -0.5])

    def W(c, order=0):
        V = contact.vertices(c)
        r, p = V - a, V @ b
        value = 0.5 * k * float(np.sum(r * r)) + 0.25 * float(np.sum(p**4))
        if order == 0:
            return value
        g = (k * r + (p**3)[:, None] * b).ravel()
        blocks = k * np.eye(3) + 3 * (p**2)[:, None, None] * np.outer(b, b)
        import scipy.sparse as sp

        H = sp.block_diag(list(blocks), format="csr")
        return value, g, H, *contact._to_dofs(c, 2, g, H, False)

    c = _perturbed(sim, rng, 0.05)
    _, g_V, H_V, grad, hess = W(c, 2)
    hess = hess.toarray()
    h = 1e-6
    for _ in range(4):
        d = rng.standard_normal(s.n_dofs)
        fd = (W(s.retract(c, h * d)) - W(s.retract(c, -h * d))) / (2 * h)
        assert fd == pytest.approx(grad @ d, rel=1e-7)

    def second(d, e, h):
        plus, minus = d + e, d - e
        return (
            W(s.retract(c, h * plus))
            - W(s.retract(c, h * (d - e)))
            - W(s.retract(c, -h * minus))
            + W(s.retract(c, -h * plus))
        ) / (4 * h * h)

    for _ in range(4):
        d, e = rng.standard_normal((2, s.n_dofs))
        fd = (4 * second(d, e, 1e-4) - second(d, e, 2e-4)) / 3
        assert fd == pytest.approx(d @ hess @ e, rel=1e-6)
    S = contact.selection(c)
    curvature = np.abs(hess - (S.T @ H_V @ S).toarray()).max()
    if frame_type == "rigid":  # the rotation chart's curvature matters
        assert curvature > 1e-3 * np.abs(hess).max()
    else:
        assert curvature <= 1e-12 * np.abs(hess).max()


def _never_intersecting(sim, steps):
    records = []
    for _ in range(steps):
        records.append(sim.step())
        assert not sim.system.contact.intersecting(sim.state.x, sim.time), sim.time
    return records


def test_a_spinning_rigid_frame_body_lands_on_the_floor_and_weighs_its_weight():
    """Dropped 2 cm above a floor, spinning about a horizontal axis, so its corners move on
    arcs: no step intersects, it comes to rest on the floor, which then carries its weight."""
    sim = ts.Simulation(integrator="backward_euler", time_step=0.02, gravity=(0, 0, -9.81))
    body = frame_block(sim, 0.02)
    sim.set_velocity(angular=(1.5, 0.0, 0.0), body="cube")
    sim.add_obstacle("floor", plane((0.1, 0.1, 0.0), (0, 0, 1), 2.0))
    sim.set_contact(dhat=2e-3)
    records = _never_intersecting(sim, 60)
    assert all(r.converged for r in records)
    weight = float(body.model.masses.sum()) * 9.81
    force = np.asarray(records[-1].extra["forces"]["floor"])
    assert force[2] == pytest.approx(weight, rel=0.03)
    points = sim.embedded_positions(body="cube")  # at rest on the floor, above it
    assert 0 < points[:, 2].min() < 2e-3


def test_a_frame_body_dropped_fast_on_a_fem_block_never_passes_into_it():
    """3 m/s down, 0.01 s steps: 3 cm per step against a 4 mm gap and a 1 mm barrier."""
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
    base = sim.add_body(
        "base", ts.box((-0.1, -0.1, -0.2), (0.3, 0.3, 0.0), (3, 3, 2)), BLOCK, density=500.0
    )
    sim.fix("base", base.mesh.point_sets["zmin"])
    frame_block(sim, 0.004, "affine")
    sim.set_velocity(linear=(0.0, 0.0, -3.0), body="cube")
    sim.set_contact(dhat=1e-3)
    records = _never_intersecting(sim, 6)
    assert all(r.converged for r in records)
    cube = sim.embedded_positions(body="cube")
    top = sim.body_positions("base")[:, 2].max()
    assert cube[:, 2].min() > top - 0.05  # it did not pass into the block (0.2 m deep)
    assert cube[:, 2].min() > sim.body_positions("base")[:, 2].min()


def test_frame_body_contact_surface_errors():
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
    frame_block(sim, 0.0)
    sim.add_frame_body(
        "bare",
        grid_frames([1, 0, 0], [1.2, 0.2, 0.2], (2, 2, 2)),
        sample_box([0.9, -0.1, -0.1], [1.3, 0.3, 0.3], 0.05),
        SOFT,
    )
    sim.set_contact(surfaces={"bare": np.array([[0, 1, 2]])})
    with pytest.raises(ts.InputError, match="'bare' has no contact surface"):
        sim.step()
    sim.set_contact(surfaces={"cube": "top"})
    with pytest.raises(ts.InputError, match="frame bodies have no facet sets"):
        sim.step()
    sim.set_contact()
    assert sim.system.contact.describe()["bodies"] == ["cube"]  # 'bare' has no surface


FRAME_SCENE = """
[frames]
type = "rigid"
grid = { lower = [0.05, 0.05, 0.07], upper = [0.15, 0.15, 0.17], counts = [2, 2, 2] }

[region]
box = { lower = [0.0, 0.0, 0.02], upper = [0.2, 0.2, 0.22] }
spacing = 0.05

[material]
model = "stvk"
youngs_modulus = 1e4
poisson_ratio = 0.3

[simulation]
density = 500.0
integrator = "backward_euler"
time_step = 0.02

[gravity]
acceleration = [0.0, 0.0, -9.81]

[contact]
dhat = 2e-3

[[obstacles]]
name = "floor"
plane = { point = [0.1, 0.1, 0.0], normal = [0.0, 0.0, 1.0], size = 2.0 }
"""


def test_a_frame_scene_with_contact_lands_on_its_floor(tmp_path):
    """A [frames] scene with [contact] and [[obstacles]]: its display surface is its contact
    surface; after the drop the floor carries the body's weight (500 kg/m^3 x 8 L x g)."""
    from tissuesim.scene.loader import load_scene

    path = tmp_path / "drop.toml"
    path.write_text(FRAME_SCENE)
    scene = load_scene(path)
    sim = scene.simulation
    records = _never_intersecting(sim, 25)
    assert all(r.converged for r in records)
    assert records[-1].extra["forces"]["floor"][2] == pytest.approx(500 * 0.008 * 9.81, rel=0.02)
    assert 0 < sim.embedded_positions(body="body")[:, 2].min() < 2e-3

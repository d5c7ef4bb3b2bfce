"""Issue 41: a fine visual surface on a coarse simulation mesh (SOFA's barycentric mapping):
any triangle surface (a polyline in 2D) carried by a FEM body, written as its own series on
its rest points with ``displacement``, drawn instead of the body's coarse surface; a cut body
refuses one; bad input is one error line naming the key."""

from __future__ import annotations

import json
import textwrap

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError, SceneError
from tissuesim.scene.loader import load_scene

A = np.array([[1.05, 0.02, 0.0], [0.0, 0.97, 0.03], [0.01, 0.0, 1.02]])
B = np.array([0.001, -0.002, 0.003])


def sphere_surface(center, radius, n: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A closed UV sphere: points (k, 3) and outward triangles."""
    th = np.linspace(0, np.pi, n // 2 + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, n, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    T, P = T.ravel(), P.ravel()
    ring = np.column_stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)])
    pts = np.vstack([ring, [[0, 0, 1], [0, 0, -1]]]) * radius + center
    rows, top, bottom = len(th), len(pts) - 2, len(pts) - 1
    idx = np.arange(rows * n).reshape(rows, n)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1], nxt[:-1], nxt[1:], idx[1:]
    tris = [np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    tris += [np.column_stack([np.full(n, top), idx[0], nxt[0]])]
    tris += [np.column_stack([np.full(n, bottom), nxt[-1], idx[-1]])]
    return pts, np.concatenate(tris)


def box_sim() -> ts.Simulation:
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim.add_body("organ", ts.box((0, 0, 0), (0.1, 0.06, 0.06), (4, 3, 3)), material)
    return sim


def test_an_affine_motion_moves_the_visual_surface_exactly_and_is_written(tmp_path):
    sim = box_sim()
    X = sim.body("organ").mesh.points
    # every vertex prescribed: the body moves affinely, u(X, t) = t (A X + B - X)
    sim.add_dirichlet(np.arange(len(X)), lambda X, t: t * (X @ A.T + B - X), body="organ")
    # a sphere poking 1 mm out of the box's top face: some points outside, by < an element
    pts, tris = sphere_surface((0.05, 0.03, 0.04), 0.021)
    visual = sim.add_visual_surface((pts, tris), body="organ", name="organ_fine")
    assert visual.embedding.outside.any() and not visual.embedding.outside.all()
    sim.run(2, tmp_path / "out", progress=False, render=False)
    np.testing.assert_allclose(sim.visual_positions("organ_fine"), pts @ A.T + B, atol=1e-13)
    out = tmp_path / "out"
    manifest = json.loads((out / "manifest.json").read_text())
    assert "organ_fine" in manifest["series"]
    assert (out / "organ_fine.pvd").read_text().count("<DataSet") == 3
    last = meshio.read(out / "organ_fine_00002.vtu")
    np.testing.assert_allclose(last.points, pts, atol=1e-15)  # rest positions
    np.testing.assert_array_equal(last.cells_dict["triangle"], tris)
    np.testing.assert_allclose(last.point_data["displacement"], pts @ A.T + B - pts, atol=1e-13)
    summary = json.loads((out / "summary.json").read_text())
    described = summary["simulation"]["visual_surfaces"]["organ_fine"]
    assert described["points"] == len(pts) and described["points_outside_body"] > 0


def test_a_2d_body_carries_a_polyline(tmp_path):
    sim = ts.Simulation(integrator="quasistatic", time_step=0.5)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim.add_body("strip", ts.rectangle((0, 0), (0.1, 0.02), (10, 2)), material)
    X = sim.body("strip").mesh.points
    A2, B2 = A[:2, :2], B[:2]
    sim.add_dirichlet(np.arange(len(X)), lambda X, t: t * (X @ A2.T + B2 - X))
    s = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    pts = np.column_stack([0.05 + 0.04 * np.cos(s), 0.01 + 0.0099 * np.sin(s)])
    lines = np.column_stack([np.arange(60), (np.arange(60) + 1) % 60])
    sim.add_visual_surface((pts, lines))
    sim.run(1, tmp_path / "out", progress=False, render=False)
    frame = meshio.read(tmp_path / "out" / "strip_visual_00001.vtu")
    np.testing.assert_array_equal(frame.cells_dict["line"], lines)
    np.testing.assert_allclose(frame.points[:, 2], 0.0)
    u = frame.point_data["displacement"]
    np.testing.assert_allclose(u[:, :2], sim.time * (pts @ A2.T + B2 - pts), atol=1e-13)


def test_a_surface_file_is_read_and_welded(tmp_path):
    pts, tris = sphere_surface((0.05, 0.03, 0.03), 0.02)
    soup = pts[tris].reshape(-1, 3)  # an STL stores each triangle's corners apart
    path = tmp_path / "fine.stl"
    meshio.write(path, meshio.Mesh(soup, [("triangle", np.arange(len(soup)).reshape(-1, 3))]))
    visual = box_sim().add_visual_surface(path)
    assert len(visual.points) == len(pts) and len(visual.cells) == len(tris)
    assert visual.name == "organ_visual"


def scene_text(surface: str, extra: str = "") -> str:
    return textwrap.dedent(
        f"""
        [mesh]
        generator = "box"
        lower = [0.0, 0.0, 0.0]
        upper = [0.1, 0.06, 0.06]
        divisions = [4, 3, 3]

        [material]
        model = "neo_hookean"
        youngs_modulus = 1e4
        poisson_ratio = 0.3

        [simulation]
        integrator = "quasistatic"
        time_step = 0.5
        density = 1000.0

        [[dirichlet]]
        vertices = {{ where = "x < 1e-9" }}

        [gravity]
        acceleration = [0.0, 0.0, -9.81]

        [[visual_surfaces]]
        file = "{surface}"
        {extra}
        """
    )


def write_sphere(path, scale: float = 1.0) -> None:
    pts, tris = sphere_surface((0.05, 0.03, 0.03), 0.02)
    meshio.write(path, meshio.Mesh(pts * scale, [("triangle", tris)]))


def test_a_scene_runs_end_to_end_and_draws_the_fine_surface(tmp_path, monkeypatch):
    pytest.importorskip("pyvista")
    from tissuesim.render import pyvista3d

    drawn = {}

    def png(path, frame, **kwargs):
        drawn["surfaces"] = frame.surfaces
        return None

    monkeypatch.setattr(pyvista3d, "render_frame_png", png)
    write_sphere(tmp_path / "organ_fine.stl")
    scene_path = tmp_path / "scene.toml"
    scene_path.write_text(scene_text("organ_fine.stl", 'name = "fine"'))
    scene = load_scene(scene_path)
    scene.simulation.run(1, tmp_path / "out", progress=False, field="displacement")
    frame = meshio.read(tmp_path / "out" / "fine_00001.vtu")
    assert np.linalg.norm(frame.point_data["displacement"], axis=1).max() > 1e-5  # it sags
    (layer,) = drawn["surfaces"]  # the fine surface instead of the coarse one
    assert len(layer.points) == len(frame.points)
    fine = scene.simulation.visual_positions("fine")
    np.testing.assert_allclose(layer.points, fine)
    np.testing.assert_allclose(layer.scalars, np.linalg.norm(fine - frame.points, axis=1))


@pytest.mark.parametrize(
    "surface, extra, message",
    [
        ("missing.stl", "", r"visual_surfaces\[1\] file: 'missing.stl': no such surface file"),
        ("mm.stl", "", r"visual_surfaces\[1\]: visual surface 'body_visual' .* farther outside"),
        ("organ_fine.stl", "colour = 1", r"visual_surfaces\[1\]: unknown key 'colour'"),
        ("organ_fine.stl", 'body = "liver"', r"visual_surfaces\[1\] body: 'liver' is not"),
        ("organ_fine.stl", 'name = "body"', r"visual_surfaces\[1\]: visual surface name 'body'"),
        ("organ_fine.stl", "max_outside = -1", r"visual_surfaces\[1\]: max_outside must be"),
    ],
    ids=["missing", "millimetres", "unknown-key", "no-body", "name-taken", "max-outside"],
)
def test_bad_input_is_one_line_naming_the_key(tmp_path, surface, extra, message):
    write_sphere(tmp_path / "organ_fine.stl")
    write_sphere(tmp_path / "mm.stl", scale=1000.0)  # a surface in millimetres
    path = tmp_path / "scene.toml"
    path.write_text(scene_text(surface, extra))
    with pytest.raises(SceneError, match=message) as caught:
        load_scene(path)
    assert "\n" not in str(caught.value)


def test_a_surface_far_outside_is_refused_unless_allowed():
    sim = box_sim()
    pts, tris = sphere_surface((0.05, 0.03, 0.13), 0.01)  # 6 cm above the box
    with pytest.raises(InputError, match=r"farther outside body 'organ' than one element"):
        sim.add_visual_surface((pts, tris))
    sim.add_visual_surface((pts, tris), max_outside=0.1)  # said to be fine


def test_a_cut_body_and_a_visual_surface_refuse_each_other():
    pts, tris = sphere_surface((0.05, 0.03, 0.03), 0.02)
    blade = np.array([[0.05, -0.01, 0.07], [0.05, 0.07, 0.07]])
    sim = box_sim()
    sim.add_cut(lambda t: blade - [0, 0, 0.1 * t], 0.0, 1.0, body="organ")
    with pytest.raises(InputError, match=r"body 'organ' is cut \(cut\); a visual surface"):
        sim.add_visual_surface((pts, tris))
    sim = box_sim()
    sim.add_visual_surface((pts, tris))
    with pytest.raises(InputError, match="carries the visual surface 'organ_visual'"):
        sim.add_cut(lambda t: blade - [0, 0, 0.1 * t], 0.0, 1.0, body="organ")
    with pytest.raises(InputError, match="set_tearing: body 'organ' carries"):
        sim.set_tearing(body="organ", stress=1e4)
    with pytest.raises(InputError, match="cut_body: body 'organ' carries"):
        sim.cut_body(None, body="organ")  # refused before the cut is looked at


def test_visual_surface_names_do_not_clash_with_other_series():
    pts, tris = sphere_surface((0.05, 0.03, 0.03), 0.02)
    sim = box_sim()
    sim.add_visual_surface((pts, tris), name="fine")
    with pytest.raises(InputError, match="is taken"):
        sim.add_visual_surface((pts, tris), name="fine")
    with pytest.raises(InputError, match="is taken"):
        sim.add_visual_surface((pts, tris), name="cut")
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    with pytest.raises(InputError, match="visual surface's series"):
        sim.add_body("fine", ts.box((1, 0, 0), (1.1, 0.1, 0.1), (1, 1, 1)), material)


def test_a_resumed_run_goes_on_with_the_visual_series(tmp_path):
    pts, tris = sphere_surface((0.05, 0.03, 0.03), 0.02)

    def make() -> ts.Simulation:
        sim = box_sim()
        X = sim.body("organ").mesh.points
        sim.add_dirichlet(np.arange(len(X)), lambda X, t: t * (X @ A.T + B - X), body="organ")
        sim.add_visual_surface((pts, tris))
        return sim

    make().run(2, tmp_path / "out", progress=False, render=False)
    sim = make()
    sim.run(4, tmp_path / "out", progress=False, render=False, resume=True)
    assert (tmp_path / "out" / "organ_visual.pvd").read_text().count("<DataSet") == 5
    last = meshio.read(tmp_path / "out" / "organ_visual_00004.vtu")
    u = sim.time * (pts @ A.T + B - pts)
    np.testing.assert_allclose(last.point_data["displacement"], u, atol=1e-13)

"""solid_shell (mesh/generators/shells.py): a layer of hexahedra or wedges of a given thickness
on a surface; its geometry (thickness, directors on a curved surface, where the surface lies,
layers), its sets, refusals, and the scene keys (generator = "shell", surface + thickness),
with contact on a shell's face."""

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import MeshError, SceneError
from tissuesim.mesh import describe_mesh, solid_shell
from tissuesim.mesh.generators.shells import shell_directors


def square(n: int = 4, size: float = 1.0):
    g = np.linspace(0.0, size, n + 1)
    x, y = np.meshgrid(g, g, indexing="xy")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    idx = np.arange(len(points)).reshape(n + 1, n + 1)
    quads = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1)
    return points, quads.reshape(-1, 4)


def cylinder(n: int = 12, radius: float = 1.0, length: float = 1.0, rings: int = 2):
    """An open cylinder of quads, normals pointing out."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    z = np.linspace(0, length, rings + 1)
    points = np.array([[radius * np.cos(t), radius * np.sin(t), h] for h in z for t in a])
    quads = [
        [r * n + k, r * n + (k + 1) % n, (r + 1) * n + (k + 1) % n, (r + 1) * n + k]
        for r in range(rings)
        for k in range(n)
    ]
    return points, np.array(quads)


@pytest.mark.parametrize(("reference", "top"), [("top", 0.0), ("middle", 0.05), ("bottom", 0.1)])
def test_a_flat_plate_volume_thickness_and_where_the_surface_lies(reference, top):
    points, quads = square()
    mesh = solid_shell(points, quads, 0.1, reference=reference)
    assert (mesh.cell_type, mesh.n_cells, mesh.n_points) == ("hexahedron", 16, 50)
    assert describe_mesh(mesh)["total_volume"] == pytest.approx(0.1, rel=1e-12)
    np.testing.assert_allclose(mesh.points[:25, 2], top)  # rows 0..n-1: the top face
    np.testing.assert_allclose(mesh.points[25:, 2], top - 0.1)
    np.testing.assert_allclose(mesh.points[:25, :2], points[:, :2])
    np.testing.assert_array_equal(mesh.point_sets["top"], np.arange(25))
    np.testing.assert_array_equal(mesh.point_sets["bottom"], np.arange(25, 50))
    for name, sign in (("top", 1.0), ("bottom", -1.0)):  # outward: up, down
        q = mesh.points[mesh.facet_sets[name]]
        n = np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1])
        np.testing.assert_allclose(n / np.linalg.norm(n, axis=1)[:, None], [[0, 0, sign]] * 16)


def test_layers_and_triangles_make_wedges():
    points, quads = square(2)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    mesh = solid_shell(points, tris, 0.3, layers=3, reference="top")
    assert (mesh.cell_type, mesh.n_cells, mesh.n_points) == ("wedge", 3 * 8, 4 * 9)
    assert describe_mesh(mesh)["total_volume"] == pytest.approx(0.3, rel=1e-12)
    np.testing.assert_allclose(np.unique(mesh.points[:, 2]), [-0.3, -0.2, -0.1, 0.0], atol=1e-15)
    assert sorted(mesh.cell_sets) == ["layer0", "layer1", "layer2"]
    z = mesh.points[mesh.cells[mesh.cell_sets["layer2"]], 2]
    np.testing.assert_allclose(z.min(), -0.3) and np.testing.assert_allclose(z.max(), -0.2)


def test_directors_on_a_cylinder():
    """Radial directors (the faces' normals point out): normalised to the thickness (the
    default), or FEBio's mean of the two unit corner normals, cos(pi / n) of it; a wall grown
    outwards from the surface (reference "bottom") has the volume of the polygonal annulus."""
    n, h = 12, 0.05
    points, quads = cylinder(n)
    radial = points * [1, 1, 0]
    np.testing.assert_allclose(shell_directors(points, quads, h), h * radial, atol=1e-14)
    febio = shell_directors(points, quads, h, normalize=False)
    np.testing.assert_allclose(np.linalg.norm(febio, axis=1), h * np.cos(np.pi / n), rtol=1e-12)
    np.testing.assert_allclose(febio / np.linalg.norm(febio, axis=1)[:, None], radial, atol=1e-14)
    mesh = solid_shell(points, quads, h, reference="bottom")
    r = np.linalg.norm(mesh.points[:, :2], axis=1)
    np.testing.assert_allclose(r[: len(points)], 1.0 + h)  # the top face, outside
    np.testing.assert_allclose(r[len(points) :], 1.0)
    polygon = 0.5 * n * np.sin(2 * np.pi / n)  # area of the unit n-gon
    volume = polygon * ((1 + h) ** 2 - 1) * 1.0
    assert describe_mesh(mesh)["total_volume"] == pytest.approx(volume, rel=1e-12)
    inward = solid_shell(points, quads, h, reference="top")  # FEBio's: the wall inside
    assert np.linalg.norm(inward.points[:, :2], axis=1).min() == pytest.approx(1.0 - h)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"thickness": 0.0}, "thickness must be a positive number"),
        ({"layers": 0}, "layers must be a whole number"),
        ({"reference": "mid"}, "reference 'mid'"),
        ({"faces": [[0, 1, 2, 3, 4]]}, r"\(k, 3\) triangles, \(k, 4\) quadrilaterals or \(k, 8\)"),
        ({"faces": [[0, 1, 99, 5]]}, "vertex indices"),
        ({"faces": "drop the first"}, "1 shell points belong to no face"),
        ({"faces": "repeat a corner"}, "corner of zero area"),
    ],
)
def test_refused(kwargs, match):
    points, quads = square()
    bad = quads.copy()
    bad[0, 2] = bad[0, 1]
    changed = {"drop the first": quads[1:], "repeat a corner": bad}
    if isinstance(kwargs.get("faces"), str):
        kwargs = {"faces": changed[kwargs["faces"]]}
    args = {"points": points, "faces": quads, "thickness": 0.1} | kwargs
    with pytest.raises(MeshError, match=match):
        solid_shell(**args)


def test_scene_generator_shell_and_a_surface_file_with_a_thickness(tmp_path):
    from tissuesim.scene.loader import build_scene

    points, quads = square(2, 0.1)
    material = {"model": "neo_hookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3}
    mesh = {"generator": "shell", "points": points.tolist(), "faces": quads.tolist(),
            "thickness": 0.01}  # fmt: skip
    sim = build_scene({"mesh": mesh, "material": material}, name="s").simulation
    expected = solid_shell(points, quads, 0.01)  # reference "middle", as the scene's default
    np.testing.assert_array_equal(sim.mesh.points, expected.points)
    np.testing.assert_array_equal(sim.mesh.cells, expected.cells)
    # a surface file of triangles (STL: corners stored apart, welded) with a thickness
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    meshio.write(
        tmp_path / "wall.stl",
        meshio.Mesh(points[tris].reshape(-1, 3), [("triangle", np.arange(24).reshape(-1, 3))]),
        binary=True,
    )
    scene = {"mesh": {"surface": "wall.stl", "thickness": 0.01, "layers": 2}, "material": material}
    sim = build_scene(scene, name="s", base_dir=tmp_path).simulation
    assert (sim.mesh.cell_type, sim.mesh.n_cells, sim.mesh.n_points) == ("wedge", 16, 27)
    assert describe_mesh(sim.mesh)["total_volume"] == pytest.approx(1e-4, rel=1e-6)  # float32
    for bad, match in [
        ({"generator": "shell", "points": [[0, 0, 0]], "faces": [[0]]}, "needs a thickness"),
        ({"surface": "wall.stl", "thickness": 0.01, "size": 0.1}, r"cannot be combined.*size"),
        ({"surface": "wall.stl", "thickness": "thin"}, "thickness must be a length"),
        ({"generator": "shell", "thickness": 0.01}, "needs points and faces"),
    ]:
        with pytest.raises(SceneError, match=match):
            build_scene({"mesh": bad, "material": material}, name="s", base_dir=tmp_path)


def test_a_shell_resting_on_a_plane_by_contact_on_its_bottom_face():
    """Contact on a shell's faces as on any hexahedral body: a 2 mm plate dropped on a floor
    rests on it (never through) and the floor carries its weight."""
    from tissuesim.contact.obstacles import plane

    points, quads = square(3, 0.1)
    mesh = solid_shell(points + [0, 0, 0.004], quads, 0.002, reference="top")
    mat = ts.make_material("neo_hookean", youngs_modulus=1e5, poisson_ratio=0.3)
    sim = ts.Simulation(mesh, mat, density=1000, time_step=0.02, gravity=(0, 0, -9.81))
    sim.add_obstacle("floor", plane((0.05, 0.05, 0.0), (0, 0, 1), 1.0))
    sim.set_contact(dhat=0.0005)
    for _ in range(15):
        sim.step()
    z = mesh.points[:, 2] + sim.displacement[:, 2]
    assert 0.0 < z.min() < 0.0005
    weight = 1000 * 0.1 * 0.1 * 0.002 * 9.81
    assert sim.forces()["floor"][2] == pytest.approx(weight, rel=0.3)

"""read_mesh / write_mesh round trips, malformed files, gmsh tags, describe_mesh."""

import math

import meshio
import numpy as np
import pytest

from tissuesim.errors import MeshError
from tissuesim.mesh import box, describe_mesh, read_mesh, rectangle, validate_mesh, write_mesh

GMSH41 = """$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
1 1 "left"
1 2 "right"
2 3 "domain"
$EndPhysicalNames
$Entities
0 2 1 0
1 0 0 0 0 1 0 1 1 0
2 1 0 0 1 1 0 1 2 0
1 0 0 0 1 1 0 1 3 0
$EndEntities
$Nodes
1 4 1 4
2 1 0 4
1
2
3
4
0 0 0
1 0 0
1 1 0
0 1 0
$EndNodes
$Elements
3 4 1 4
1 1 1 1
1 4 1
1 2 1 1
2 2 3
2 1 2 2
3 1 2 3
4 1 3 4
$EndElements
"""


def _same(a, b):
    assert a.dim == b.dim
    np.testing.assert_allclose(a.points, b.points)
    np.testing.assert_array_equal(a.cells, b.cells)


@pytest.mark.parametrize("name", ["m.vtu", "m.mesh", "m.msh"])
@pytest.mark.parametrize("make", [lambda: box(divisions=(2, 1, 2)), lambda: rectangle()])
def test_write_read_round_trip(tmp_path, name, make):
    mesh = make()
    write_mesh(mesh, tmp_path / name)
    back = read_mesh(tmp_path / name)
    _same(mesh, back)
    assert back.source == str(tmp_path / name)
    if name.endswith(".msh"):  # gmsh 2.2 keeps facet sets
        for k, v in mesh.facet_sets.items():
            np.testing.assert_array_equal(back.facet_sets[k], v)


@pytest.mark.parametrize("fmt", ["gmsh22", "gmsh"])
def test_read_meshio_written_gmsh(tmp_path, fmt):
    mesh = box(divisions=(1, 2, 1))
    path = tmp_path / "t.msh"
    meshio.Mesh(mesh.points, [("tetra", mesh.cells)]).write(path, file_format=fmt)
    _same(mesh, read_mesh(path))


def test_gmsh22_physical_tags_become_sets(tmp_path):
    p = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    cells = [("line", np.array([[3, 0], [1, 2]])), ("triangle", np.array([[0, 1, 2], [0, 2, 3]]))]
    m = meshio.Mesh(
        p,
        cells,
        cell_data={
            "gmsh:physical": [np.array([1, 2]), np.array([3, 3])],
            "gmsh:geometrical": [np.array([1, 2]), np.array([1, 1])],
        },
        field_data={"left": np.array([1, 1]), "domain": np.array([3, 2])},
    )
    m.write(tmp_path / "tags.msh", file_format="gmsh22")
    mesh = read_mesh(tmp_path / "tags.msh")
    assert mesh.dim == 2
    np.testing.assert_array_equal(mesh.facet_sets["left"], [[3, 0]])
    np.testing.assert_array_equal(mesh.facet_sets["tag_2"], [[1, 2]])  # unnamed tag
    np.testing.assert_array_equal(mesh.cell_sets["domain"], [0, 1])


def test_gmsh41_file_physical_names(tmp_path):
    (tmp_path / "sq.msh").write_text(GMSH41)
    mesh = read_mesh(tmp_path / "sq.msh")
    np.testing.assert_array_equal(mesh.facet_sets["left"], [[3, 0]])
    np.testing.assert_array_equal(mesh.facet_sets["right"], [[1, 2]])
    np.testing.assert_array_equal(mesh.cell_sets["domain"], [0, 1])


def test_missing_file(tmp_path):
    with pytest.raises(MeshError, match="nothere.msh: no such mesh file"):
        read_mesh(tmp_path / "nothere.msh")


def test_garbage_file(tmp_path, capsys):
    path = tmp_path / "garbage.msh"
    path.write_text("this is not a mesh\n1 2 3\n")
    with pytest.raises(MeshError, match="garbage.msh: meshio could not read"):
        read_mesh(path)  # meshio calls sys.exit here; it must not escape
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize("name", ["cut.msh", "cut.vtu"])
def test_truncated_file(tmp_path, name):
    full = tmp_path / ("full" + name[3:])
    write_mesh(box(divisions=(2, 2, 2)), full)
    data = full.read_bytes()
    (tmp_path / name).write_bytes(data[: len(data) // 2])
    with pytest.raises(MeshError, match=name):
        read_mesh(tmp_path / name)


def test_surface_mesh_rejected(tmp_path):
    p = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    tris = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    meshio.Mesh(p, [("triangle", tris)]).write(tmp_path / "surf.vtu")
    with pytest.raises(MeshError, match="surface mesh.*volume mesh \\(tetrahedra\\) is needed"):
        read_mesh(tmp_path / "surf.vtu")


def test_quadratic_triangles_read_and_mixed_orders_rejected(tmp_path):
    p = np.array([[0.0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5], [1, 1]])
    meshio.Mesh(p[:6], [("triangle6", np.arange(6)[None])]).write(tmp_path / "q.vtu")
    mesh = read_mesh(tmp_path / "q.vtu")
    assert mesh.order == 2 and mesh.cells.shape == (1, 6)
    blocks = [("triangle6", np.arange(6)[None]), ("triangle", np.array([[1, 6, 2]]))]
    meshio.Mesh(p, blocks).write(tmp_path / "mixed.vtu")
    with pytest.raises(MeshError, match="mixes triangle6 with other elements"):
        read_mesh(tmp_path / "mixed.vtu")


def test_inverted_cell_in_file_reoriented(tmp_path):
    mesh = box(divisions=(1, 1, 1))
    cells = mesh.cells.copy()
    cells[3] = cells[3][[1, 0, 2, 3]]
    meshio.Mesh(mesh.points, [("tetra", cells)]).write(tmp_path / "inv.vtu")
    with pytest.warns(UserWarning, match=r"inv.vtu: reoriented 1 .*\[3\]"):
        read_mesh(tmp_path / "inv.vtu")


def test_describe_unit_box():
    info = describe_mesh(box(divisions=(2, 2, 2)))
    assert info["dim"] == 3 and info["n_points"] == 27 and info["n_cells"] == 48
    assert info["n_boundary_facets"] == 48
    assert info["bounding_box"] == ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    assert info["total_volume"] == pytest.approx(1.0)
    assert info["measure_min"] == pytest.approx(1 / 48)
    assert info["measure_max"] == pytest.approx(1 / 48)
    assert info["edge_min"] == pytest.approx(0.5)
    assert info["edge_max"] == pytest.approx(math.sqrt(3) / 2)
    # Kuhn tetrahedron: inradius 1/(2(1+sqrt2)), circumradius sqrt3/2 (unit cube)
    assert info["quality_min"] == pytest.approx(3 / ((1 + math.sqrt(2)) * math.sqrt(3)))
    assert info["facet_sets"]["xmin"] == 8 and info["point_sets"]["zmax"] == 9


def test_describe_right_triangles():
    info = describe_mesh(rectangle(divisions=(1, 1), pattern="right"))
    # right isosceles triangle: r = (2 - sqrt2)/2 h, R = sqrt2/2 h, quality 2r/R = 2(sqrt2 - 1)
    assert info["quality_min"] == pytest.approx(2 * (math.sqrt(2) - 1))
    assert info["total_volume"] == pytest.approx(1.0)


def test_gmsh_round_trip_keeps_cell_and_point_sets(tmp_path):
    base = box(divisions=(1, 1, 2))
    mesh = validate_mesh(
        base.points,
        base.cells,
        source="b",
        point_sets={"corner": [0]},
        facet_sets={"bottom": base.facet_sets["zmin"]},
        cell_sets={"lower": np.arange(6), "upper": np.arange(6, 12)},
    )
    write_mesh(mesh, tmp_path / "sets.msh")
    back = read_mesh(tmp_path / "sets.msh")
    np.testing.assert_array_equal(back.point_sets["corner"], [0])
    np.testing.assert_array_equal(back.facet_sets["bottom"], mesh.facet_sets["bottom"])
    np.testing.assert_array_equal(back.cell_sets["upper"], np.arange(6, 12))


def test_interior_tagged_facets_dropped_with_warning(tmp_path):
    p = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    cells = [("line", np.array([[0, 2], [3, 0]])), ("triangle", np.array([[0, 1, 2], [0, 2, 3]]))]
    tags = [np.array([1, 2]), np.array([3, 3])]
    m = meshio.Mesh(p, cells, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags})
    m.write(tmp_path / "diag.msh", file_format="gmsh22")
    with pytest.warns(UserWarning, match="'tag_1': dropped 1 of 1 facets"):
        mesh = read_mesh(tmp_path / "diag.msh")
    assert "tag_1" not in mesh.facet_sets and len(mesh.facet_sets["tag_2"]) == 1


def test_mixed_elements_rejected(tmp_path):
    p = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1], [2, 0], [2, 1]])
    cells = [("triangle", np.array([[0, 1, 2], [0, 2, 3]])), ("quad", np.array([[1, 4, 5, 2]]))]
    meshio.Mesh(p, cells).write(tmp_path / "mixed.vtu")
    with pytest.raises(MeshError, match=r"mixed.vtu: mixes triangle .*\['quad'\]"):
        read_mesh(tmp_path / "mixed.vtu")


def test_a_read_in_a_worker_thread_leaves_the_process_streams_alone(tmp_path, monkeypatch):
    """sys.stdout / sys.stderr are the whole process's: a read in a worker thread (a study on
    a thread pool, a Dask worker) must not swap them, or the main thread's output (a study's
    progress lines) goes into the read's buffer."""
    import sys
    import threading

    path = tmp_path / "box.vtu"
    write_mesh(box((0, 0, 0), (1, 1, 1), (1, 1, 1)), path)
    seen = []
    real = meshio.read

    def spying_read(p, *args, **kwargs):
        seen.append((threading.current_thread() is threading.main_thread(), sys.stderr))
        return real(p, *args, **kwargs)

    monkeypatch.setattr(meshio, "read", spying_read)
    before = sys.stderr
    worker = threading.Thread(target=read_mesh, args=(path,))
    worker.start()
    worker.join()
    read_mesh(path)
    assert seen[0] == (False, before)  # the worker's read: the streams untouched
    assert seen[1][0] and seen[1][1] is not before  # the main thread's read: caught
    assert sys.stderr is before

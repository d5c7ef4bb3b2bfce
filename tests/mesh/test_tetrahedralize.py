"""mesh_surface: a triangle surface -> a checked tetrahedral Mesh; bad input and mesher failures
are one-line errors, never a silent empty or tangled mesh."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import InputError, MeshError
from tissuesim.mesh import signed_volumes, write_mesh
from tissuesim.mesh.from_surface import meshers
from tissuesim.mesh.from_surface import tetrahedralize as tet
from tissuesim.mesh.from_surface.tetrahedralize import dihedral_angles, mesh_surface, read_surface

RADII = (0.05, 0.03, 0.02)
EXACT = 4 / 3 * np.pi * np.prod(RADII)
SIZE = 0.008  # m; about 0.065 of the ellipsoid's bounding-box diagonal

needs_pytetwild = pytest.mark.skipif(
    "pytetwild" not in meshers.available_meshers(),
    reason="pytetwild (the default mesher, a dependency) is not installed: pip install pytetwild",
)


def ellipsoid_surface() -> tuple[np.ndarray, np.ndarray]:
    """The boundary triangles of the ellipsoid generator (inscribed: 1.6 % below EXACT)."""
    m = ts.ellipsoid(radii=RADII, divisions=8)
    return m.points, m.facet_sets["surface"]


@pytest.fixture
def stl(tmp_path):
    points, faces = ellipsoid_surface()
    path = tmp_path / "organ.stl"
    meshio.write_points_cells(path, points, [("triangle", faces)], binary=True)
    return path


def _check_volume_mesh(mesh: ts.Mesh, expected: float, rtol: float) -> None:
    assert mesh.dim == 3 and mesh.order == 1 and mesh.n_cells > 100
    assert (signed_volumes(mesh.points, mesh.cells) > 0).all()
    assert signed_volumes(mesh.points, mesh.cells).sum() == pytest.approx(expected, rel=rtol)
    assert len(mesh.facet_sets["surface"]) > 0 and len(mesh.point_sets["surface"]) > 0


# -- the default mesher -------------------------------------------------------------------------


@needs_pytetwild
def test_ellipsoid_stl_gives_a_valid_mesh_of_the_right_volume(stl):
    result = tet.tetrahedralize(stl, SIZE)
    mesh, report = result.mesh, result.report
    _check_volume_mesh(mesh, EXACT, 0.03)  # the STL is inscribed, 1.6 % below the ellipsoid
    assert report["mesher"] == "pytetwild" and report["n_tets"] == mesh.n_cells
    assert report["volume_ratio"] == pytest.approx(1.0, abs=0.01)  # vs the surface's volume
    assert report["min_dihedral_deg"] > 5.0 and report["radius_ratio_min"] > 0.05
    assert report["surface"] == {
        "triangles": 768,
        "closed": True,
        "boundary_edges": 0,
        "nonmanifold_edges": 0,
        "misoriented_edges": 0,
        "removed_faces": 0,
    }
    # the boundary lies on the surface: every boundary vertex is within the ellipsoid's shell
    b = mesh.points[mesh.point_sets["surface"]]
    level = np.sqrt(((b / RADII) ** 2).sum(axis=1))
    assert level.max() < 1.01 and level.min() > 0.95
    # it goes through the project's own checks and back through a file
    assert str(stl) in mesh.source and "pytetwild" in mesh.source


@needs_pytetwild
def test_size_sets_the_edge_length(stl):
    coarse = mesh_surface(stl, 0.012)
    fine = mesh_surface(stl, 0.006)
    assert fine.n_cells > 2 * coarse.n_cells
    for mesh, size in ((coarse, 0.012), (fine, 0.006)):
        edges = np.linalg.norm(
            mesh.points[mesh.cells[:, 1]] - mesh.points[mesh.cells[:, 0]], axis=1
        )
        assert 0.4 * size < np.median(edges) < 1.5 * size


@needs_pytetwild
def test_arrays_input_is_welded_and_a_hole_is_closed():
    points, faces = ellipsoid_surface()
    soup = points[faces].reshape(-1, 3)  # every triangle with its own corners, as STL stores it
    soup_faces = np.arange(len(soup)).reshape(-1, 3)
    surface = read_surface((soup, soup_faces))
    assert surface.closed and len(surface.points) == len(np.unique(faces))
    centre = points[faces].mean(axis=1)
    holed = soup_faces[centre[:, 2] < 0.9 * RADII[2]]  # a cap of triangles removed
    assert not read_surface((soup, holed)).closed
    with pytest.warns(UserWarning, match="open"):
        mesh = mesh_surface((soup, holed), SIZE)
    _check_volume_mesh(mesh, surface.volume, 0.05)


def test_dihedral_angles_of_the_regular_tetrahedron():
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    np.testing.assert_allclose(dihedral_angles(p, np.array([[0, 1, 2, 3]])), 70.528779, rtol=1e-6)
    p[3] = [0, 0, -0.999]  # nearly flat: a sliver
    assert dihedral_angles(p, np.array([[0, 1, 2, 3]])).min() < 1.0


# -- the other meshers (not in the test extra: run where installed) -----------------------------


@pytest.mark.skipif("tetgen" not in meshers.available_meshers(), reason="tetgen not installed")
def test_tetgen_meshes_a_clean_surface(stl):
    result = tet.tetrahedralize(stl, SIZE, mesher="tetgen")
    _check_volume_mesh(result.mesh, EXACT, 0.03)
    assert result.report["volume_ratio"] == pytest.approx(1.0, abs=1e-4)  # keeps the surface


@pytest.mark.skipif("gmsh" not in meshers.available_meshers(), reason="gmsh not installed")
def test_gmsh_on_a_surface_with_a_hole_is_an_error_not_an_empty_mesh():
    points, faces = ellipsoid_surface()
    centre = points[faces].mean(axis=1)
    with pytest.warns(UserWarning, match="open"), pytest.raises(MeshError, match="gmsh"):
        mesh_surface((points, faces[centre[:, 2] < 0.9 * RADII[2]]), SIZE, mesher="gmsh")


# -- mesher output is checked (a fake mesher stands for a failing one) -------------------------


def _fake(monkeypatch, output):
    monkeypatch.setattr(tet, "available_meshers", lambda: ["pytetwild"])
    monkeypatch.setattr(tet, "run_mesher", lambda name, p, f, size, source, *options: output(p, f))


def _good_output(p, f):
    m = ts.ellipsoid(radii=RADII, divisions=8)
    return m.points, m.cells


def test_zero_tetrahedra_is_an_error(monkeypatch, stl):
    _fake(monkeypatch, lambda p, f: (p, np.zeros((0, 4), dtype=np.int64)))
    with pytest.raises(MeshError, match="produced no tetrahedra") as info:
        mesh_surface(stl)
    assert str(stl) in str(info.value) and "\n" not in str(info.value)


def test_a_tangled_output_is_an_error(monkeypatch, stl):
    def tangled(p, f):
        v, t = _good_output(p, f)
        t = t.copy()
        t[:5] = t[:5][:, [0, 1, 3, 2]]  # five inverted among positive ones
        return v, t

    _fake(monkeypatch, tangled)
    with pytest.raises(MeshError, match="5 inverted"):
        mesh_surface(stl)


def test_an_output_that_lost_the_solid_is_an_error(monkeypatch, stl):
    _fake(monkeypatch, lambda p, f: (_good_output(p, f)[0], _good_output(p, f)[1][:200]))
    with pytest.raises(MeshError, match="lost most of the solid"):
        mesh_surface(stl)
    assert mesh_surface(stl, check_volume=False).n_cells == 200  # kept when asked to


def test_an_output_with_the_other_orientation_is_flipped(monkeypatch, stl):
    _fake(monkeypatch, lambda p, f: (_good_output(p, f)[0], _good_output(p, f)[1][:, [1, 0, 2, 3]]))
    mesh = mesh_surface(stl)
    assert (signed_volumes(mesh.points, mesh.cells) > 0).all()


def test_a_mesher_exception_names_the_file_and_the_alternatives(monkeypatch, stl):
    def broken(p, f, size):
        raise RuntimeError("Failed to tetrahedralize")

    monkeypatch.setitem(meshers._ADAPTERS, "tetgen", broken)
    monkeypatch.setattr(meshers, "_import", lambda name: None)
    with pytest.raises(MeshError, match="mesher 'tetgen' failed.*try mesher 'pytetwild'"):
        mesh_surface(stl, mesher="tetgen")


# -- bad input ----------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    with pytest.raises(MeshError, match="no such surface file") as info:
        mesh_surface(tmp_path / "nothing.stl")
    assert "nothing.stl" in str(info.value)


def test_a_file_that_is_not_a_surface(tmp_path):
    text = tmp_path / "notes.stl"
    text.write_text("this is not a mesh\n")
    with pytest.raises(MeshError, match="notes.stl: meshio could not read"):
        mesh_surface(text)
    volume = tmp_path / "block.vtu"
    write_mesh(ts.box(divisions=(2, 2, 2)), volume)
    with pytest.raises(MeshError, match="already a volume mesh.*read_mesh"):
        mesh_surface(volume)
    lines = tmp_path / "polyline.vtu"
    meshio.write_points_cells(lines, np.eye(3), [("line", np.array([[0, 1], [1, 2]]))])
    with pytest.raises(MeshError, match="no surface triangles"):
        mesh_surface(lines)


@pytest.mark.parametrize(
    ("size", "message"),
    [(-0.01, "size must be > 0"), ("3 mm", "size must be a number"), (1.0, "larger than the")],
)
def test_bad_size(stl, size, message):
    with pytest.raises(InputError, match=message):
        mesh_surface(stl, size)


def test_a_size_that_would_make_too_many_tetrahedra(stl):
    with pytest.raises(InputError, match="would make about .* tetrahedra"):
        mesh_surface(stl, 1e-5)


def test_bad_mesher_and_bad_surface_arrays(stl):
    with pytest.raises(InputError, match="mesher must be 'auto' or one of"):
        mesh_surface(stl, mesher="netgen")
    with pytest.raises(MeshError, match="indices below"):
        mesh_surface((np.eye(4)[:, :3], np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 9]])))
    with pytest.raises(InputError, match="file path .* or a \\(points, faces\\) pair"):
        mesh_surface(42)


def test_a_missing_mesher_says_how_to_install_it(monkeypatch, stl):
    monkeypatch.setitem(meshers._PACKAGE, "pytetwild", "tissuesim_no_such_module")
    with pytest.raises(InputError, match="install it with pip install pytetwild"):
        mesh_surface(stl, mesher="pytetwild")
    monkeypatch.setattr(tet, "available_meshers", lambda: [])
    with pytest.raises(
        InputError, match="no tetrahedral mesher is installed.*pip install pytetwild"
    ):
        mesh_surface(stl)

"""PNG and GIF rendering of small triangle and tetrahedron meshes."""

import numpy as np
import pytest
from matplotlib.colors import TwoSlopeNorm
from PIL import Image

from tissuesim.mesh.mesh import Mesh
from tissuesim.render import (
    render_animation,
    render_frame,
    render_frame_png,
    render_frame_png_3d,
    render_gif,
    render_gif_3d,
)
from tissuesim.render.plot2d import _colour_map, _subsample
from tissuesim.render.plot3d import boundary_faces

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def two_triangles() -> Mesh:
    points = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return Mesh(points, np.array([[0, 1, 2], [0, 2, 3]]))


def two_tets() -> Mesh:
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)
    return Mesh(points, np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))


def assert_real_png(path):
    assert path.read_bytes()[:8] == PNG_MAGIC
    with Image.open(path) as im:
        pixels = np.asarray(im.convert("RGB"), dtype=float)
    assert pixels.std() > 5  # not one flat colour
    coloured = np.abs(pixels[..., 0] - pixels[..., 2]) > 60  # red or blue from the colour map
    assert coloured.sum() > 100


def gif_frames(path) -> int:
    with Image.open(path) as im:
        assert im.format == "GIF"
        return im.n_frames


def no_temp_files(directory) -> bool:
    return not any(p.name.startswith(".") for p in directory.iterdir())


def test_png_2d(tmp_path):
    mesh = two_triangles()
    x = mesh.points * [1.3, 0.7] + [0.2, 0.0]
    out = render_frame_png(mesh, x, np.array([0.8, 1.2]), tmp_path / "f.png", title="squeezed")
    assert out == tmp_path / "f.png"
    assert_real_png(out)
    assert no_temp_files(tmp_path)


def test_png_3d(tmp_path):
    mesh = two_tets()
    x = mesh.points * [1.2, 1.0, 0.8]
    out = render_frame_png_3d(mesh, x, np.array([0.6, 1.5]), tmp_path / "f3.png", title="tets")
    assert_real_png(out)
    assert no_temp_files(tmp_path)


def test_dispatch_and_other_label(tmp_path):
    m2, m3 = two_triangles(), two_tets()
    assert_real_png(
        render_frame(m2, m2.points, np.array([0.0, 5.0]), tmp_path / "a.png", label="p")
    )
    assert_real_png(render_frame(m3, m3.points, np.array([0.9, 1.1]), tmp_path / "b.png"))
    frames = [(t, m3.points * (1 + t), np.full(2, 1 + t)) for t in (0.0, 0.5)]
    assert gif_frames(render_animation(m3, frames, tmp_path / "c.gif")) == 2


def test_gif_2d_frame_count_and_subsampling(tmp_path):
    mesh = two_triangles()
    frames = [
        (0.1 * k, mesh.points * (1 + 0.1 * k), np.array([1 - 0.05 * k, 1 + 0.05 * k]))
        for k in range(5)
    ]
    assert gif_frames(render_gif(mesh, frames, tmp_path / "a.gif", fps=10)) == 5
    many = frames * 3
    many = [(0.1 * k, x, v) for k, (_, x, v) in enumerate(many)]
    assert gif_frames(render_gif(mesh, many, tmp_path / "b.gif", max_frames=4)) == 4
    assert no_temp_files(tmp_path)


def test_gif_3d_frame_count(tmp_path):
    mesh = two_tets()
    frames = [(t, mesh.points + [0.0, 0.0, t], np.array([1.0, 1.0 + t])) for t in (0.0, 0.4, 0.8)]
    assert gif_frames(render_gif_3d(mesh, frames, tmp_path / "a.gif")) == 3
    assert no_temp_files(tmp_path)


def test_boundary_faces_outward_with_owner():
    mesh = two_tets()
    faces, owner = boundary_faces(mesh.cells)
    assert faces.shape == (6, 3) and sorted(owner.tolist()) == [0, 0, 0, 1, 1, 1]
    shared = {1, 2, 3}
    assert all(set(f.tolist()) != shared for f in faces)
    tri = mesh.points[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    centroid = mesh.points[mesh.cells[owner]].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", normal, tri.mean(axis=1) - centroid) > 0)


def test_colour_scales():
    _, norm = _colour_map([np.array([0.5, 1.5, 2.0])], "J", None, None)
    assert isinstance(norm, TwoSlopeNorm) and norm(1.0) == pytest.approx(0.5)
    cmap, norm = _colour_map([np.array([1.2, 1.4])], "J", None, None)  # one-sided: 1 still white
    assert norm.vmin == 1.0 and np.allclose(cmap(norm(1.0))[:3], cmap(0.0)[:3])
    cmap, norm = _colour_map([np.array([3.0, np.nan, 7.0])], "p", None, None)
    assert cmap.name.startswith("viridis") and (norm.vmin, norm.vmax) == (3.0, 7.0)
    _, norm = _colour_map([np.ones(4)], "J", None, None)
    assert norm.vmin < 1.0 < norm.vmax
    assert _subsample(10, 4).tolist() == [0, 3, 6, 9]
    assert _subsample(3, 150).tolist() == [0, 1, 2]


def test_wrong_shapes_raise(tmp_path):
    mesh = two_triangles()
    with pytest.raises(ValueError, match="cell_values"):
        render_frame_png(mesh, mesh.points, np.ones(3), tmp_path / "x.png")
    with pytest.raises(ValueError, match="3D mesh"):
        render_frame_png_3d(mesh, mesh.points, np.ones(2), tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


def test_3d_picture_of_a_smooth_body_without_feature_edges(tmp_path):
    """A generated ellipsoid has no sharp edges: the rest outline is empty, which matplotlib
    refused (the plain install's palpation example ended in an internal error)."""
    from tissuesim.mesh.generators.ellipsoids import ellipsoid

    mesh = ellipsoid((0.0, 0.0, 0.0), (0.06, 0.04, 0.03), 6)
    x = mesh.points * 1.01
    out = render_frame_png_3d(mesh, x, np.ones(mesh.n_cells), tmp_path / "e.png", title="smooth")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

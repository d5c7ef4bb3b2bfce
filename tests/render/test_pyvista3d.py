"""Off-screen PyVista pictures of coupled scenes: PNG of one moment, GIF of a run."""

import sys

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from PIL import Image, ImageSequence  # noqa: E402

from tissuesim.render import pyvista3d  # noqa: E402
from tissuesim.render.gif3d import GifWriter  # noqa: E402
from tissuesim.render.pyvista3d import (  # noqa: E402
    Camera,
    Frame3D,
    PointLayer,
    SurfaceLayer,
    render_frame_png,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def sphere(centre, radius=1.0) -> tuple[np.ndarray, np.ndarray]:
    s = pv.Sphere(radius=radius, center=centre, theta_resolution=24, phi_resolution=24)
    s = s.triangulate()
    return np.asarray(s.points, dtype=float), np.asarray(s.regular_faces)


def scene(shift: float = 0.0, *, cut: bool = True, n_points: int = 400) -> Frame3D:
    p1, t1 = sphere((-1.5, 0.0, 0.0))
    p2, t2 = sphere((1.5 + shift, 0.0, 0.0), 0.8)
    rng = np.random.default_rng(0)
    pts = rng.uniform([-0.6, -0.6, -0.6], [0.6, 0.6, 0.6], (n_points, 3))
    cuts = [np.array([[[0.0, -1.0, -1.0], [0.0, 1.0, -1.0], [0.0, 0.0, 1.0]]])] if cut else []
    return Frame3D(
        surfaces=[
            SurfaceLayer("organ A", p1, t1, color="steelblue"),
            SurfaceLayer("organ B", p2, t2, color="lightgrey", opacity=0.9),
        ],
        points=[PointLayer("tissue", pts, np.abs(pts[:, 0]), "strain", clim=(0.0, 0.6))],
        cuts=cuts,
        title=f"shift {shift:.2f}",
    )


def rgb(image) -> np.ndarray:
    return np.asarray(image.convert("RGB"), dtype=float)


def test_png_is_a_real_picture_of_the_scene(tmp_path):
    path = tmp_path / "scene.png"
    camera = render_frame_png(path, scene(), window_size=(400, 300))
    assert isinstance(camera, Camera)
    assert path.read_bytes()[:8] == PNG_MAGIC
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.png"]  # no temporary left
    with Image.open(path) as im:
        assert im.size == (400, 300)
        pixels = rgb(im)
    assert pixels.std() > 20  # not blank
    r, g, b = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    scene_part = np.zeros(r.shape, dtype=bool)
    scene_part[:, : int(0.78 * 400)] = True  # left of the legend (whose "cut" square is red too)
    red = (r > g + 60) & (r > b + 60) & scene_part
    assert red.sum() > 100  # the semi-transparent cut shows up
    blue = (b > r + 40) & scene_part  # organ A in steel blue
    assert blue.sum() > 500

    # the returned camera reproduces the view
    again = tmp_path / "again.png"
    assert render_frame_png(again, scene(), window_size=(400, 300), camera=camera) == camera
    with Image.open(again) as im:
        assert np.abs(rgb(im) - pixels).mean() < 1.0


def test_gif_shows_motion_with_one_fixed_camera(tmp_path):
    path = tmp_path / "run.gif"
    frames = [scene(shift, cut=False, n_points=0) for shift in (0.0, 0.5, 1.0)]
    with GifWriter(path, window_size=(240, 180), fps=10) as gif:
        for f in frames:
            gif.add(f)
        camera = gif.camera
    assert isinstance(camera, Camera)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.gif"]
    with Image.open(path) as im:
        assert im.size == (240, 180)
        assert im.n_frames == 3
        assert im.info.get("loop") == 0
        images = [rgb(f) for f in ImageSequence.Iterator(im)]
    for a, b in zip(images, images[1:], strict=False):
        assert a.std() > 20
        assert np.abs(a - b).mean() > 0.5  # organ B moved
    # organ A did not move and the camera is fixed: its steel blue stays where it was
    blue = [(f[..., 2] > f[..., 0] + 40) for f in images]
    assert (blue[0] & blue[-1]).sum() > 0.9 * blue[0].sum()


def fake_render(self, frame):
    """Stand-in for GifWriter._render: a tiny image whose red value is the frame's title."""
    return Image.new("RGB", (4, 4), (int(frame.title), 0, 0)).quantize(256)


def test_gif_frame_budget_keeps_every_kth_and_the_last(tmp_path, monkeypatch):
    monkeypatch.setattr(GifWriter, "_render", fake_render)
    path = tmp_path / "budget.gif"
    gif = GifWriter(path, max_frames=4)
    for i in range(10):
        gif.add(Frame3D(title=str(10 * i)))
    assert gif.n_added == 10
    gif.close()
    assert gif.close() == path  # a second close does nothing
    with Image.open(path) as im:
        kept = [int(rgb(f)[0, 0, 0]) // 10 for f in ImageSequence.Iterator(im)]
    assert kept == [0, 4, 8, 9]  # stride 4, then the last frame added


def test_gif_writes_nothing_after_an_error(tmp_path, monkeypatch):
    monkeypatch.setattr(GifWriter, "_render", fake_render)
    path = tmp_path / "broken.gif"
    with pytest.raises(RuntimeError, match="solver failed"), GifWriter(path) as gif:
        gif.add(Frame3D(title="1"))
        raise RuntimeError("solver failed")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(RuntimeError, match="closed"):
        gif.add(Frame3D(title="2"))
    with pytest.raises(ValueError, match="at least one frame"):
        GifWriter(tmp_path / "empty.gif").close()
    assert list(tmp_path.iterdir()) == []


def test_missing_pyvista_gives_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyvista", None)  # makes `import pyvista` fail
    message = r"need PyVista: pip install 'tissuesim\[pyvista\]'"
    with pytest.raises(ImportError, match=message):
        render_frame_png(tmp_path / "x.png", scene())
    with pytest.raises(ImportError, match=message):
        GifWriter(tmp_path / "x.gif")
    assert list(tmp_path.iterdir()) == []


def test_layers_check_their_shapes():
    pts = np.zeros((4, 3))
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    with pytest.raises(ValueError, match="points"):
        SurfaceLayer("a", np.zeros((4, 2)), tri, "red")
    with pytest.raises(ValueError, match="ids"):
        SurfaceLayer("a", pts, tri + 2, "red")
    with pytest.raises(ValueError, match="scalars"):
        SurfaceLayer("a", pts, tri, "red", scalars=np.zeros(3))
    with pytest.raises(ValueError, match="scalars"):
        PointLayer("p", pts, np.zeros(5), "strain")
    with pytest.raises(ValueError, match="clim"):
        PointLayer("p", pts, np.zeros(4), "strain", clim=(1.0, 0.0))
    with pytest.raises(ValueError, match="cut"):
        Frame3D(cuts=[np.zeros((2, 3))])
    with pytest.raises(TypeError):
        Frame3D(surfaces=[pts])
    # arrays are copied and read-only; one (m, 3, 3) array counts as one cut; empty layers work
    source = np.ones((4, 3))
    layer = PointLayer("p", source, None, "")
    source[:] = 7.0
    assert layer.points.max() == 1.0 and not layer.points.flags.writeable
    f = Frame3D(points=[PointLayer("e", np.zeros((0, 3)))], cuts=np.zeros((2, 3, 3)))
    assert len(f.cuts) == 1 and f.cuts[0].shape == (2, 3, 3)


def test_default_camera_frames_the_scene():
    cam = pyvista3d._fit_camera(pyvista3d._scene_points(scene()), (800, 600), 0.04)
    d = np.subtract(cam.position, cam.focal_point)
    assert np.linalg.norm(d) > 3.0  # outside the scene, looking at it
    assert d[2] > 0 and abs(np.dot(d, cam.view_up)) < 1e-9 * np.linalg.norm(d)  # from above
    empty = pyvista3d._fit_camera(np.zeros((0, 3)), (800, 600), 0.04)
    assert np.isfinite(empty.position).all()


def test_the_view_frames_the_bodies_not_a_large_floor_under_them():
    """A 10 m floor under a 0.1 m block: framed on the floor the block was a speck; the floor
    is context, so only its part near the block counts for the view."""
    block, tri = sphere((0.0, 0.0, 0.05), 0.05)
    floor = np.array([[-5.0, -5.0, 0.0], [5.0, -5.0, 0.0], [5.0, 5.0, 0.0], [-5.0, 5.0, 0.0]])
    floor_tri = np.array([[0, 1, 2], [0, 2, 3]])
    frame = Frame3D(
        surfaces=[
            SurfaceLayer("floor", floor, floor_tri, context=True),
            SurfaceLayer("block", block, tri, scalars=block[:, 2], scalar_name="z (m)"),
        ]
    )
    framed = pyvista3d._scene_points(frame)
    assert np.abs(framed).max() <= 0.1 + 1e-6  # the floor's far corners left out
    plain = Frame3D(surfaces=[SurfaceLayer("floor", floor, floor_tri), frame.surfaces[1]])
    assert np.abs(pyvista3d._scene_points(plain)).max() == 5.0  # not context: all of it
    near = pyvista3d._fit_camera(framed, (800, 600), 0.04)
    far = pyvista3d._fit_camera(pyvista3d._scene_points(plain), (800, 600), 0.04)
    distance = np.linalg.norm(np.subtract(near.position, near.focal_point))
    assert distance < 0.05 * np.linalg.norm(np.subtract(far.position, far.focal_point))
    only_floor = Frame3D(surfaces=[SurfaceLayer("floor", floor, floor_tri, context=True)])
    assert len(pyvista3d._scene_points(only_floor)) == 4  # no body: the floor is the scene


def test_colour_bar_labels_have_the_digits_their_range_needs():
    assert pyvista3d._label_format(0.998, 1.0) == "%.5g"  # 0.9985 apart from 0.998
    assert pyvista3d._label_format(0.0, 1000.0) == "%.3g"
    assert pyvista3d._label_format(1.0, 1.0) == "%.3g"  # a constant field
    assert pyvista3d._label_format(1.0, 1.0 + 1e-12) == "%.8g"  # capped
    labels = {pyvista3d._label_format(0.998, 1.0) % v for v in np.linspace(0.998, 1.0, 5)}
    assert len(labels) == 5


def test_long_colour_bar_titles_wrap_between_words_instead_of_being_cut():
    title = "liver\nlargest principal Green strain (-)"
    wrapped = pyvista3d._wrap_title(title, room=150.0, letter=6.0)  # 25 letters a line
    lines = wrapped.split("\n")
    assert lines == ["liver", "largest principal Green", "strain (-)"]
    assert ".." not in wrapped
    cut = pyvista3d._wrap_title("a b c d e f g h", room=18.0, letter=6.0, max_lines=2)
    assert len(cut.split("\n")) == 2 and cut.endswith("..")


def test_several_bodies_get_their_own_colour_bars_and_one_heading(tmp_path):
    a, ta = sphere((-1.5, 0.0, 0.0))
    b, tb = sphere((1.5, 0.0, 0.0))
    frame = Frame3D(
        surfaces=[
            SurfaceLayer("liver", a, ta, scalars=a[:, 0], scalar_name="liver", clim=(-2.5, -0.5)),
            SurfaceLayer("gallbladder", b, tb, scalars=b[:, 0], scalar_name="gallbladder"),
        ],
        title="t = 1 s",
        bar_heading="largest principal Green strain (-)",
    )
    out = tmp_path / "two.png"
    render_frame_png(out, frame, window_size=(800, 600))
    assert out.read_bytes()[:8] == PNG_MAGIC

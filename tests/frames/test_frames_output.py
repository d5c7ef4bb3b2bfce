"""Simulation.run output of a frame body: series of points, frames and surface, summary,
pictures."""

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest
from PIL import Image

import tissuesim.render.points3d as points3d
from tissuesim.frames.placement import grid_frames
from tissuesim.frames.sampling import box_surface, sample_box
from tissuesim.io.series.vtu import VTUSeriesWriter
from tissuesim.materials import make_material
from tissuesim.simulation import Simulation

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
FIELDS = {"J", "green_strain", "cauchy_stress", "von_mises", "energy_density"}
POINT_ARRAYS = {"displacement", "velocity", "volume", "mass"} | FIELDS
FRAME_ARRAYS = {"displacement", "velocity", "axis_x", "axis_y", "axis_z", "radius"}
SERIES = {"integration_points": "body", "frames": "body_frames", "surface": "body_surface"}


def column(surface: bool = True) -> Simulation:
    """A 0.4 x 0.4 x 1 column on 3 rigid frames, clamped at z = 0, sagging under gravity."""
    sim = Simulation.from_frames(
        grid_frames([0.2, 0.2, 0], [0.2, 0.2, 1], (1, 1, 3)),
        sample_box([0, 0, 0], [0.4, 0.4, 1], 0.1),
        make_material("stvk", youngs_modulus=1e3, poisson_ratio=0.3),
        density=10,
        time_step=0.02,
    )
    sim.fix_frames(sim.frames_where(lambda X: X[:, 2] < 1e-9))
    if surface:
        sim.embed_surface(box_surface([0, 0, 0], [0.4, 0.4, 1]))
    sim.add_gravity([0, -9.81, 0])
    return sim


def read_pvd(path: Path) -> list[tuple[float, Path]]:
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    return [(float(d.get("timestep")), path.parent / d.get("file")) for d in root.iter("DataSet")]


def assert_picture(path: Path, fmt: str) -> None:
    data = path.read_bytes()
    assert len(data) > 0
    if fmt == "PNG":
        assert data[:8] == PNG_MAGIC
    else:
        assert data[:6] in (b"GIF87a", b"GIF89a")
    with Image.open(path) as im:
        assert im.format == fmt
        pixels = np.asarray(im.convert("RGB"), dtype=float)
    assert pixels.std() > 5  # something was drawn


def gif_frame_count(path: Path) -> int:
    with Image.open(path) as im:
        return im.n_frames


def test_run_writes_three_series_summary_and_pictures(tmp_path):
    sim = column()
    out = tmp_path / "run"
    history = sim.run(4, out, progress=False, metadata={"scene": "column"})
    assert len(history) == 4

    series = {kind: read_pvd(out / f"{name}.pvd") for kind, name in SERIES.items()}
    for kind, rows in series.items():  # the rest frame, then every step
        assert [p.name for _, p in rows] == [f"{SERIES[kind]}_{k:05d}.vtu" for k in range(5)]
        times = [t for t, _ in rows]
        assert times[0] == 0.0 and times[-1] == pytest.approx(sim.time)
        assert np.all(np.diff(times) > 0)
        assert all(p.is_file() for _, p in rows)

    points = meshio.read(series["integration_points"][-1][1])
    q = sim.model.samples.n
    assert points.points.shape == (q, 3)
    assert [c.type for c in points.cells] == ["vertex"] and points.cells[0].data.shape == (q, 1)
    assert set(points.point_data) == POINT_ARRAYS
    fields = sim.point_fields()
    # rest positions + displacement: ParaView's Warp By Vector gives the deformed body
    np.testing.assert_allclose(points.points, sim.model.samples.points, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        points.points + points.point_data["displacement"], fields["positions"], atol=1e-12
    )
    np.testing.assert_allclose(points.point_data["J"], fields["J"], atol=1e-12)
    assert points.point_data["green_strain"].shape == (q, 9)
    np.testing.assert_allclose(
        points.point_data["green_strain"], fields["green_strain"].reshape(q, 9), atol=1e-12
    )
    np.testing.assert_allclose(points.point_data["volume"], sim.model.samples.volumes)
    np.testing.assert_allclose(points.point_data["mass"], 10 * sim.model.samples.volumes)
    assert np.abs(points.point_data["displacement"]).max() > 1e-4  # it did sag

    frames = meshio.read(series["frames"][-1][1])
    assert frames.points.shape == (3, 3) and frames.cells[0].type == "vertex"
    assert set(frames.point_data) == FRAME_ARRAYS
    np.testing.assert_allclose(frames.points, sim.rest_frames, atol=1e-12)
    np.testing.assert_allclose(
        frames.point_data["displacement"], sim.frame_positions - sim.rest_frames, atol=1e-12
    )
    R = sim.frame_rotations
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(frames.point_data[f"axis_{axis}"], R[:, :, k], atol=1e-12)
    np.testing.assert_allclose(frames.point_data["radius"], sim.model.shapes.radii)
    np.testing.assert_array_equal(frames.point_data["displacement"][0], 0.0)  # clamped frame
    assert not np.allclose(R[2], np.eye(3))  # the top frame turned

    first = meshio.read(series["surface"][0][1])
    last = meshio.read(series["surface"][-1][1])
    assert [c.type for c in last.cells] == ["triangle"]
    np.testing.assert_array_equal(last.cells[0].data, sim.surface.triangles)
    np.testing.assert_allclose(first.points, sim.surface.points, atol=1e-12)
    np.testing.assert_allclose(last.points, sim.surface.points, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        last.points + last.point_data["displacement"],
        sim.embedded_positions("surface"),
        atol=1e-12,
    )

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["error"] is None
    assert summary["scene"] == "column"
    body = summary["simulation"]["bodies"]["body"]
    assert body["kind"] == "frames" and body["frames"] == 3 and body["integration_points"] == q
    assert body["volume"] == pytest.approx(0.16) and body["mass"] == pytest.approx(1.6)
    assert body["surface_triangles"] == len(sim.surface.triangles)
    # the clamped frame's reaction balances the weight (1.6 kg) once the column has settled
    assert summary["forces"][-1]["body.fixed_frames"][1] > 0
    assert summary["totals"]["steps"] == 4 and len(summary["steps"]) == 4
    assert [s["step"] for s in summary["steps"]] == [1, 2, 3, 4]
    assert summary["totals"]["min_J"] == pytest.approx(min(r.min_J for r in history))

    assert_picture(out / "final.png", "PNG")
    assert_picture(out / "run.gif", "GIF")
    assert gif_frame_count(out / "run.gif") == 5
    assert not any(p.name.startswith(".") for p in out.iterdir())  # no temporary files left


def test_every_and_no_pictures(tmp_path):
    sim = column()
    sim.run(3, tmp_path, every=2, progress=False, render=False)
    for name in SERIES.values():
        times = [t for t, _ in read_pvd(tmp_path / f"{name}.pvd")]
        assert times == pytest.approx([0.0, 0.04, 0.06])  # rest, step 2, and the last step
    assert not (tmp_path / "final.png").exists() and not (tmp_path / "run.gif").exists()
    assert json.loads((tmp_path / "summary.json").read_text())["totals"]["steps"] == 3


def test_a_crash_leaves_a_failed_summary_and_readable_series(tmp_path, monkeypatch):
    sim = column()
    step = sim.step

    def failing_step():
        if len(sim.history) == 2:
            raise RuntimeError("solver exploded")
        return step()

    monkeypatch.setattr(sim, "step", failing_step)
    with pytest.raises(RuntimeError, match="solver exploded"):
        sim.run(5, tmp_path, progress=False)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert summary["error"] == "RuntimeError: solver exploded"
    assert summary["totals"]["steps"] == 2 and len(summary["steps"]) == 2
    for name in SERIES.values():
        rows = read_pvd(tmp_path / f"{name}.pvd")
        assert len(rows) == 3  # the rest frame and the two steps done
        for _, path in rows:
            assert meshio.read(path).points.shape[1] == 3
    assert_picture(tmp_path / "final.png", "PNG")  # the state it failed in


def test_without_surface_the_point_cloud_is_drawn(tmp_path, monkeypatch):
    stale = column()  # an earlier run with a surface in the same directory
    stale.run(1, tmp_path, progress=False, render=False)
    assert (tmp_path / "body_surface.pvd").exists()
    monkeypatch.setitem(__import__("sys").modules, "pyvista", None)  # the matplotlib fallback

    calls = []
    real = points3d.render_points_png

    def spy(positions, values, path, **kwargs):
        calls.append((np.array(positions), np.array(values), kwargs))
        return real(positions, values, path, **kwargs)

    monkeypatch.setattr(points3d, "render_points_png", spy)
    sim = column(surface=False)
    sim.run(2, tmp_path, progress=False)
    assert not (tmp_path / "body_surface.pvd").exists()
    assert not list(tmp_path.glob("body_surface_*.vtu"))
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["simulation"]["bodies"]["body"]["surface_triangles"] == 0
    assert "PyVista not installed" in summary["pictures"]

    ((positions, values, kwargs),) = calls
    assert kwargs["triangles"] is None
    np.testing.assert_allclose(positions, sim.point_fields()["positions"])
    u = sim.point_fields()["positions"] - sim.model.samples.points
    np.testing.assert_allclose(values, np.linalg.norm(u, axis=1))
    np.testing.assert_allclose(kwargs["markers"], sim.frame_positions)
    assert kwargs["vmin"] == 0.0 and kwargs["vmax"] == pytest.approx(values.max())
    assert_picture(tmp_path / "final.png", "PNG")
    assert gif_frame_count(tmp_path / "run.gif") == 3


def test_vtu_writer_with_cell_blocks(tmp_path):
    x = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    cloud = VTUSeriesWriter(
        tmp_path, None, "cloud", cells=("vertex", np.arange(4)[:, None]), n_points=4
    )
    skin = VTUSeriesWriter(
        tmp_path, name="skin", cells=("triangle", [[0, 1, 2], [0, 3, 1]]), n_points=4
    )
    for t in (0.0, 0.5):
        cloud.write(t, x + t, {"s": np.arange(4.0) * t, "T": np.ones((4, 3, 3))})
        skin.write(t, x * (1 + t), {"u": x * t}, {"id": np.array([7, 8])})
    assert [p.name for _, p in read_pvd(tmp_path / "cloud.pvd")] == [
        "cloud_00000.vtu",
        "cloud_00001.vtu",
    ]
    back = meshio.read(tmp_path / "cloud_00001.vtu")
    assert back.cells[0].type == "vertex"
    np.testing.assert_array_equal(back.cells[0].data.ravel(), np.arange(4))
    np.testing.assert_allclose(back.points, x + 0.5)
    assert back.point_data["T"].shape == (4, 9)
    back = meshio.read(tmp_path / "skin_00001.vtu")
    assert back.cells[0].type == "triangle"
    np.testing.assert_array_equal(back.cells[0].data, [[0, 1, 2], [0, 3, 1]])
    np.testing.assert_allclose(back.point_data["u"], x * 0.5)
    np.testing.assert_array_equal(back.cell_data["id"][0], [7, 8])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({}, "either a mesh or cells"),
        ({"cells": ("vertex", np.zeros((2, 1), dtype=int))}, "n_points"),
        ({"cells": ("triangle", np.zeros((2, 2), dtype=int)), "n_points": 3}, r"\(m, 3\)"),
        ({"cells": ("triangle", np.array([[0, 1, 3]])), "n_points": 3}, "ids must lie"),
        ({"cells": ("blob", np.zeros((1, 1), dtype=int)), "n_points": 1}, "not one of"),
        ({"cells": ("vertex", np.zeros((1, 1))), "n_points": 1}, "integer ids"),
    ],
)
def test_vtu_writer_rejects_bad_cell_blocks(tmp_path, kwargs, match):
    with pytest.raises(ValueError, match=match):
        VTUSeriesWriter(tmp_path, None, "bad", **kwargs)


def test_vtu_writer_cell_block_checks_positions(tmp_path):
    writer = VTUSeriesWriter(tmp_path, cells=("vertex", np.arange(3)[:, None]), n_points=3)
    with pytest.raises(ValueError, match=r"expected \(3, 3\)"):
        writer.write(0.0, np.zeros((3, 2)))
    with pytest.raises(ValueError, match="point_data"):
        writer.write(0.0, np.zeros((3, 3)), {"s": np.zeros(2)})
    assert writer.frames == [] and not writer.pvd_path.exists()

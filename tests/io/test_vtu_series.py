"""VTU/PVD series and atomic writers: round trips through meshio, valid index after every frame."""

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

from tissuesim.io import VTUSeriesWriter, write_json_atomic, write_text_atomic
from tissuesim.mesh.mesh import Mesh


def two_triangles() -> Mesh:
    points = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    return Mesh(points, np.array([[0, 1, 2], [0, 2, 3]]))


def two_tets() -> Mesh:
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)
    return Mesh(points, np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))


def read_pvd(path: Path) -> list[tuple[float, str]]:
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def leftovers(directory: Path) -> list[str]:
    return [p.name for p in directory.iterdir() if p.name.startswith(".") or "tmp" in p.name]


def test_three_frames_round_trip_2d(tmp_path):
    mesh = two_triangles()
    writer = VTUSeriesWriter(tmp_path / "out", mesh)
    times = [0.0, 0.05, 0.1]
    for k, t in enumerate(times):
        u = np.full((4, 2), 0.1 * k)
        x = mesh.points + u
        path = writer.write(
            t, x, {"u": u, "s": np.arange(4.0) + k}, {"J": np.array([1.0, 2.0]) * k}
        )
        assert path.name == f"frame_{k:05d}.vtu"
        entries = read_pvd(tmp_path / "out" / "frame.pvd")  # valid after every write
        assert [e[0] for e in entries] == times[: k + 1]
        assert leftovers(tmp_path / "out") == []

    assert [t for t, _ in writer.frames] == times
    for (t, file), (t2, path) in zip(read_pvd(writer.pvd_path), writer.frames, strict=True):
        assert t == t2 and (tmp_path / "out" / file).is_file() and path.name == file
    back = meshio.read(writer.frames[2][1])
    assert back.cells[0].type == "triangle"
    np.testing.assert_array_equal(back.cells[0].data, mesh.cells)
    np.testing.assert_allclose(back.points[:, :2], mesh.points + 0.2)
    np.testing.assert_array_equal(back.points[:, 2], 0.0)
    assert back.point_data["u"].shape == (4, 3)  # 2D vector padded for ParaView
    np.testing.assert_allclose(back.point_data["u"][:, :2], 0.2)
    np.testing.assert_array_equal(back.point_data["u"][:, 2], 0.0)
    np.testing.assert_allclose(back.point_data["s"], np.arange(4.0) + 2)
    np.testing.assert_allclose(back.cell_data["J"][0], [2.0, 4.0])


def test_tetra_frames(tmp_path):
    mesh = two_tets()
    writer = VTUSeriesWriter(tmp_path, mesh, name="run")
    for t in (0.0, 1.0, 2.0):
        writer.write(t, mesh.points * (1 + t), {"v": mesh.points * t}, {"J": np.full(2, 1 + t)})
    assert [f for _, f in read_pvd(tmp_path / "run.pvd")] == [f"run_{k:05d}.vtu" for k in range(3)]
    back = meshio.read(tmp_path / "run_00001.vtu")
    assert back.cells[0].type == "tetra"
    np.testing.assert_allclose(back.points, mesh.points * 2)
    np.testing.assert_allclose(back.point_data["v"], mesh.points)
    np.testing.assert_allclose(back.cell_data["J"][0], [2.0, 2.0])


def test_failed_write_keeps_index_and_frames(tmp_path, monkeypatch):
    mesh = two_triangles()
    writer = VTUSeriesWriter(tmp_path, mesh)
    writer.write(0.0, mesh.points)
    writer.write(0.5, mesh.points)
    before = (tmp_path / "frame.pvd").read_text()

    def crash(path, *args, **kwargs):  # dies half way through writing the temporary file
        Path(path).write_bytes(b"<VTKFile partial")
        raise OSError("disk full")

    monkeypatch.setattr(meshio, "write", crash)
    with pytest.raises(OSError, match="disk full"):
        writer.write(1.0, mesh.points)
    assert (tmp_path / "frame.pvd").read_text() == before
    assert len(writer.frames) == 2 and leftovers(tmp_path) == []
    assert not (tmp_path / "frame_00002.vtu").exists()
    # a temp file left by a hard kill does not touch the index or the frames it lists
    (tmp_path / ".frame_00002.tmp-dead.vtu").write_bytes(b"<VTKFile partial")
    for _, file in read_pvd(tmp_path / "frame.pvd"):
        assert meshio.read(tmp_path / file).points.shape == (4, 3)


def test_reopen_starts_fresh_and_spares_other_series(tmp_path):
    mesh = two_triangles()
    old = VTUSeriesWriter(tmp_path, mesh)
    other = VTUSeriesWriter(tmp_path, mesh, name="frame_x")
    for t in (0.0, 1.0, 2.0):
        old.write(t, mesh.points)
    other.write(0.0, mesh.points)
    new = VTUSeriesWriter(tmp_path, mesh)
    assert not (tmp_path / "frame.pvd").exists()
    assert sorted(p.name for p in tmp_path.glob("frame_0*.vtu")) == []
    assert (tmp_path / "frame_x_00000.vtu").exists() and (tmp_path / "frame_x.pvd").exists()
    new.write(3.0, mesh.points)
    assert read_pvd(tmp_path / "frame.pvd") == [(3.0, "frame_00000.vtu")]


def test_bad_shapes_are_rejected(tmp_path):
    mesh = two_triangles()
    writer = VTUSeriesWriter(tmp_path, mesh)
    with pytest.raises(ValueError, match="positions"):
        writer.write(0.0, np.zeros((3, 2)))
    with pytest.raises(ValueError, match="cell_data"):
        writer.write(0.0, mesh.points, cell_data={"J": np.ones(3)})
    with pytest.raises(ValueError, match="finite"):
        writer.write(float("nan"), mesh.points)
    assert writer.frames == [] and not writer.pvd_path.exists()


def test_write_json_atomic_is_strict_json(tmp_path):
    path = tmp_path / "summary.json"
    obj = {
        "n": np.int64(3),
        "x": np.float32(0.5),
        "arr": np.array([[1.0, np.nan], [np.inf, -2.0]]),
        "flag": np.bool_(True),
        "bad": float("-inf"),
        "path": tmp_path,
        1: (1, 2),
    }
    write_json_atomic(path, obj)

    def reject(name):
        raise AssertionError(f"non-standard JSON constant {name}")

    data = json.loads(path.read_text(), parse_constant=reject)
    assert data == {
        "n": 3,
        "x": 0.5,
        "arr": [[1.0, None], [None, -2.0]],
        "flag": True,
        "bad": None,
        "path": str(tmp_path),
        "1": [1, 2],
    }
    assert leftovers(tmp_path) == []
    with pytest.raises(TypeError):
        write_json_atomic(path, {"x": object()})
    assert json.loads(path.read_text())["n"] == 3  # old file intact


def test_write_text_atomic_replaces(tmp_path):
    path = tmp_path / "a.txt"
    write_text_atomic(path, "one\n")
    write_text_atomic(path, "two ü\n")
    assert path.read_text(encoding="utf-8") == "two ü\n"
    assert leftovers(tmp_path) == []

"""A crash-safe time series for ParaView: one ``.vtu`` per frame plus a ``.pvd`` index.

Each frame file and the index are written atomically (temporary file, fsync, ``os.replace``), and
the index is rewritten after every frame, so a hard kill at any moment leaves a readable series
holding every frame completed so far.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from tissuesim.errors import InputError
from tissuesim.io.atomic import atomic_output, write_text_atomic
from tissuesim.mesh.mesh import Mesh

__all__ = ["VTUSeriesWriter", "remove_series"]

_CELL_TYPE = {2: "triangle", 3: "tetra"}
# vertices per cell of the meshio cell types accepted with ``cells=``
_NODES_PER_CELL = {
    "vertex": 1,
    "line": 2,
    "triangle": 3,
    "quad": 4,
    "tetra": 4,
    "pyramid": 5,
    "wedge": 6,
    "hexahedron": 8,
}


def remove_series(directory: str | os.PathLike[str], name: str) -> None:
    """Delete ``{name}.pvd`` and every ``{name}_NNNNN.vtu`` in ``directory`` (index first).

    The index goes first so that a crash half way never leaves it listing a deleted frame; also
    used to clear a series a new run will not write, so it cannot be mistaken for this run's.
    """
    directory = Path(directory)
    (directory / f"{name}.pvd").unlink(missing_ok=True)
    if not directory.is_dir():
        return
    pattern = re.compile(rf"{re.escape(name)}_\d{{5,}}\.vtu")
    for old in directory.iterdir():
        if pattern.fullmatch(old.name):
            old.unlink()


def _cell_block(cells: tuple[str, np.ndarray], n_points: int) -> tuple[str, np.ndarray]:
    """Check a (cell_type, ids (m, k)) block against meshio's vertex count and n_points."""
    try:
        cell_type, ids = cells
    except (TypeError, ValueError):
        raise InputError("cells must be a pair (cell_type, ids (m, k))") from None
    if cell_type not in _NODES_PER_CELL:
        raise InputError(f"cell type {cell_type!r} is not one of {sorted(_NODES_PER_CELL)}")
    ids = np.asarray(ids)
    k = _NODES_PER_CELL[cell_type]
    if ids.ndim != 2 or ids.shape[1] != k or not np.issubdtype(ids.dtype, np.integer):
        raise InputError(
            f"{cell_type} cells need integer ids of shape (m, {k}), got {ids.dtype} {ids.shape}"
        )
    if n_points < 1:
        raise InputError(f"n_points must be >= 1, got {n_points}")
    if ids.size and (ids.min() < 0 or ids.max() >= n_points):
        raise InputError(
            f"cell vertex ids must lie in [0, {n_points - 1}], got {ids.min()}..{ids.max()}"
        )
    return str(cell_type), np.ascontiguousarray(ids, dtype=np.int64)


def _prepare(
    data: Mapping[str, np.ndarray], count: int, dim: int, kind: str
) -> dict[str, np.ndarray]:
    """Check each (count, ...) array; pad 2D vectors (count, 2) to (count, 3); flatten tensors."""
    out: dict[str, np.ndarray] = {}
    for key, value in data.items():
        arr = np.asarray(value)
        if arr.ndim == 0 or arr.shape[0] != count:
            raise InputError(
                f"{kind} {key!r} has shape {arr.shape}; it needs one row per "
                f"{'point' if kind == 'point_data' else 'cell'} ({count}, ...)"
            )
        if arr.dtype == bool:
            arr = arr.astype(np.uint8)
        if dim == 2 and arr.ndim == 2 and arr.shape[1] == 2:
            arr = np.concatenate([arr, np.zeros((count, 1), dtype=arr.dtype)], axis=1)
        elif arr.ndim > 2:
            arr = arr.reshape(count, -1)
        out[str(key)] = np.ascontiguousarray(arr)
    return out


class VTUSeriesWriter:
    """Write frames ``{name}_{index:05d}.vtu`` and the index ``{name}.pvd`` into ``directory``.

    mesh: the rest mesh; its cells (m, d + 1) are written as "triangle" (d = 2) or "tetra" (d = 3).
    Without a mesh, give ``cells=(cell_type, ids (m, k))`` and ``n_points``: any meshio cell block
    in 3D, e.g. ("vertex", (k, 1)) for a point cloud or ("triangle", (m, 3)) for a surface, so
    meshless bodies use the same crash-safe series as meshes.

    Opening a directory that already holds a series of the same ``name`` starts afresh: the old
    ``{name}.pvd`` and every ``{name}_NNNNN.vtu`` are deleted at construction (series with other
    names are left alone), so the index never mixes frames of two runs. ``keep``: (time, file
    name) of the first frames, to continue a resumed run's series instead: those are kept,
    later frames deleted, and the index rewritten.
    """

    def __init__(
        self,
        directory: str | os.PathLike[str],
        mesh: Mesh | None = None,
        name: str = "frame",
        *,
        cells: tuple[str, np.ndarray] | None = None,
        n_points: int | None = None,
        keep: Sequence[tuple[float, str]] | None = None,
    ) -> None:
        if (mesh is None) == (cells is None):
            raise InputError("VTUSeriesWriter needs either a mesh or cells=(cell_type, ids)")
        if mesh is not None:
            if n_points is not None:
                raise InputError("n_points is taken from the mesh; give it only with cells=")
            if mesh.dim not in _CELL_TYPE:
                raise InputError(f"VTUSeriesWriter supports 2D and 3D meshes, got dim {mesh.dim}")
            kind = mesh.cell_type  # meshio's name: triangle(6), tetra(10), quad, hexahedron
            block = (kind, np.asarray(mesh.cells, dtype=np.int64))
            self.dim, self.n_points = mesh.dim, mesh.n_points
            self._mesh_based = True
        else:
            if n_points is None:
                raise InputError("VTUSeriesWriter with cells= needs n_points")
            block = _cell_block(cells, int(n_points))
            self.dim, self.n_points = 3, int(n_points)
            self._mesh_based = False
        if not name or os.sep in name or "/" in name:
            raise InputError(f"series name {name!r} must be a non-empty file name stem")
        self.directory = Path(directory)
        self.mesh = mesh
        self.name = name
        self.cell_type = block[0]
        self.n_cells = int(block[1].shape[0])
        self._frames: list[tuple[float, Path]] = []
        self.directory.mkdir(parents=True, exist_ok=True)
        self._cells = [block]
        if keep:
            self._continue(keep)
        else:
            remove_series(self.directory, name)

    def _continue(self, keep: Sequence[tuple[float, str]]) -> None:
        """Adopt the frames ``keep`` (time, file name) of a resumed run; drop later ones."""
        self._frames = [(float(t), self.directory / file) for t, file in keep]
        write_text_atomic(self.pvd_path, self._pvd_text())  # first: it never lists a lost frame
        pattern = re.compile(rf"{re.escape(self.name)}_(\d{{5,}})\.vtu")
        for old in self.directory.iterdir():
            match = pattern.fullmatch(old.name)
            if match and int(match.group(1)) >= len(keep):
                old.unlink()

    def set_mesh(self, mesh: Mesh) -> None:
        """Write the next frames on ``mesh`` (a body that was cut: more points and cells);
        frames written before keep theirs, and the index lists them all (ParaView follows a
        series whose topology changes)."""
        if not self._mesh_based or mesh.dim != self.dim:
            raise InputError("set_mesh needs a writer made with a mesh of the same dimension")
        self.mesh = mesh
        self.n_points = mesh.n_points
        self._cells = [(mesh.cell_type, np.asarray(mesh.cells, dtype=np.int64))]
        self.n_cells = int(mesh.n_cells)

    @property
    def frames(self) -> list[tuple[float, Path]]:
        """(time, path of the .vtu) for every frame written so far, in order."""
        return list(self._frames)

    @property
    def pvd_path(self) -> Path:
        return self.directory / f"{self.name}.pvd"

    def write(
        self,
        time: float,
        positions: np.ndarray,
        point_data: Mapping[str, np.ndarray] | None = None,
        cell_data: Mapping[str, np.ndarray] | None = None,
        cells: tuple[str, np.ndarray] | None = None,
    ) -> Path:
        """Write one frame and rewrite the index; return the frame's path.

        cells: this frame's own cell block (a surface that grows, a cloud that loses points),
            with any number of positions (writers made with ``cells=`` only).

        positions: (n, d) current vertex positions (written as 3D points, z = 0 in 2D; d = 3
            for a writer made with ``cells=``).
        point_data: name -> (n,) or (n, k) arrays; 2D vectors (n, 2) are padded to (n, 3) so
            ParaView shows them as vectors; (n, a, b) tensors are flattened to (n, a * b).
        cell_data: name -> (m,) or (m, k) arrays, treated the same way.
        """
        import meshio

        n, dim = self.n_points, self.dim
        blocks, n_cells = self._cells, self.n_cells
        if cells is not None:
            if self._mesh_based:
                raise InputError("per-frame cells= need a writer made with cells=")
            n = int(np.asarray(positions).shape[0])
            block = _cell_block(cells, max(n, 1))
            blocks, n_cells = [block], int(block[1].shape[0])
        time = float(time)
        if not math.isfinite(time):
            raise InputError(f"frame time must be finite, got {time}")
        x = np.asarray(positions, dtype=np.float64)
        if x.shape != (n, dim):
            raise InputError(f"positions have shape {x.shape}; expected ({n}, {dim})")
        if dim == 2:
            x = np.concatenate([x, np.zeros((n, 1))], axis=1)
        pdata = _prepare(point_data or {}, n, dim, "point_data")
        cdata = _prepare(cell_data or {}, n_cells, dim, "cell_data")
        out = meshio.Mesh(x, blocks, point_data=pdata, cell_data={k: [v] for k, v in cdata.items()})
        path = self.directory / f"{self.name}_{len(self._frames):05d}.vtu"
        with atomic_output(path) as tmp:
            meshio.write(tmp, out, file_format="vtu")
        self._frames.append((time, path))
        write_text_atomic(self.pvd_path, self._pvd_text())
        return path

    def _pvd_text(self) -> str:
        rows = "".join(
            f'    <DataSet timestep="{t!r}" part="0" file={quoteattr(p.name)}/>\n'
            for t, p in self._frames
        )
        return (
            '<?xml version="1.0"?>\n'
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            f"  <Collection>\n{rows}  </Collection>\n</VTKFile>\n"
        )

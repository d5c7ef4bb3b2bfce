"""Quadratic quadrilaterals and hexahedra (quad8 / quad9, hex20 / hex27) on a structured grid,
for ``rectangle`` and ``box``."""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MeshError
from tissuesim.mesh.checks import validate_mesh
from tissuesim.mesh.generators.common import _order, check_mesh_size
from tissuesim.mesh.mesh import Mesh

#: generator element names of the quadratic quadrilaterals / hexahedra -> meshio's cell type
QUADRATIC_TENSOR = {
    "quad8": "quad8",
    "quad9": "quad9",
    "hex20": "hexahedron20",
    "hex27": "hexahedron27",
}


def _quadratic_tensor(name, element, coords, names, order, source) -> Mesh:
    """Quadratic quadrilaterals / hexahedra on the grid of 1D vertex coordinates ``coords``
    (one array per axis): midside (and face, centre) nodes at the midpoints, nodes no cell
    uses (a hexahedron20's face centres) left out; point sets hold every node on their side,
    facet sets the boundary facets by their corners."""
    from tissuesim.mesh.cells import tensor_quadratic as tq

    if _order(order) == 1:
        raise MeshError(f"{name}: element = {element!r} is quadratic; give order 2 or leave it out")
    kind = QUADRATIC_TENSOR[element]
    d = len(coords)
    fine = [np.insert(c, np.arange(1, len(c)), 0.5 * (c[1:] + c[:-1])) for c in coords]
    shape = [len(f) for f in fine]  # 2 n + 1 per axis
    grid = np.meshgrid(*[np.arange(k) for k in shape], indexing="ij")
    index = [g.ravel(order="F") for g in grid]  # x fastest
    points = np.column_stack([f[i] for f, i in zip(fine, index, strict=True)])
    ncell = [(k - 1) // 2 for k in shape]
    base = np.meshgrid(*[2 * np.arange(k) for k in ncell], indexing="ij")
    base = np.stack([b.ravel(order="F") for b in base], axis=1)  # (m, d) fine index of corner 0
    local = (tq.NODES[kind] + 1).astype(np.int64)  # (nv, d) offsets 0, 1, 2
    node = base[:, None, :] + local[None]  # (m, nv, d)
    strides = np.cumprod([1, *shape[:-1]])
    cells = node @ strides
    used = np.unique(cells)
    renumber = np.full(points.shape[0], -1, dtype=np.int64)
    renumber[used] = np.arange(used.size)
    points, cells = points[used], renumber[cells]
    index = [i[used] for i in index]
    from tissuesim.mesh.cells.tensor import boundary_faces

    bf = boundary_faces(cells[:, : 2**d], d)
    psets, fsets = {}, {}
    for axis, (low, high) in enumerate(names):
        for set_name, value in ((low, 0), (high, shape[axis] - 1)):
            ids = np.flatnonzero(index[axis] == value)
            psets[set_name] = ids
            fsets[set_name] = bf[np.isin(bf, ids).all(axis=1)]
    check_mesh_size(name, cells.shape[0], d)
    source = source[:-1] + f", element={element!r})"
    return validate_mesh(points, cells, source=source, point_sets=psets, facet_sets=fsets)

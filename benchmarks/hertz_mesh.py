"""The graded quarter block of the Hertz benchmark and of the ``hertz_indentation`` example.

[0, L]^2 x [-L, 0], tetrahedra of size h0 within r_fine of the contact point (the origin),
growing linearly with the distance beyond it (gmsh's Distance + Threshold fields) to L / 8;
gmsh physical groups name the volume "block" and the faces "top" (z = 0), "base" (z = -L),
"xmin" and "ymin" (the symmetry planes), so ``read_mesh`` gives them as facet sets. gmsh
(GPL, ``pip install gmsh``) is a tool of this script only; the example ships the file it wrote:

    python3 benchmarks/hertz_mesh.py src/tissuesim/examples/hertz_block.msh
"""

from __future__ import annotations

import sys
from pathlib import Path

L = 0.15  # m: block width and depth, > 100 contact radii at the benchmark's deepest step
H0, R_FINE, GROWTH = 1.4e-4, 1.7e-3, 0.15  # the example's mesh


def graded_block(
    path: Path, h0: float = H0, r_fine: float = R_FINE, growth: float = GROWTH
) -> Path:
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("hertz")
        volume = gmsh.model.occ.addBox(0, 0, -L, L, L, L)
        gmsh.model.occ.synchronize()
        eps = 1e-5  # OCC's bounding boxes carry a tolerance

        def face(lo, hi) -> int:
            (entity,) = gmsh.model.getEntitiesInBoundingBox(*lo, *hi, 2)
            return entity[1]

        faces = {
            "top": face((-eps, -eps, -eps), (L + eps, L + eps, eps)),
            "base": face((-eps, -eps, -L - eps), (L + eps, L + eps, -L + eps)),
            "xmin": face((-eps, -eps, -L - eps), (eps, L + eps, eps)),
            "ymin": face((-eps, -eps, -L - eps), (L + eps, eps, eps)),
        }
        for name, tag in faces.items():
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [tag]), name)
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [volume]), "block")
        corner = gmsh.model.getEntitiesInBoundingBox(-eps, -eps, -eps, eps, eps, eps, 0)
        field = gmsh.model.mesh.field
        field.add("Distance", 1)
        field.setNumbers(1, "PointsList", [corner[0][1]])
        field.add("Threshold", 2)
        field.setNumber(2, "InField", 1)
        h_max = L / 8
        field.setNumber(2, "SizeMin", h0)
        field.setNumber(2, "SizeMax", h_max)
        field.setNumber(2, "DistMin", r_fine)
        field.setNumber(2, "DistMax", r_fine + (h_max - h0) / growth)
        field.setAsBackgroundMesh(2)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        gmsh.option.setNumber("Mesh.Algorithm3D", 1)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


if __name__ == "__main__":
    out = graded_block(Path(sys.argv[1]))
    import tissuesim as ts

    print(ts.read_mesh(out))

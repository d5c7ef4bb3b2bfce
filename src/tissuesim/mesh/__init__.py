"""Meshes of simplices or Q1 cells: generators, file I/O, validation, boundary facets and
selections.

The Mesh type is in ``mesh.py``, its checks in ``checks.py``, files in ``io.py``; the folders
hold one concept each: ``generators/`` (rectangles, boxes, ellipsoids), ``cells/`` (cell types:
node orders, shape functions, their checks), ``queries/`` (boundary, selections, location,
embedding), ``cutting/`` (the virtual node cut) and ``from_surface/`` (tetrahedra from a
surface).

Use ``from tissuesim.mesh import select`` for vertex and facet selections
(``select.vertices_on_plane(mesh, 0, 0.0)``).
"""

from tissuesim.mesh.checks import signed_volumes, validate_mesh
from tissuesim.mesh.from_surface.tetrahedralize import mesh_surface
from tissuesim.mesh.generators.boxes import box
from tissuesim.mesh.generators.ellipsoids import ellipsoid
from tissuesim.mesh.generators.rectangles import rectangle
from tissuesim.mesh.generators.shells import solid_shell
from tissuesim.mesh.io import describe_mesh, read_mesh, write_mesh
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.queries import select
from tissuesim.mesh.queries.boundary import boundary_facets, facet_measures, facet_normals

__all__ = [
    "Mesh",
    "validate_mesh",
    "signed_volumes",
    "rectangle",
    "box",
    "ellipsoid",
    "solid_shell",
    "boundary_facets",
    "facet_measures",
    "facet_normals",
    "read_mesh",
    "write_mesh",
    "describe_mesh",
    "mesh_surface",
    "select",
]

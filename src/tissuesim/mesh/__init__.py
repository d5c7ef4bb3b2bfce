"""Meshes of simplices or Q1 cells: generators, file I/O, validation, boundary facets and
selections.

Use ``from tissuesim.mesh import select`` for vertex and facet selections
(``select.vertices_on_plane(mesh, 0, 0.0)``).
"""

from tissuesim.mesh import select
from tissuesim.mesh.boundary import boundary_facets, facet_measures, facet_normals
from tissuesim.mesh.checks import signed_volumes, validate_mesh
from tissuesim.mesh.generators import box, ellipsoid, rectangle
from tissuesim.mesh.io import describe_mesh, read_mesh, write_mesh
from tissuesim.mesh.mesh import Mesh
from tissuesim.mesh.tetrahedralize import mesh_surface

__all__ = [
    "Mesh",
    "validate_mesh",
    "signed_volumes",
    "rectangle",
    "box",
    "ellipsoid",
    "boundary_facets",
    "facet_measures",
    "facet_normals",
    "read_mesh",
    "write_mesh",
    "describe_mesh",
    "mesh_surface",
    "select",
]

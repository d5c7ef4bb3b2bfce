"""Tetrahedra from a surface (``mesh_surface``, ``tissuesim mesh``): reading, welding and checks
(``tetrahedralize.py``), the meshers behind one call (``meshers.py``), the size options and the
corrective passes to an element count (``sizing.py``) and smoothing a voxel staircase
(``smoothing.py``)."""

"""What a mesh is asked: boundary facets, normals and measures (``boundary.py``), the faces two
cells share (``interior_faces.py``), vertex and facet selections (``select.py``, exported as
``tissuesim.mesh.select``), point location and closest boundary points (``locate.py``) and
points embedded by barycentric coordinates (``embedding.py``)."""

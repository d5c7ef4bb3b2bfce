"""Structured meshes: rectangles (``rectangles.py``), boxes (``boxes.py``), ellipsoids
(``ellipsoids.py``) and solid shells on a surface (``shells.py``); what they share in
``common.py``, the quadratic quadrilaterals and hexahedra on a grid in
``quadratic_tensor.py``. ``tissuesim.mesh`` exports the generators."""

"""Structured meshes: rectangles (``rectangles.py``), boxes (``boxes.py``) and ellipsoids
(``ellipsoids.py``); what they share in ``common.py``, the quadratic quadrilaterals and
hexahedra on a grid in ``quadratic_tensor.py``. ``tissuesim.mesh`` exports the generators."""

"""Cell types: the reference simplex (P1 / P2 shape functions, quadrature), quadratic simplices
(node order, midside nodes, elevation and their checks), Q1 quadrilaterals and hexahedra
(``tensor.py``, checks in ``tensor_checks.py``), quadratic quadrilaterals and hexahedra
(``tensor_quadratic.py``) and linear wedges (``wedge.py``)."""

"""A law from its strain-energy density (``EnergyLaw``, ``model = "energy"``): psi parsed and
differentiated by SymPy (``energy_expr.py``), the law and its checks (``energy.py``), its
generated Numba point kernel (``energy_kernel.py``) and the kernels' Numba helpers
(``energy_point.py``)."""

"""The isotropic laws of (E, nu) or (mu, lambda): the course's neo-Hookean, neo-Hookean,
St. Venant-Kirchhoff, linear elasticity and fixed corotated, one file each; what every law
shares (input checks, J, cofactor, d2J/dF2, the (E, nu) base class) in ``_common.py``, the Lame
conversion in ``lame.py`` and the laws' Numba point kernels in ``point_kernels.py``."""

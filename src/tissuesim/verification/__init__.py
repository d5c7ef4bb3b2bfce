"""Verification problems shipped with tissuesim (``tissuesim verify``): each computes a
quantity with the library and compares it with a reference derived independently (a closed
form or a published value), within a stated tolerance.

One file per family: ``laws.py`` (homogeneous uniaxial, equibiaxial and simple-shear stress of
every registered isotropic law), ``fibres.py`` (the same for the fibre-reinforced laws, along
and across the fibres), ``patch.py`` (P1, P2 and Q1 patch tests), ``viscoelastic.py``
(relaxation against the Prony series), ``dynamics.py`` (Newmark's free fall and energy),
``cook.py`` (Cook's membrane against published values),
``hertz.py`` (a coarse Hertz indentation). ``run`` collects them; ``table`` prints them.
"""

from __future__ import annotations

from tissuesim.verification.check import run, table
from tissuesim.verification.result import Check

__all__ = ["Check", "run", "table"]

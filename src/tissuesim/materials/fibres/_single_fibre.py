"""One fibre family as a law of its own, as FEBio's fibre materials are: W(I4) along ``fiber``,
nothing in compression, no matrix and no bulk term. They are meant as components of a solid
mixture (``materials/mixture.py``), as in FEBio, where a matrix and the bulk term come from the
other components or from the uncoupled mixture's k.

    coupled     W = f(I4),   I4  = a . C a
    uncoupled   W = f(I4b),  I4b = J^(-2/3) a . C a   (the deviatoric fibre of FEBio's *UC laws)

The chain rule to P and dP/dF is ``_fibres.py``'s (``FibreLaw``): f' and f'' in I4 (or I4b) are
all a law gives. ``fiber``: the reference direction, one vector or one per element ((m, 3),
expanded by ``bind``). ``.mu`` = ``.lam`` = ``.k`` = 0: a fibre has no small-strain stiffness
(it is slack at rest), so a body needs a matrix beside it.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.fibres._fibres import FibreLaw, planar_keys, unit_vectors
from tissuesim.materials.soft_tissue._hyperelastic import parameter

__all__ = ["SingleFibre"]


class SingleFibre(FibreLaw):
    """A fibre family W = f(I4) (``uncoupled``: f(I4b)) along ``fiber``; subclasses give
    ``fibre(I4, order)`` -> (f, f', f'') with zeros where the fibre is slack."""

    uses_i2 = False

    def _set_fibre(self, fiber: object) -> None:
        self.fiber = unit_vectors(self.name, "fiber", fiber)
        self.planar = planar_keys(fiber=fiber)
        self.fibres = self.fiber.reshape(-1, 1, 3)
        self.k = self.mu = self.lam = 0.0

    def _fibre_parameter(self) -> dict[str, object]:
        return {"fiber": self.fiber.tolist()}

    def bulk(self, J: np.ndarray, lnJ: np.ndarray) -> tuple:
        zero = np.zeros_like(J)
        return zero, zero, zero

    def fibre(self, I4: np.ndarray, order: int) -> tuple:
        """(f, f', f'') at the fibre invariant I4 (q,) (I4b when ``uncoupled``)."""
        raise NotImplementedError

    def w(self, inv: np.ndarray, order: int) -> tuple:
        f, df, ddf = self.fibre(inv[:, 1], order)
        q = inv.shape[0]
        g = np.stack([np.zeros(q), df], axis=1)
        h = np.zeros((q, 2, 2))
        if order >= 2:
            h[:, 1, 1] = ddf
        return f, g, h


def exponent(law: str, beta: object) -> float:
    """FEBio's beta >= 2 of the fibre laws."""
    value = parameter(law, "beta", beta, unit="")
    if value < 2.0:
        raise MaterialError(f"{law}: beta must be >= 2 (as FEBio requires), got {value!r}")
    return value

"""FEBio's prescribed active contraction, an active stress T0(t) that a solid mixture adds to its
passive components (``FEPrescribedActiveContractionIsotropic``, ``...TransIso``,
``...Uniaxial`` and their ``...UC`` forms). FEBio gives the Cauchy stress

    isotropic     sigma = T0 / J b
    trans iso     sigma = T0 / J (b - n n),   n = F n0
    uniaxial      sigma = T0 / J n n

(n0 the first local axis, e1 of ``mat_axis``). Pulled back, each is a constant second
Piola-Kirchhoff stress S = T0 A with A = I, I - n0 n0 or n0 n0, so each has an energy and a
tangent (FEBio returns a zero tangent; the converged states are the same):

    W = T0 / 2 (C - I) : A        P = T0 F A        dP_ij / dF_kl = T0 delta_ik A_lj

FEBio's uncoupled forms return the same stress from ``DevStress`` (it is not deviatoric), to
which the uncoupled mixture adds its pressure: the ``*_uncoupled`` laws here are the same law,
marked uncoupled so that an uncoupled mixture takes them. In 2D (plane strain, C33 = 1) A's
in-plane block enters.

``T0`` (Pa) is a number or an expression of t (FEBio's value times its load curve,
``febio/curves.py``); the law keeps the time itself (``_time.py``). ``fiber``
(trans iso, uniaxial): n0, one vector or one per element ((m, 3), expanded by ``bind``).
``.mu`` = ``.lam`` = 0: the active stress adds no small-strain stiffness, so it is a mixture's
component beside a matrix.
"""

from __future__ import annotations

import copy

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.active._time import TimeKept, time_function
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input

__all__ = [
    "PrescribedIsotropicActiveContraction",
    "PrescribedTransIsoActiveContraction",
    "PrescribedUniaxialActiveContraction",
    "ACTIVE_CONTRACTION_LAWS",
]


class _ActiveContraction(TimeKept, Material):
    """S = T0(t) A (``_structure``); subclasses give A from n0."""

    name = "prescribed_active_contraction"
    uncoupled = False
    has_fibre = False

    def __init__(self, *, T0: float | str = 0.0, fiber: object = (1.0, 0.0, 0.0)) -> None:
        self.T0 = T0
        self._t0 = time_function(self.name, "T0", T0)
        self.mu = self.lam = 0.0
        self.k = 0.0
        self.time = 0.0  # the accepted time
        self._trial = 0.0  # the time of the step in progress
        if self.has_fibre:
            from tissuesim.materials.fibres._fibres import unit_vectors

            self.fiber = unit_vectors(self.name, "fiber", fiber)
        else:
            self.fiber = np.array([1.0, 0.0, 0.0])

    def parameters(self) -> dict[str, object]:
        out: dict[str, object] = {"T0": self.T0}
        if self.has_fibre:
            out["fiber"] = self.fiber.tolist()
        return out

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.parameters().items())
        return f"{type(self).__name__}({args})"

    def active_stress(self) -> float:
        """T0 at the time of the step in progress (Pa)."""
        return self._t0(self._trial)

    def stand_in(self) -> Material:
        """What a mixture checks in this law's place (a law without a history, with this one's
        name, moduli and coupling): ``reactive/history_mixture.py``."""
        out = Material()
        out.name, out.mu, out.lam = self.name, 0.0, 0.0
        out.uncoupled = self.uncoupled
        return out

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> _ActiveContraction:
        """This law with per-element fibres expanded to the body's integration points."""
        p = 1 if self.fiber.ndim == 1 else self.fiber.shape[0]
        if p in (1, n_points):
            return self
        if (n_cells is not None and p != n_cells) or n_points % p:
            raise MaterialError(
                f"{self.name}: {p} fibre directions given, read as one per element, but the "
                f"body has {n_cells} elements: give one per element or one for the whole body"
            )
        out = copy.copy(self)
        out.fiber = np.repeat(self.fiber, n_points // p, axis=0)
        return out

    def _structure(self, q: int, d: int) -> np.ndarray:
        """A (q, d, d) or (1, d, d): S = T0 A (in-plane block in 2D)."""
        raise NotImplementedError

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q, d = F.shape[0], F.shape[-1]
        if self.fiber.ndim == 2 and self.fiber.shape[0] not in (1, q):
            raise MaterialError(
                f"{self.name} has {self.fiber.shape[0]} fibre directions (one per element or "
                f"point) but was given {q} deformation gradients"
            )
        T0 = self.active_stress()
        A = np.broadcast_to(self._structure(q, d), (q, d, d))
        C = np.swapaxes(F, 1, 2) @ F
        psi = 0.5 * T0 * np.einsum("qij,qij->q", C - np.eye(d), A)
        if order == 0:
            return MaterialResponse(psi)
        P = T0 * F @ A
        if order == 1:
            return MaterialResponse(psi, P)
        tangent = T0 * np.einsum("ik,qlj->qijkl", np.eye(d), A)
        return MaterialResponse(psi, P, tangent)


def _n0(fiber: np.ndarray, d: int) -> np.ndarray:
    n = fiber.reshape(-1, 3)[:, :d]
    return np.einsum("qi,qj->qij", n, n)


class PrescribedIsotropicActiveContraction(_ActiveContraction):
    """FEBio's ``prescribed isotropic active contraction``: sigma = T0 / J b (S = T0 I)."""

    name = "prescribed_isotropic_active_contraction"

    def _structure(self, q: int, d: int) -> np.ndarray:
        return np.eye(d)[None]


class PrescribedTransIsoActiveContraction(_ActiveContraction):
    """FEBio's ``prescribed trans iso active contraction``: sigma = T0 / J (b - n n)."""

    name = "prescribed_trans_iso_active_contraction"
    has_fibre = True

    def _structure(self, q: int, d: int) -> np.ndarray:
        return np.eye(d)[None] - _n0(self.fiber, d)


class PrescribedUniaxialActiveContraction(_ActiveContraction):
    """FEBio's ``prescribed uniaxial active contraction``: sigma = T0 / J n n."""

    name = "prescribed_uniaxial_active_contraction"
    has_fibre = True

    def _structure(self, q: int, d: int) -> np.ndarray:
        return _n0(self.fiber, d)


def _uncoupled(cls: type[_ActiveContraction]) -> type[_ActiveContraction]:
    """FEBio's ``uncoupled ...`` form: the same stress, taken by an uncoupled mixture."""
    return type(
        f"Uncoupled{cls.__name__}",
        (cls,),
        {
            "name": f"uncoupled_{cls.name}",
            "uncoupled": True,
            "__doc__": f"FEBio's ``uncoupled {cls.name.replace('_', ' ')}`` (the same stress).",
        },
    )


UncoupledPrescribedIsotropicActiveContraction = _uncoupled(PrescribedIsotropicActiveContraction)
UncoupledPrescribedTransIsoActiveContraction = _uncoupled(PrescribedTransIsoActiveContraction)
UncoupledPrescribedUniaxialActiveContraction = _uncoupled(PrescribedUniaxialActiveContraction)

#: the laws by name
ACTIVE_CONTRACTION_LAWS: dict[str, type[_ActiveContraction]] = {
    cls.name: cls
    for cls in (
        PrescribedIsotropicActiveContraction,
        PrescribedTransIsoActiveContraction,
        PrescribedUniaxialActiveContraction,
        UncoupledPrescribedIsotropicActiveContraction,
        UncoupledPrescribedTransIsoActiveContraction,
        UncoupledPrescribedUniaxialActiveContraction,
    )
}

"""Visco-elasticity as a Prony series on any elastic law: FEBio's ``viscoelastic`` and
``uncoupled viscoelastic`` materials, integrated so that a Backward Euler step stays an energy
minimisation.

Definition (FEBio's). The relaxation function G(t) = g0 + sum_i g_i exp(-t / tau_i) acts on
the second Piola-Kirchhoff stress Se = F^-1 P_e of the elastic law (coupled) or of its
deviatoric part (uncoupled: the bulk term U(J) stays elastic):

    S(t) = g0 Se(t) + sum_i g_i H_i(t),   H_i(t) = int_0^t exp(-(t - s)/tau_i) dSe/ds ds.

With Se linear in time over a step of length h (the only assumption), the convolution is
exact step by step, with e_i = exp(-h/tau_i) and gamma_i = (1 - e_i) / (h / tau_i):

    H_i^{n+1} = e_i H_i^n + gamma_i (Se^{n+1} - Se^n)                          (FEBio's too)

so S^{n+1} = a Se(F) + S_h, a = g0 + sum_i g_i gamma_i, S_h = sum_i g_i (e_i H_i^n
- gamma_i Se^n): a multiple of the elastic stress plus a history stress fixed over the step.

The incremental potential. With E = (F^T F - I)/2 the Green strain, dE/dF : dF = sym(F^T dF),
so d(S_h : E)/dF = F S_h for the symmetric, fixed S_h. Hence the step's stress is the
derivative of

    psi_step(F) = a psi_e(F) + S_h : E(F)          [uncoupled: a psi_dev(F) + U(J) + S_h : E]

and P = a P_e + F S_h, dP_ij/dF_kl = a A_e,ijkl + delta_ik (S_h)_lj: Newton minimises a sum of
energies as for every other law. FEBio's tangent is the same a C_e (its geometric term comes
with the total Cauchy stress).

The state per integration point, sized by ``bind(n, d)`` (``model.py`` binds a copy to its
body's points): H (m, n, d, d) and Se^n (n, d, d). ``begin_step(h)`` freezes a and S_h from the
last accepted state (called at every attempt, halved ones too: it reads, never writes, the
state); ``accept_step(F)`` updates H and Se once a step converged. Between steps (after
accept, before the first step) the law answers with the instantaneous response from the
current state (the limit h -> 0: e = gamma = 1), whose stress at the accepted F is S^{n+1}, and
its energy is the stored (free) energy g0 psi_e + sum_i g_i/2 H_i : C0^-1 : H_i (C0 the law's
small-strain stiffness: exact at small strain, an estimate beyond).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import (
    check_input,
)
from tissuesim.materials.soft_tissue._hyperelastic import (
    bulk_response,
    parameter_list,
)
from tissuesim.validate import short

__all__ = ["Viscoelastic", "UncoupledViscoelastic", "VISCOELASTIC_LAWS"]


class Viscoelastic(Material):
    """FEBio's ``viscoelastic``: G(t) = g0 + sum_i g_i exp(-t/tau_i) on the second
    Piola-Kirchhoff stress of ``elastic`` (any law); see the module docstring.

    ``Viscoelastic(NeoHookean(youngs_modulus=1e4, poisson_ratio=0.3), g=[0.5], tau=[0.1])``
    relaxes to the law's stress from 1.5 times it with the time constant 0.1 s. Parameters:
    ``g`` (>= 0, FEBio's g1..g6) and ``tau`` (s, > 0, its t1..t6), as long lists, ``g0`` > 0
    (default 1)."""

    name = "viscoelastic"
    febio_name = "viscoelastic"
    #: the relaxing part is the deviatoric one (FEBio's uncoupled viscoelastic)
    uncoupled = False

    def __init__(
        self,
        elastic: Material | None = None,
        *,
        g: object = None,
        tau: object = None,
        g0: float = 1.0,
    ) -> None:
        law = self.name
        if not isinstance(elastic, Material) or isinstance(elastic, Viscoelastic):
            what = "another viscoelastic material" if isinstance(elastic, Viscoelastic) else None
            raise MaterialError(
                f"{law} needs an elastic law (elastic = a material, e.g. "
                f"NeoHookean(...) or {{ model = 'neo_hookean', ... }}), not "
                f"{what or short(elastic)}"
            )
        if g is None or tau is None:
            raise MaterialError(f"{law} needs g (the Prony weights) and tau (their times, s)")
        self.g = parameter_list(law, "g", g, unit="")
        self.tau = parameter_list(law, "tau", tau, unit="s")
        if len(self.g) != len(self.tau):
            raise MaterialError(
                f"{law}: g and tau must have the same length, got {len(self.g)} and {len(self.tau)}"
            )
        for i, (gi, ti) in enumerate(zip(self.g, self.tau, strict=True)):
            if gi < 0.0:
                raise MaterialError(f"{law}: g[{i}] must be >= 0, got {gi!r}")
            if ti <= 0.0:
                raise MaterialError(f"{law}: tau[{i}] must be > 0 s, got {ti!r}")
        self.g0 = parameter_list(law, "g0", g0, unit="")[0]
        if self.g0 <= 0.0:
            raise MaterialError(f"{law}: g0 must be > 0, got {self.g0!r}")
        self._check_base(elastic)
        self.elastic = elastic
        scale = self.g0 + sum(self.g)  # the instantaneous response
        self.mu, self.lam = elastic.mu * scale, elastic.lam * scale
        self._n: int | None = None  # bound points
        self._H = self._Se = None  # (m, n, d, d), (n, d, d)
        self._frozen: tuple[float, np.ndarray] | None = None  # in a step: (a, S_h)
        self._step: tuple[np.ndarray, np.ndarray] | None = None  # in a step: (e, gamma)

    def _check_base(self, elastic: Material) -> None:
        """Coupled: any law."""

    def __repr__(self) -> str:
        name, g, tau = type(self).__name__, self.g, self.tau
        return f"{name}({self.elastic!r}, g={g!r}, tau={tau!r}, g0={self.g0!r})"

    # -- the state ------------------------------------------------------------------------
    @property
    def bound(self) -> bool:
        """True when the law holds a state for a body's integration points (``bind``)."""
        return self._n is not None

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> Viscoelastic:
        """A copy holding the state of ``n_points`` integration points in ``dim`` dimensions,
        at rest (no history); ``n_cells`` goes to the elastic law's ``bind``."""
        out = copy.copy(self)
        if hasattr(self.elastic, "bind"):  # a law with data per point (fibre directions)
            out.elastic = self.elastic.bind(n_points, dim, n_cells)
        out._n = int(n_points)
        out._H = np.zeros((len(self.g), out._n, dim, dim))
        out._Se = np.zeros((out._n, dim, dim))
        out._frozen = out._step = None
        return out

    def _need_state(self, what: str) -> None:
        if not self.bound:
            raise MaterialError(
                f"{self.name}: {what} needs the state of a body's integration points; a "
                "viscoelastic material works on FEM bodies (their model binds it)"
            )

    def begin_step(self, h: float) -> None:
        """Freeze the step's factor a and history stress S_h for a step of ``h`` s from the
        last accepted state (reads the state only: a rejected attempt leaves it as it was)."""
        self._need_state("begin_step")
        x = h / np.asarray(self.tau)
        e = np.exp(-x)
        gamma = -np.expm1(-x) / x  # (1 - e) / x, exact for small x too
        g = np.asarray(self.g)
        a = self.g0 + float(g @ gamma)
        Sh = np.einsum("m,mnij->nij", g * e, self._H) - float(g @ gamma) * self._Se
        self._frozen, self._step = (a, Sh), (e, gamma)

    def accept_step(self, F: np.ndarray) -> None:
        """The step converged at deformation gradients ``F`` (n, d, d): H_i and Se updated
        (FEBio's recursion), after which the law answers as between steps."""
        self._need_state("accept_step")
        if self._step is None:
            raise MaterialError(f"{self.name}: accept_step without begin_step")
        F = np.asarray(F, dtype=float)
        Se = self.relaxing_pk2(F)
        e, gamma = self._step
        self._H = e[:, None, None, None] * self._H + gamma[:, None, None, None] * (Se - self._Se)
        self._Se = Se
        self._frozen = self._step = None

    def state_arrays(self) -> dict[str, np.ndarray]:
        """The state between steps: {"H": (m, n, d, d), "Se": (n, d, d)} (for checkpoints)."""
        self._need_state("state_arrays")
        return {"H": self._H.copy(), "Se": self._Se.copy()}

    def set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        """Restore a state of ``state_arrays`` (the shapes must match)."""
        self._need_state("set_state_arrays")
        H, Se = np.asarray(arrays["H"], float), np.asarray(arrays["Se"], float)
        if H.shape != self._H.shape or Se.shape != self._Se.shape:
            raise MaterialError(
                f"{self.name}: a state of shapes {H.shape}, {Se.shape} does not fit "
                f"{self._H.shape}, {self._Se.shape}"
            )
        self._H, self._Se = H.copy(), Se.copy()
        self._frozen = self._step = None

    @property
    def history(self) -> np.ndarray:
        """The history stresses H_i (m, n, d, d) of the last accepted step (Pa)."""
        self._need_state("history")
        return self._H.copy()

    # -- the law --------------------------------------------------------------------------
    def _relaxing(self, F: np.ndarray, order: int) -> MaterialResponse:
        """The part G(t) acts on: the whole law (coupled)."""
        return self.elastic.evaluate(F, order)

    def _elastic_rest(self, F: np.ndarray, order: int) -> MaterialResponse | None:
        """The part that stays elastic: none (coupled)."""
        return None

    def relaxing_pk2(self, F: np.ndarray) -> np.ndarray:
        """Se = F^-1 P of the relaxing part at F (n, d, d), symmetrised (Pa)."""
        F = check_input(F, 1)
        S = np.linalg.solve(F, self._relaxing(F, 1).stress)
        return 0.5 * (S + np.swapaxes(S, 1, 2))

    def _history_stress(self, F: np.ndarray) -> tuple[float, np.ndarray | None, bool]:
        """(a, S_h shaped like F or None, in a step) for these points: the step's frozen values,
        or between steps the instantaneous ones; None where F is not the bound points."""
        g = np.asarray(self.g)
        if self._frozen is not None:
            a, Sh = self._frozen
            in_step = True
        else:
            a, in_step = self.g0 + float(g.sum()), False
            Sh = None
            if self.bound:
                Sh = np.einsum("m,mnij->nij", g, self._H) - float(g.sum()) * self._Se
        if Sh is None or Sh.shape[0] != F.shape[0]:
            return a, None, in_step
        d, k = F.shape[-1], Sh.shape[-1]
        if d != k:  # a plane-strain state asked in 3D (measures embed F): S_h has no 33 part
            full = np.zeros((Sh.shape[0], d, d))
            full[:, :k, :k] = Sh
            Sh = full
        return a, Sh, in_step

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        """In a step: psi = a psi_e + S_h : E (+ U(J) uncoupled), P = a P_e + F S_h (+ ...),
        A = a A_e + delta_ik S_h,lj (+ ...). Between steps: the instantaneous response, with
        the stored energy as energy. Shapes as ``Material.evaluate``."""
        F = check_input(F, order)
        a, Sh, in_step = self._history_stress(F)
        r = self._relaxing(F, order)
        rest = self._elastic_rest(F, order)
        if not in_step:
            psi = self._stored_energy(r.energy, F.shape[0])
        else:
            psi = a * r.energy
            if Sh is not None:
                E = 0.5 * (np.swapaxes(F, 1, 2) @ F - np.eye(F.shape[-1]))
                with np.errstate(invalid="ignore"):
                    psi = psi + np.einsum("qij,qij->q", Sh, E)
        if rest is not None:
            psi = psi + rest.energy
        if order == 0:
            return MaterialResponse(psi)
        P = a * r.stress
        if Sh is not None:
            P = P + F @ Sh
        if rest is not None:
            P = P + rest.stress
        if order == 1:
            return MaterialResponse(psi, P)
        A = a * r.tangent
        if Sh is not None:
            d = F.shape[-1]
            A = A + np.eye(d)[None, :, None, :, None] * np.swapaxes(Sh, 1, 2)[:, None, :, None, :]
        if rest is not None:
            A = A + rest.tangent
        return MaterialResponse(psi, P, A)

    def _stored_energy(self, psi_e: np.ndarray, q: int) -> np.ndarray:
        """g0 psi_e + sum_i g_i/2 H_i : C0^-1 : H_i (the branches' energy at small strain)."""
        out = self.g0 * psi_e
        if not self.bound or q != self._n:
            return out
        mu, lam = self.elastic.mu, self.elastic.lam
        for gi, H in zip(self.g, self._H, strict=True):
            tr = np.einsum("nii->n", H)
            HH = np.einsum("nij,nij->n", H, H)
            # C0^-1 : H = (H - lam / (2 mu + 3 lam) tr H I) / (2 mu)
            out = out + 0.5 * gi * (HH - lam / (2.0 * mu + 3.0 * lam) * tr**2) / (2.0 * mu)
        return out

    def stored_energy_density(self, F: np.ndarray) -> np.ndarray:
        """The stored (free) energy density at the bound points (J/m^3, (n,)): g0 psi_e(F)
        plus the branches' sum_i g_i/2 H_i : C0^-1 : H_i, whatever the step's state."""
        F = check_input(F, 0)
        r = self._relaxing(F, 0)
        rest = self._elastic_rest(F, 0)
        out = self._stored_energy(r.energy, F.shape[0])
        return out if rest is None else out + rest.energy


class UncoupledViscoelastic(Viscoelastic):
    """FEBio's ``uncoupled viscoelastic``: the Prony series on the deviatoric part of an
    uncoupled law (``mooney_rivlin``, ``ogden``, ``yeoh``, ...); its bulk term U(J) (k) stays
    elastic. Parameters as ``Viscoelastic``."""

    name = "uncoupled_viscoelastic"
    febio_name = "uncoupled viscoelastic"
    uncoupled = True

    def _check_base(self, elastic: Material) -> None:
        from tissuesim.materials.soft_tissue.ogden import Ogden

        if not (isinstance(elastic, Ogden) or getattr(elastic, "uncoupled", False) is True):
            raise MaterialError(
                f"{self.name} needs an uncoupled elastic law (mooney_rivlin, ogden, yeoh, "
                f"veronda_westmann, arruda_boyce), not {getattr(elastic, 'name', short(elastic))}"
                "; use viscoelastic for the others"
            )

    def _bulk(self, F: np.ndarray, order: int) -> MaterialResponse:
        base = self.elastic
        return bulk_response(base.name, base.bulk_kind, float(base.k), F, order)

    def _relaxing(self, F: np.ndarray, order: int) -> MaterialResponse:
        full, bulk = self.elastic.evaluate(F, order), self._bulk(F, order)
        with np.errstate(invalid="ignore"):
            psi = full.energy - bulk.energy
        psi = np.where(np.isfinite(full.energy), psi, math.inf)
        if order == 0:
            return MaterialResponse(psi)
        P = full.stress - bulk.stress
        if order == 1:
            return MaterialResponse(psi, P)
        return MaterialResponse(psi, P, full.tangent - bulk.tangent)

    def _elastic_rest(self, F: np.ndarray, order: int) -> MaterialResponse | None:
        return self._bulk(F, order)


#: the wrappers by name (``make_material`` builds their ``elastic`` law from a table)
VISCOELASTIC_LAWS: dict[str, type[Viscoelastic]] = {
    Viscoelastic.name: Viscoelastic,
    UncoupledViscoelastic.name: UncoupledViscoelastic,
}

"""FEBio's continuous fibre distribution, ``continuous fiber distribution`` and its uncoupled
twin (``FEContinuousFiberDistribution.cpp``, ``FEContinuousFiberDistributionUC.cpp``): a fibre
law f (``fibers``: fiber_exp_pow, fiber_pow_linear, ... and their uncoupled forms) in every
direction of the sphere (or the local 1-2 plane), weighted by a density R
(``distribution``) and summed by an integration scheme (``scheme``,
``fibre_distribution.py``):

    W = sum_k c_k f(I4_k),   c_k = w_k R(n_k) / IFD,   IFD = sum_k' w_k' R(n_k') (fixed points)

with I4_k = a_k . C a_k, a_k = Q n_k the global direction of the local n_k, Q = [e1 e2 e3]
from ``mat_axis_a`` and ``mat_axis_d`` (FEBio's mat_axis, ``local_axes``). Each f bears
tension only, so only the stretched directions count. Uncoupled: f of Ib_k = s I4_k,
s = J^(-2/3) (the bulk term is the mixture's). With the coupled law's s = 1, cJ = 0 and the
uncoupled law's s = J^(-2/3), cJ = 2 / (3 J), g_k = c_k f'(Ib_k), h_k = c_k f''(Ib_k),
M1 = sum g_k a_k (x) a_k, M2 = sum h_k Ib_k a_k (x) a_k, K = sum h_k a_k (x) a_k (x) a_k (x) a_k:

    dIb_k/dF = s G_k - cJ Ib_k cof F,   G_k = 2 (F a_k) (x) a_k
    P = 2 s F M1 - cJ (sum g_k Ib_k) cof F
    A = sum h_k dIb_k (x) dIb_k + sum g_k d2Ib_k/dF2
      = 4 s^2 F F : K - 2 s cJ ((F M2) (x) cof + cof (x) (F M2)) + cJ^2 (sum h Ib^2) cof (x) cof
        + 2 s delta_ik (M1)_jl - 2 s cJ ((F M1) (x) cof + cof (x) (F M1))
        + 10 / 9 (sum g Ib) / J^2 cof (x) cof - cJ (sum g Ib) d2J/dF2

(s' = -cJ s, s'' = 10 s / (9 J^2)). The Gauss-Kronrod scheme moves its points with C; as
FEBio, the stress and tangent are those of the points of the current C held fixed (its energy
is then the stress's potential to the accuracy of the quadrature). FEBio takes those points in
the eigenvectors of the global C and reads them as local directions (R(n), then Q n): with
local axes other than the global ones the stretched cap is missed and the stress is no
energy's derivative, so that case is refused.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.fibres._fibres import local_axes, planar_keys
from tissuesim.materials.fibres._single_fibre import SingleFibre
from tissuesim.materials.fibres.fibre_distribution import make_distribution, make_scheme
from tissuesim.materials.fibres.fibre_exp_linear import FiberExpLinear, FiberExpLinearUncoupled
from tissuesim.materials.fibres.fibre_exp_pow import FiberExpPow, FiberExpPowUncoupled
from tissuesim.materials.fibres.fibre_pow_linear import FiberPowLinear, FiberPowLinearUncoupled
from tissuesim.materials.isotropic._common import (
    bcast,
    check_input,
    cofactor,
    det,
    det_hessian,
    outer,
)
from tissuesim.materials.soft_tissue._hyperelastic import HyperelasticMaterial, inverted_error
from tissuesim.validate import short

__all__ = ["ContinuousFiberDistribution", "ContinuousFiberDistributionUncoupled", "fibre_sum"]

#: the index pairs (i <= j) of a symmetric 3 x 3 tensor, and the pair of each of the 9 (i, j)
_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_PAIR_OF = np.array([_PAIRS.index((min(i, j), max(i, j))) for i, j in np.ndindex(3, 3)])
_PI, _PJ = np.array(_PAIRS).T

#: the fibre laws a distribution takes, by name (FEBio's names work: case, spaces and dashes
#: do not matter)
_FIBRES = {
    cls.name: cls
    for cls in (FiberExpPow, FiberExpPowUncoupled, FiberPowLinear, FiberPowLinearUncoupled,
                FiberExpLinear, FiberExpLinearUncoupled)
}  # fmt: skip
_ALIASES = {"uncoupled_fiber_exp_linear": "fiber_exp_linear_uncoupled"}


def _key(model: str) -> str:
    return model.strip().lower().replace("-", "_").replace(" ", "_").replace("fibre", "fiber")


def fibre_sum(
    law: SingleFibre,
    F: np.ndarray,
    a: np.ndarray,
    c: np.ndarray,
    uncoupled: bool,
    order: int,
) -> MaterialResponse:
    """W = sum_k c_k f(I4_k) (or f(Ib_k)) with its P and dP/dF: F (q, 3, 3), a (q or 1, K, 3)
    global unit directions, c (q or 1, K) coefficients, f = ``law.fibre``."""
    q = F.shape[0]
    cof = cofactor(F)
    J = det(F, cof)
    ok = J > 0.0
    if order > 0 and not ok.all():
        raise inverted_error(law.name, J, ok)
    Js = np.where(ok, J, 1.0)
    a = np.broadcast_to(a, (q,) + a.shape[1:])
    c = np.broadcast_to(c, a.shape[:2])
    Fa = a @ np.swapaxes(F, 1, 2)  # (q, K, 3): F a_k
    I4 = np.sum(Fa * Fa, axis=-1)
    s = Js ** (-2.0 / 3.0) if uncoupled else np.ones(q)
    cJ = 2.0 / (3.0 * Js) if uncoupled else np.zeros(q)
    Ib = I4 * s[:, None]
    f, f1, f2 = (None if x is None else x.reshape(Ib.shape) for x in law.fibre(Ib.ravel(), order))
    psi = np.where(ok, np.sum(c * f, axis=-1), np.inf)
    if order == 0:
        return MaterialResponse(psi)
    g = c * f1
    gI = np.sum(g * Ib, axis=-1)
    M1 = np.swapaxes(a, 1, 2) @ (g[:, :, None] * a)  # sum g_k a_k (x) a_k
    FM1 = F @ M1
    P = bcast(2.0 * s, 3) * FM1 - bcast(cJ * gI, 3) * cof
    if order == 1:
        return MaterialResponse(psi, P)
    h = c * f2
    # K_pjrl = sum_k h_k (a_p a_j)_k (a_r a_l)_k: the 6 x 6 of the pairs, then all 81
    at = np.ascontiguousarray(np.swapaxes(a, 1, 2))  # (q, 3, K)
    pairs = at[:, _PI] * at[:, _PJ]  # (q, 6, K)
    K6 = (pairs * h[:, None, :]) @ np.swapaxes(pairs, 1, 2)
    K = K6[:, _PAIR_OF[:, None], _PAIR_OF[None, :]].reshape(q, 3, 3, 3, 3)  # p j r l
    A = 4.0 * bcast(s**2, 5) * np.einsum("qip,qmr,qpjrl->qijml", F, F, K, optimize=True)
    FM2 = F @ (np.swapaxes(a, 1, 2) @ ((h * Ib)[:, :, None] * a))
    hI2 = np.sum(h * Ib**2, axis=-1)
    A += 2.0 * bcast(s, 5) * np.eye(3)[None, :, None, :, None] * M1[:, None, :, None, :]
    if uncoupled:
        X = FM2 + FM1
        A -= bcast(2.0 * s * cJ, 5) * (outer(X, cof) + outer(cof, X))
        A += bcast(cJ**2 * hI2 + 10.0 / 9.0 * gI / Js**2, 5) * outer(cof, cof)
        A -= bcast(cJ * gI, 5) * det_hessian(F)
    return MaterialResponse(psi, P, A)


class ContinuousFiberDistribution(HyperelasticMaterial):
    """FEBio's ``continuous fiber distribution``: a fibre law (``fibers``, a table with its
    model: fiber_exp_pow, ...) over a density (``distribution``: spherical, ellipsoidal,
    von_mises_3d, elliptical, von_mises_2d) summed by ``scheme`` (fibers_3d_gkt,
    fibers_2d_trapezoidal), in the local axes of ``mat_axis_a`` and ``mat_axis_d``."""

    name = "continuous_fiber_distribution"
    febio_name = "continuous fiber distribution"
    uncoupled = False

    def __init__(
        self,
        *,
        fibers: object = None,
        distribution: object = None,
        scheme: object = None,
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
    ) -> None:
        law = self.name
        if isinstance(fibers, SingleFibre):
            fibre = fibers
        elif isinstance(fibers, dict) and "model" in fibers:
            table = dict(fibers)
            model = str(table.pop("model"))
            cls = _FIBRES.get(_ALIASES.get(_key(model), _key(model)))
            if cls is None:
                raise MaterialError(f"{law}: fibers: unknown fibre law {short(model)}; valid: "
                                    f"{', '.join(_FIBRES)}")  # fmt: skip
            try:
                fibre = cls(**table)
            except TypeError as exc:
                raise MaterialError(f"{law}: fibers: {exc}") from None
            except MaterialError as exc:
                raise MaterialError(f"{law}: fibers: {exc}") from None
        else:
            raise MaterialError(f"{law}: fibers must be a table with its model (e.g. "
                                f"'fiber_exp_pow'), not {short(fibers)}")  # fmt: skip
        if not isinstance(fibre, SingleFibre) or fibre.uncoupled != self.uncoupled:
            kind = "uncoupled" if self.uncoupled else "coupled"
            raise MaterialError(f"{law}: fibers must be a {kind} fibre law (fiber_exp_pow"
                                f"{'_uncoupled' if self.uncoupled else ''}, ...), not "
                                f"{fibre.name}")  # fmt: skip
        if getattr(fibre, "fibre_mu", 0.0):
            raise MaterialError(f"{law}: a fibre shear modulus mu > 0 in a distribution is not "
                                "supported by tissuesim (give mu = 0)")  # fmt: skip
        self.fibre = fibre
        self.distribution = make_distribution(distribution)
        self.scheme = make_scheme(scheme)
        if self.distribution.planar != self.scheme.planar:
            raise MaterialError(f"{law}: the {self.distribution.model} distribution needs a "
                                f"{'2D' if self.distribution.planar else '3D'} scheme, not "
                                f"{self.scheme.model}")  # fmt: skip
        self.mat_axis_a, self.mat_axis_d = mat_axis_a, mat_axis_d
        e1, e2 = local_axes(law, mat_axis_a, mat_axis_d)
        self.planar = planar_keys(mat_axis_a=mat_axis_a, mat_axis_d=mat_axis_d)
        self.Q = np.stack([e1, e2, np.cross(e1, e2)], axis=-1).reshape(-1, 3, 3)
        if self.scheme.adaptive and not np.allclose(self.Q, np.eye(3), rtol=0.0, atol=1e-12):
            raise MaterialError(
                f"{law}: FEBio's fibers-3d-gkt takes its points in the eigenvectors of the "
                "global C and reads them as local directions, so with local axes other than "
                "the global ones (a mat_axis) its stress is not the derivative of an energy of "
                "F, which tissuesim minimises in each step: give global axes or another scheme"
            )
        n, w = self.scheme.fixed
        self.ifd = float(np.sum(w * self.distribution.density(n))) or 1.0
        self.k = self.mu = self.lam = 0.0

    def parameters(self) -> dict[str, object]:
        fibre = {"model": self.fibre.name, **self.fibre.parameters()}
        fibre.pop("fiber", None)
        return {
            "fibers": fibre,
            "distribution": {"model": self.distribution.model, **self.distribution.params},
            "scheme": {"model": self.scheme.model, **self.scheme.params},
            "mat_axis_a": np.asarray(self.mat_axis_a).tolist(),
            "mat_axis_d": np.asarray(self.mat_axis_d).tolist(),
        }

    def bind(
        self, n_points: int, dim: int, n_cells: int | None = None
    ) -> ContinuousFiberDistribution:
        """This law with per-element axes expanded to the body's integration points."""
        p = self.Q.shape[0]
        if dim == 3 and self.planar:
            raise MaterialError(f"{self.name}: {', '.join(self.planar)} has 2 components on a "
                                "3D body; give [x, y, z]")  # fmt: skip
        if n_cells is not None and p not in (1, n_cells, n_points):
            raise MaterialError(f"{self.name}: {p} local axes given, read as one per element, "
                                f"but the body has {n_cells} elements")  # fmt: skip
        if p in (1, n_points):
            return self
        if n_points % p:
            raise MaterialError(f"{self.name}: {p} local axes do not match {n_points} "
                                "integration points")  # fmt: skip
        bound = object.__new__(type(self))
        bound.__dict__.update(self.__dict__)
        bound.Q = np.repeat(self.Q, n_points // p, axis=0)
        return bound

    def directions(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(a (q or 1, K, 3) global directions, c (q or 1, K) weights w R / IFD) at F."""
        C = np.swapaxes(F, 1, 2) @ F
        if self.uncoupled:
            J = np.linalg.det(F)
            C = C * np.where(J > 0.0, J, 1.0)[:, None, None] ** (-2.0 / 3.0)
        n, w = self.scheme.points(C)
        c = w * self.distribution.density(n) / self.ifd
        return n @ np.swapaxes(self.Q, -1, -2), c

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        if F.shape[-1] != 3:
            raise MaterialError(f"{self.name} runs on 3D bodies only")
        if self.Q.shape[0] not in (1, F.shape[0]):
            raise MaterialError(f"{self.name} has {self.Q.shape[0]} local axes (one per element "
                                f"or point) but was given {F.shape[0]} deformation "
                                "gradients")  # fmt: skip
        a, c = self.directions(F)
        return fibre_sum(self.fibre, F, a, c, self.uncoupled, order)


class ContinuousFiberDistributionUncoupled(ContinuousFiberDistribution):
    """FEBio's ``continuous fiber distribution uncoupled``: the same with an uncoupled fibre law
    (fiber_exp_pow_uncoupled, ...) of the isochoric I4b; its bulk term is the mixture's."""

    name = "continuous_fiber_distribution_uncoupled"
    febio_name = "continuous fiber distribution uncoupled"
    uncoupled = True
